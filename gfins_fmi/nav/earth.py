"""The Earth and rotations in numpy: WGS-84 (constants, radii of curvature, normal
gravity) and the one set of quaternion and rotation helpers (product, Euler angles to
q_b^n, q_b^n to C_b^n, attitude error, skew matrix, Rodrigues' formula).

This module imports nothing but numpy — not the C core — so that it can serve as truth:
the tests check the core's Earth model (``gf_earth``) and quaternion code (``gf_math.h``)
against these formulas to round-off, and the closed-form motions of
:mod:`gfins_fmi.sim.trajectory` are built on them.

Which Euler conversion is which: :func:`euler_to_quat` here takes heading, pitch and roll
as separate arrays of any (broadcast) shape, complex ones included (complex-step
derivatives of the closed-form motions), and checks nothing. The navigators' own
conversions are the C core's, :func:`gfins_fmi.nav.strapdown.euler_to_quat` (one checked
(3,) angle set; ``gfins_fmi.euler_to_quat``) and :func:`gfins_fmi.nav.strapdown.
quat_to_euler` (unit quaternions (4,) or (n, 4), refused when not unit). Both forms of
euler_to_quat compose the same three axis quaternions in the same order (measured: equal
bit for bit on 10^4 random angle sets); there is no numpy quat_to_euler — every caller
wants the C one's checks.

Frames and angles follow the C core (gf_sins.h): body right-front-up, navigation ENU,
heading clockwise from north, C_b^n = Rz(-psi) Rx(theta) Ry(gamma); quaternions scalar
first, Hamilton product, q_b^n maps body to navigation axes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["WGS84", "radii", "gravity", "quat_multiply", "euler_to_quat", "quat_to_dcm",
           "attitude_error_rad", "skew", "rotation_matrix", "deg", "rad"]

deg = np.pi / 180.0  #: multiply degrees by this to get radians
rad = 1.0            #: radians


class WGS84:
    """WGS-84 constants (NIMA TR8350.2)."""
    a = 6378137.0
    f = 1.0 / 298.257223563
    e2 = f * (2.0 - f)
    b = a * (1.0 - f)
    omega_ie = 7.292115e-5
    GM = 3.986004418e14
    gamma_e = 9.7803253359
    k = 0.00193185265241
    m = omega_ie ** 2 * a ** 2 * b / GM


def radii(lat):
    """R_M, R_N (m) and their derivatives with respect to latitude (m/rad)."""
    s, c = np.sin(lat), np.cos(lat)
    q = 1.0 - WGS84.e2 * s * s
    RN = WGS84.a / np.sqrt(q)
    RM = WGS84.a * (1.0 - WGS84.e2) / q ** 1.5
    dRN = RN * WGS84.e2 * s * c / q
    dRM = 3.0 * RM * WGS84.e2 * s * c / q
    return RM, RN, dRM, dRN


def gravity(lat, h):
    """Normal gravity (m/s^2): Somigliana with the second-order height expansion."""
    s2 = np.sin(lat) ** 2
    g0 = WGS84.gamma_e * (1 + WGS84.k * s2) / np.sqrt(1 - WGS84.e2 * s2)
    a, f, m = WGS84.a, WGS84.f, WGS84.m
    return g0 * (1 - 2 / a * (1 + f + m - 2 * f * s2) * h + 3 / a ** 2 * h * h)


def quat_multiply(p, q):
    """The Hamilton product p (x) q of quaternions (..., 4), scalar first."""
    p0, p1, p2, p3 = np.moveaxis(p, -1, 0)
    q0, q1, q2, q3 = np.moveaxis(q, -1, 0)
    return np.stack([p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3,
                     p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
                     p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1,
                     p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0], axis=-1)


def _qaxis(axis: int, angle):
    angle = np.asarray(angle)
    # complex angles pass through, so that tests can differentiate by complex step
    q = np.zeros(angle.shape + (4,), dtype=np.result_type(angle, float))
    q[..., 0] = np.cos(angle / 2)
    q[..., 1 + axis] = np.sin(angle / 2)
    return q


def euler_to_quat(heading, pitch, roll):
    """q_b^n of Euler angles (rad), C_b^n = Rz(-heading) Rx(pitch) Ry(roll)."""
    return quat_multiply(quat_multiply(_qaxis(2, -np.asarray(heading)), _qaxis(0, pitch)),
                         _qaxis(1, roll))


def attitude_error_rad(q_est, q_true) -> np.ndarray:
    """Rotation vector (n, 3), in the navigation frame, of q_est (x) q_true^*: the
    attitude error of an estimate (rad). atan2 form, accurate for small angles."""
    q_est, q_true = np.atleast_2d(q_est), np.atleast_2d(q_true)
    w = np.sum(q_est * q_true, axis=1)
    v = (q_true[:, :1] * q_est[:, 1:] - q_est[:, :1] * q_true[:, 1:]
         - np.cross(q_est[:, 1:], q_true[:, 1:]))
    nv = np.linalg.norm(v, axis=1)
    angle = 2 * np.arctan2(nv, np.abs(w))
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(nv[:, None] > 0, v / nv[:, None], 0.0)
    return np.sign(w)[:, None] * angle[:, None] * axis


def quat_to_dcm(q):
    """C_b^n (..., 3, 3) of quaternions q_b^n (..., 4)."""
    q0, q1, q2, q3 = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3, 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)], -1),
        np.stack([2 * (q1 * q2 + q0 * q3), q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3, 2 * (q2 * q3 - q0 * q1)], -1),
        np.stack([2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3], -1),
    ], -2)


def skew(v):
    """The cross-product matrix [v x] (3, 3) of a 3-vector."""
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rotation_matrix(rotvec):
    """exp([v x]) (3, 3) of a rotation vector (rad) by Rodrigues' formula."""
    v = np.asarray(rotvec, float)
    th = np.linalg.norm(v)
    K = skew(v)
    if th < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th ** 2 * K @ K
