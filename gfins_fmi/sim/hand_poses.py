"""A hand-turned IMU: a sequence of still poses at random orientations joined by turns,
on a rotating Earth, with its exact rates and specific forces (the truth of the
calibration at unknown poses, gfins_fmi.calibration.poses).

Each turn from pose k to pose k+1 is closed-form: C_b^n(t) = C_k exp(theta(t) [a x])
exp(phi(t) [b x]), with a the axis of the relative rotation C_k^T C_(k+1) (body axes),
theta(t) = Theta s(u) its angle on the minimum-jerk profile s(u) = 10u^3 - 15u^4 + 6u^5
(u = t / T, rate and acceleration zero at both ends), and phi(t) = A sin^3(pi u) a wobble
about an axis b perpendicular to a (zero with its rate and acceleration at both ends, so the turn ends at C_(k+1); it
makes the motion non-planar: coning). Body rate relative to the navigation frame:
omega_nb = exp(phi [b x])^T a theta' + b phi'. The IMU also feels the Earth's rate,
omega_ib = omega_nb + C_n^b omega_ie^n (ENU: [0, Omega cos L, Omega sin L]), and the
specific force of gravity and of its own motion about the hand's pivot, which sits at
``lever_m`` from the IMU (body axes): f = C_n^b [0, 0, g] + omega' x r + omega x (omega x r),
r = -lever (the IMU turning about a point off its centre). Sensor outputs: ImuErrors.apply
plus ImuNoise.sample.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.earth import WGS84, gravity, quat_multiply, quat_to_dcm
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise

__all__ = ["HandPoseRecord", "hand_turned_record", "random_orientation", "CONSUMER_MEMS_ERRORS"]

#: the issue's consumer MEMS: scale errors 1-3%, misalignments up to 1 deg, biases of a
#: few 0.1 m/s^2 and a few deg/s (stds of ImuErrors.random; scale 2% = 20000 ppm)
CONSUMER_MEMS_ERRORS = dict(gyro_bias_deg_h=2.0 * 3600, gyro_scale_ppm=20000.0,
                            gyro_misalignment_arcsec=1800.0, accel_bias_ug=30000.0,
                            accel_scale_ppm=20000.0, accel_misalignment_arcsec=1800.0)


def random_orientation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly distributed rotation as q_b^n (Shoemake's method)."""
    u1, u2, u3 = rng.uniform(size=3)
    q = np.array([np.sqrt(1 - u1) * np.sin(2 * np.pi * u2), np.sqrt(1 - u1) * np.cos(2 * np.pi * u2),
                  np.sqrt(u1) * np.sin(2 * np.pi * u3), np.sqrt(u1) * np.cos(2 * np.pi * u3)])
    return q if q[0] >= 0 else -q


def _axis_angle(q):
    """Axis (3,) and angle in [0, pi] of a unit quaternion."""
    q = q if q[0] >= 0 else -q
    s = np.linalg.norm(q[1:])
    if s < 1e-12:
        return np.array([1.0, 0.0, 0.0]), 0.0
    return q[1:] / s, 2 * np.arctan2(s, q[0])


def _qrot(axis, angle):
    """Quaternions (n, 4) of rotations by angle (n,) about a fixed axis (3,)."""
    return np.column_stack([np.cos(angle / 2), np.outer(np.sin(angle / 2), axis)])


@dataclass
class HandPoseRecord:
    """A simulated hand-turned record and its truth.

    Attributes
    ----------
    imu : ImuRecord of rates (sensor outputs: errors and noise applied)
    t_s : (n,) sample times
    q_bn : (n, 4) true attitude
    omega_ib_rad_s, f_m_s2 : (n, 3) true rates and specific forces (body axes)
    poses : (k, 2) sample index ranges [start, end) of the still poses
    errors : ImuErrors applied; noise : ImuNoise added
    lat_rad, h_m, g_m_s2 : the site and its gravity
    """
    imu: ImuRecord
    t_s: np.ndarray
    q_bn: np.ndarray
    omega_ib_rad_s: np.ndarray
    f_m_s2: np.ndarray
    poses: np.ndarray
    errors: ImuErrors
    noise: ImuNoise
    lat_rad: float
    h_m: float
    g_m_s2: float


def hand_turned_record(errors: ImuErrors, noise: ImuNoise, *, n_poses: int = 36,
                       still_s=(5.0, 10.0), turn_s=(1.0, 3.0), first_still_s: float = 30.0,
                       rate_hz: float = 100.0, lat_rad: float = 0.7, h_m: float = 100.0,
                       wobble_rad: float = 0.3, lever_m: float = 0.05,
                       seed: int = 0) -> HandPoseRecord:
    """Simulate ``n_poses`` still poses (the first ``first_still_s`` long, the others
    uniform in ``still_s``) at uniformly random orientations joined by turns of uniform
    duration in ``turn_s``, sampled at ``rate_hz`` (see the module docstring).

    The turn to the next pose takes the shortest rotation there; orientations closer
    than 30 deg to the previous one are drawn again (a hand turns an IMU noticeably).
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    qs = [random_orientation(rng)]
    while len(qs) < n_poses:
        q = random_orientation(rng)
        if _axis_angle(quat_multiply(qs[-1] * [1, -1, -1, -1], q))[1] > np.radians(30):
            qs.append(q)
    stills = np.r_[first_still_s, rng.uniform(*still_s, n_poses - 1)]
    turns = rng.uniform(*turn_s, n_poses - 1)
    n_still = np.round(stills * rate_hz).astype(int)
    n_turn = np.round(turns * rate_hz).astype(int)
    lever = rng.normal(0.0, lever_m, 3) if lever_m > 0 else np.zeros(3)
    q_parts, w_parts, wd_parts, poses = [], [], [], []
    k0 = 0
    for k in range(n_poses):
        q_parts.append(np.tile(qs[k], (n_still[k], 1)))
        w_parts.append(np.zeros((n_still[k], 3)))
        wd_parts.append(np.zeros((n_still[k], 3)))
        poses.append((k0, k0 + n_still[k]))
        k0 += n_still[k]
        if k == n_poses - 1:
            break
        a, Theta = _axis_angle(quat_multiply(qs[k] * [1, -1, -1, -1], qs[k + 1]))
        b = np.cross(a, rng.normal(size=3))
        b /= np.linalg.norm(b)
        A = rng.uniform(-wobble_rad, wobble_rad)
        # samples strictly inside the turn, u = i / (n + 1): the poses hold its end points
        T = (n_turn[k] + 1) * dt
        u = np.arange(1, n_turn[k] + 1) / (n_turn[k] + 1)
        th = Theta * (10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5)
        thd = Theta * (30 * u ** 2 - 60 * u ** 3 + 30 * u ** 4) / T
        thdd = Theta * (60 * u - 180 * u ** 2 + 120 * u ** 3) / T ** 2
        sn, cs = np.sin(np.pi * u), np.cos(np.pi * u)
        ph = A * sn ** 3
        phd = 3 * A * np.pi * sn ** 2 * cs / T
        phdd = 3 * A * np.pi ** 2 * (2 * sn * cs ** 2 - sn ** 3) / T ** 2
        qa, qb = _qrot(a, th), _qrot(b, ph)
        q_parts.append(quat_multiply(quat_multiply(np.broadcast_to(qs[k], qa.shape), qa), qb))
        Cb = quat_to_dcm(qb)                                   # exp(phi [b x])
        a_b = np.einsum("nji,j->ni", Cb, a)                    # C_b^T a
        w = a_b * thd[:, None] + np.outer(phd, b)
        # omega' = d/dt (Cb^T a theta') + b phi'' ; d(Cb^T a)/dt = -phi' b x (Cb^T a)
        wd = a_b * thdd[:, None] - np.cross(np.outer(phd, b), a_b) * thd[:, None] + np.outer(phdd, b)
        w_parts.append(w)
        wd_parts.append(wd)
        k0 += n_turn[k]
    q = np.concatenate(q_parts)
    w_nb = np.concatenate(w_parts)
    w_dot = np.concatenate(wd_parts)
    n = len(q)
    C = quat_to_dcm(q)                                         # C_b^n
    g = float(gravity(lat_rad, h_m))
    w_ie_n = WGS84.omega_ie * np.array([0.0, np.cos(lat_rad), np.sin(lat_rad)])
    w_ib = w_nb + np.einsum("nji,j->ni", C, w_ie_n)
    r = -lever
    f = (np.einsum("nji,j->ni", C, np.array([0.0, 0.0, g])) + np.cross(w_dot, r)
         + np.cross(w_nb, np.cross(w_nb, r)))
    gyro, accel = errors.apply(w_ib, f)
    ng, na = noise.sample(n, dt, rng)
    t = np.arange(n) * dt
    imu = ImuRecord(t, gyro + ng, accel + na, "rates", f"hand_turned_record(seed={seed})")
    return HandPoseRecord(imu, t, q, w_ib, f, np.array(poses), errors, noise, lat_rad, h_m, g)
