"""Truth that does not come from the code under test: the 9-accelerometer layout typed in
from seed 000's table, the array's outputs from the output equation (seed 000, eq. 1-2)
written with the identity omega x (omega x u) = omega (omega.u) - |omega|^2 u, a smooth
motion, the attitude and horizontal errors, and WGS-84 written out again.
"""
from __future__ import annotations

import numpy as np

#: the Earth rate (rad/s)
OMEGA = 7.292115e-5

EPS = np.finfo(float).eps
S2 = np.sqrt(0.5)


def paper_layout(l_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(u, theta) of seed 000 section 1, with u_7..u_9 = l[...] (not sqrt(l))."""
    u = l_m * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
                        [1, -1, 0], [1, 0, -1], [0, 1, -1]], float)
    th = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
                   [S2, S2, 0], [S2, 0, S2], [0, S2, S2]])
    return u, th


def numpy_outputs(u, th, f, w, wd) -> np.ndarray:
    """A[k, i] = th_i . (f_k + wd_k x u_i + w_k (w_k . u_i) - |w_k|^2 u_i), in numpy."""
    wdxu = np.cross(wd[:, None, :], u[None, :, :])                  # (n, N, 3)
    centripetal = w[:, None, :] * (w @ u.T)[:, :, None] - (w * w).sum(1)[:, None, None] * u[None]
    a = f[:, None, :] + wdxu + centripetal
    return np.einsum("nij,ij->ni", a, th)


#: rate of smooth_motion at t = 0 (rad/s): the omega_init its solutions start from
W0 = [0.0, 1.8, -2.0]


def smooth_motion(n: int, dt: float):
    """Closed-form f (m/s^2), omega (rad/s), omega_dot (rad/s^2) with zero crossings of
    omega_x (at t = 2 pi k) and omega_z (at t = 20 s)."""
    t = np.arange(n) * dt
    f = np.c_[1 + np.sin(0.7 * t), -2 + 0.5 * np.cos(1.3 * t), 9.8 + 0.2 * np.sin(0.3 * t)]
    w = np.c_[0.8 * np.sin(0.5 * t), 1.5 + 0.3 * np.cos(0.9 * t), -2 + 0.1 * t]
    wd = np.c_[0.4 * np.cos(0.5 * t), -0.27 * np.sin(0.9 * t), np.full(n, 0.1)]
    return t, f, w, wd


def attitude_error_rad(q_est, q_true) -> np.ndarray:
    """Rotation vector (n, 3), in the navigation frame, of q_est (x) q_true^*: the
    attitude error. atan2 form, accurate for small angles (arccos of the dot product
    is not: it bottoms out at ~1e-8 rad)."""
    qe, qt = np.atleast_2d(q_est), np.atleast_2d(q_true)
    # d = qe (x) conj(qt)
    w = np.sum(qe * qt, axis=1)
    v = (qt[:, :1] * qe[:, 1:] - qe[:, :1] * qt[:, 1:]
         - np.cross(qe[:, 1:], qt[:, 1:]))
    s = np.sign(w)[:, None]
    norm_v = np.linalg.norm(v, axis=1)
    angle = 2 * np.arctan2(norm_v, np.abs(w))
    # 0 / 0 where the rotation is zero: np.where takes 0 there
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(norm_v[:, None] > 0, v / norm_v[:, None], 0.0)
    return s * axis * angle[:, None]


def horizontal_error_m(lat, lon, lat_true, lon_true) -> np.ndarray:
    """Horizontal position error (m), small-difference approximation with the mean
    Earth radius (ample for errors below kilometres)."""
    R = 6371000.0
    return np.hypot((lat - lat_true) * R, (lon - lon_true) * R * np.cos(lat_true))


# ---- WGS-84, written out here (the references of the tests must not come from the code) ----
A_WGS, F_WGS = 6378137.0, 1 / 298.257223563
E2 = F_WGS * (2 - F_WGS)


def radii(L):
    q = 1 - E2 * np.sin(L) ** 2
    return A_WGS * (1 - E2) / q ** 1.5, A_WGS / np.sqrt(q)


def gravity(L, h):
    s2 = np.sin(L) ** 2
    g0 = 9.7803253359 * (1 + 0.00193185265241 * s2) / np.sqrt(1 - E2 * s2)
    m = OMEGA ** 2 * A_WGS ** 2 * A_WGS * (1 - F_WGS) / 3.986004418e14
    return g0 * (1 - 2 / A_WGS * (1 + F_WGS + m - 2 * F_WGS * s2) * h + 3 / A_WGS ** 2 * h * h)
