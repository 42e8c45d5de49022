"""Calibration of an IMU at unknown static poses, without a turntable (Tedaldi, Pretto and
Menegatti, "A robust and easy to implement method for IMU calibration without external
equipments", ICRA 2014; the method of the imu_tk library), on the model of
:class:`~gfins_fmi.nav.imu_errors.ImuErrors`.

1. **Still poses** (:mod:`gfins_fmi.calibration.still`): the record starts at rest, then the
   IMU is turned by hand to >= ~20 orientations and held still at each.
2. **Accelerometers** (Tedaldi eq. 10-12): at rest the specific force has the norm of
   gravity g (normal gravity at the site, or given), whatever the orientation. With the
   model a = (I + S_a)(I + N_a) f + b_a (+ K2 u^2), the pose means a_k give residuals
   r_k = (|f(a_k)| - g) / sigma_k, sigma_k the pose mean's noise along gravity (from the
   pose's own samples); minimised with a robust loss (scipy's soft_l1). |f| = g does not
   see a rotation of the body frame, so the frame is DEFINED by the accelerometers: x_b
   along the x accelerometer, y_b in the plane of x and y (N_a lower triangular: 3
   misalignment angles; 9 parameters, 12 with K2).
3. **Gyros** (Tedaldi eq. 13-16): between two poses the compensated rates, integrated
   (quaternion product of the two-sample rotation vectors (w0 + w1) T/2 + T^2/12 w0 x w1,
   exact for rates linear over a sample), must turn the gravity direction of pose k into
   that of pose k+1: residual u_(k+1) x (R_k^T u_k) on the two axes perpendicular to
   u_(k+1), weighted by the angle random walk over the turn and the directions' noise.
   Parameters: scale (3), misalignment (6: a full N_g, the body frame being the
   accelerometers'), bias. The bias is the initial still period's gyro mean less the
   Earth's rate there, which is known along the vertical from the latitude; its
   horizontal part (the heading is unknown) is a nuisance parameter with its prior
   (Omega cos L)^2 / 2 per axis, carried through the turns by the integrated attitude;
   the still mean's noise is the bias's prior (``gyro_bias="still"``) or the turns alone
   estimate it (``"fit"``).

Parameter uncertainties come from the weighted Jacobian at the solution (scaled up by the
reduced chi-square when that exceeds 1). Too few poses or turns, poses too alike to
separate some parameters (named), and motion inside detected poses are refused.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from gfins_fmi.calibration.still import StillDetector, StillIntervals, detect_still
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.earth import WGS84, gravity, quat_multiply, quat_to_dcm
from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors

__all__ = ["PoseCalibration", "calibrate_poses", "ACCEL_NAMES", "GYRO_NAMES", "pose_frame_truth",
           "PoseRefused"]

ACCEL_NAMES = ("accel_scale_x", "accel_scale_y", "accel_scale_z", "accel_mis_yx", "accel_mis_zx",
               "accel_mis_zy", "accel_bias_x", "accel_bias_y", "accel_bias_z", "accel_k2_x",
               "accel_k2_y", "accel_k2_z")
GYRO_NAMES = ("gyro_scale_x", "gyro_scale_y", "gyro_scale_z", "gyro_mis_xy", "gyro_mis_xz",
              "gyro_mis_yx", "gyro_mis_yz", "gyro_mis_zx", "gyro_mis_zy", "gyro_bias_x",
              "gyro_bias_y", "gyro_bias_z")
_LOWER = ((1, 0), (2, 0), (2, 1))
_OFF = ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))


class PoseRefused(ValueError):
    """The record cannot give the calibration; the message says why and what to change."""


def _errors(accel=None, gyro=None, gyro_bias=None) -> ImuErrors:
    """ImuErrors of SI parameter vectors (accel 9 or 12, gyro 9, bias 3)."""
    kw = {}
    if accel is not None:
        N = np.zeros((3, 3))
        for (i, j), v in zip(_LOWER, accel[3:6]):
            N[i, j] = v
        kw.update(accel_scale_ppm=accel[0:3] / PPM, accel_misalignment_arcsec=N / ARCSEC,
                  accel_bias_ug=accel[6:9] / UG)
        if len(accel) == 12:
            kw["accel_k2_ug_g2"] = accel[9:12] * G0 / 1e-6
    if gyro is not None:
        N = np.zeros((3, 3))
        for (i, j), v in zip(_OFF, gyro[3:9]):
            N[i, j] = v
        kw.update(gyro_scale_ppm=gyro[0:3] / PPM, gyro_misalignment_arcsec=N / ARCSEC)
    if gyro_bias is not None:
        kw["gyro_bias_deg_h"] = np.asarray(gyro_bias) / DEG_H
    return ImuErrors(**kw)


def _compensate_accel(p, a):
    return _errors(accel=p).compensate(np.zeros_like(a), a)[1]


def _perp_basis(u):
    """Two unit vectors perpendicular to each row of u (n, 3), (n, 2, 3)."""
    ref = np.where(np.abs(u[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    e1 = np.cross(u, ref)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(u, e1)
    return np.stack([e1, e2], axis=1)


def _qexp(phi):
    """Quaternions (..., 4) of rotation vectors (..., 3)."""
    th = np.linalg.norm(phi, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.where(th > 1e-12, np.sin(th / 2) / th, 0.5 - th * th / 48)
    return np.concatenate([np.cos(th / 2), k * phi], axis=-1)


def _qrotate_inv(q, v):
    """C(q)^T v for quaternions q (n, 4) and vectors v (n, 3): v in the rotated frame."""
    w, x = q[:, :1], -q[:, 1:]
    t = 2 * np.cross(x, v)
    return v + w * t + np.cross(x, t)


def _product(q):
    """The ordered product q[:, 0] (x) q[:, 1] (x) ... of (m, L, 4), by pairs (log2 L steps)."""
    while q.shape[1] > 1:
        if q.shape[1] % 2:
            q = np.concatenate([q, np.broadcast_to([1.0, 0.0, 0.0, 0.0], (q.shape[0], 1, 4))], axis=1)
        q = quat_multiply(q[:, 0::2], q[:, 1::2])
    return q[:, 0]


def _scan(q):
    """Inclusive prefix products along axis 1 of (m, L, 4), in order (Hillis-Steele)."""
    q = q.copy()
    s = 1
    while s < q.shape[1]:
        q[:, s:] = quat_multiply(q[:, :-s], q[:, s:])
        s *= 2
    return q


@dataclass
class _Turns:
    idx: np.ndarray          # (m, L+1) sample indices of each turn, padded with the last
    valid: np.ndarray        # (m, L) increments that are real
    dt: np.ndarray           # (m, L)
    T_s: np.ndarray          # (m,) duration


def _turns(t, ranges) -> _Turns:
    starts = ranges[:-1, 1] - 1                  # last sample of pose k
    ends = ranges[1:, 0]                          # first sample of pose k + 1
    L = int(np.max(ends - starts))
    off = np.arange(L + 1)
    idx = np.minimum(starts[:, None] + off, ends[:, None])
    valid = off[1:][None, :] <= (ends - starts)[:, None]
    dt = np.where(valid, t[idx[:, 1:]] - t[idx[:, :-1]], 0.0)
    return _Turns(idx, valid, dt, t[ends] - t[starts])


def _increments(w, turns: _Turns, earth=None):
    """Two-sample rotation vectors (m, L, 3) of each turn from rates w (n, 3); ``earth``
    (m, L+1, 3), the Earth's rate in body axes at the turn's samples, is removed first."""
    wi = w[turns.idx]                                        # (m, L+1, 3)
    if earth is not None:
        wi = wi - earth
    w0, w1 = wi[:, :-1], wi[:, 1:]
    dt = turns.dt[..., None]
    phi = 0.5 * (w0 + w1) * dt + dt * dt / 12.0 * np.cross(w0, w1)
    return np.where(turns.valid[..., None], phi, 0.0)


def _integrate(w, turns: _Turns, earth=None):
    """Rotations (m, 4) body(k+1) -> body(k) of each turn (see :func:`_increments`)."""
    return _product(_qexp(_increments(w, turns, earth)))


def _to_pose0(w, turns: _Turns):
    """C^T (m, L+1, 3, 3) at every sample of every turn: pose-0 axes -> body(t) axes,
    from rates w integrated turn by turn (the poses in between are still)."""
    part = _scan(_qexp(_increments(w, turns)))                # body(t) -> body(turn start)
    start = _scan(np.concatenate([[[1.0, 0, 0, 0]], part[:-1, -1]])[None])[0]   # turn start -> pose 0
    q = quat_multiply(np.broadcast_to(start[:, None], part.shape), part)
    q = np.concatenate([start[:, None], q], axis=1)           # (m, L+1, 4)
    C = quat_to_dcm(q)                                        # body(t) -> pose 0
    return np.swapaxes(C, -1, -2)


@dataclass
class PoseCalibration:
    """The result of :func:`calibrate_poses`.

    Attributes
    ----------
    errors : ImuErrors in the accelerometer-defined body frame (the module docstring)
    accel, accel_cov : SI parameters (ACCEL_NAMES order; 9 or 12) and their covariance
    gyro, gyro_cov : SI parameters (GYRO_NAMES: scale, misalignment, bias) and covariance
    g_m_s2 : the gravity fitted to
    still : StillIntervals (the poses used)
    pose_table : per pose: t0, t1, accel mean (3), |f| - g nominal and calibrated, its sigma
    turn_table : per turn: t0, t1, angle turned, direction residual before (raw rates
        less the initial mean) and after, its sigma (rad)
    accel_chi2, gyro_chi2 : weighted chi-square and degrees of freedom of each fit
    notes : what was found and done, in words
    """
    errors: ImuErrors
    accel: np.ndarray
    accel_cov: np.ndarray
    gyro: np.ndarray
    gyro_cov: np.ndarray
    g_m_s2: float
    still: StillIntervals
    pose_table: dict
    turn_table: dict
    accel_chi2: tuple
    gyro_chi2: tuple
    notes: list = field(default_factory=list)

    @property
    def names(self) -> tuple:
        return ACCEL_NAMES[:len(self.accel)] + GYRO_NAMES

    @property
    def values(self) -> np.ndarray:
        return np.r_[self.accel, self.gyro]

    @property
    def std(self) -> np.ndarray:
        return np.sqrt(np.r_[np.diag(self.accel_cov), np.diag(self.gyro_cov)])


def pose_frame_truth(errors: ImuErrors) -> np.ndarray:
    """The parameters (ACCEL_NAMES[:9] + GYRO_NAMES, SI) that a perfect pose calibration
    finds for a sensor with ``errors`` (no K2): the accelerometer matrix (I + S)(I + N)
    written as L Q (L lower triangular, Q a rotation: the LQ decomposition), the body
    frame turned by Q, the gyro matrix then M_g Q^T split into (I + S)(I + N)."""
    s_a = np.asarray(errors.accel_scale_ppm if errors.accel_scale_ppm is not None else np.zeros(3)) * PPM
    N_a = np.asarray(errors.accel_misalignment_arcsec if errors.accel_misalignment_arcsec is not None
                     else np.zeros((3, 3))) * ARCSEC
    s_g = np.asarray(errors.gyro_scale_ppm if errors.gyro_scale_ppm is not None else np.zeros(3)) * PPM
    N_g = np.asarray(errors.gyro_misalignment_arcsec if errors.gyro_misalignment_arcsec is not None
                     else np.zeros((3, 3))) * ARCSEC
    M_a = np.diag(1 + s_a) @ (np.eye(3) + N_a)
    Q_, R_ = np.linalg.qr(M_a.T)                 # M_a^T = Q_ R_  ->  M_a = R_^T Q_^T
    D = np.diag(np.sign(np.diag(R_)))
    L, Q = (D @ R_).T, (Q_ @ D).T                # M_a = L Q, diag(L) > 0
    sa = np.diag(L) - 1
    Na = np.diag(1 / np.diag(L)) @ L - np.eye(3)
    M_g = np.diag(1 + s_g) @ (np.eye(3) + N_g) @ Q.T
    sg = np.diag(M_g) - 1
    Ng = np.diag(1 / np.diag(M_g)) @ M_g - np.eye(3)
    b_a = np.asarray(errors.accel_bias_ug if errors.accel_bias_ug is not None else np.zeros(3)) * UG
    b_g = np.asarray(errors.gyro_bias_deg_h if errors.gyro_bias_deg_h is not None else np.zeros(3)) * DEG_H
    return np.r_[sa, [Na[i, j] for i, j in _LOWER], b_a, sg, [Ng[i, j] for i, j in _OFF], b_g]


#: the largest 1-sigma (SI) a parameter may have for the poses to be called distinct
#: enough: ~100x what a 20-pose hand-turned record gives a consumer MEMS
_WEAK = {"accel_scale": 5e-3, "accel_mis": 5e-3, "accel_bias": 0.05, "accel_k2": 1e-3,
         "gyro_scale": 5e-3, "gyro_mis": 5e-3, "gyro_bias": 5e-3}


def _unobservable(J, names, what, n_obs):
    """Refuse when the weighted Jacobian J (at the start) leaves a parameter unseen or
    uncertain beyond _WEAK: name them."""
    scale = np.linalg.norm(J, axis=0)
    if np.any(scale == 0):
        bad = [names[i] for i in np.flatnonzero(scale == 0)]
        raise PoseRefused(f"{what}: {', '.join(bad)} cannot be seen from these {n_obs} poses")
    Js = J / scale
    U, s, Vt = np.linalg.svd(Js, full_matrices=False)
    std = np.sqrt(np.sum((Vt / np.maximum(s, 1e-300)[:, None]) ** 2, axis=0)) / scale
    bad = [n for n, sd in zip(names, std) if not sd <= _WEAK[n.rsplit("_", 1)[0]]]
    if bad:
        raise PoseRefused(f"{what}: the {n_obs} poses are too alike to separate {', '.join(bad)} "
                          "(turn the IMU so that every axis points up and down, and in between)")


def calibrate_poses(imu: ImuRecord, *, gravity_m_s2: Optional[float] = None,
                    lat_rad: Optional[float] = None, h_m: float = 0.0,
                    detector: StillDetector = StillDetector(), accel_k2: bool = False,
                    gyro_bias: str = "still") -> PoseCalibration:
    """Calibrate accelerometers and gyros from a hand-turned record (module docstring).

    Parameters
    ----------
    imu : ImuRecord
        Rates or increments in SI (raw counts converted by their nominal sensitivity);
        at rest for ``detector.initial_s`` at the start.
    gravity_m_s2 : float, optional
        Local gravity; default: normal gravity at ``lat_rad``, ``h_m``.
    lat_rad, h_m : site latitude (rad) and height (m): the gravity and the Earth's rate
        along the vertical; without a latitude the Earth's rate is wholly unknown (prior
        Omega^2 / 3 per axis).
    detector : StillDetector
    accel_k2 : also fit the accelerometers' second-order coefficient K2
    gyro_bias : "still" (the initial period's mean, its noise as prior) or "fit" (the
        turns alone)

    Raises
    ------
    PoseRefused
        Too few poses; poses too alike (the parameters that cannot be separated named);
        motion inside a detected pose.
    """
    from scipy.optimize import least_squares   # lazy: scipy.optimize is slow to import
    if gyro_bias not in ("still", "fit"):
        raise ValueError(f"gyro_bias must be 'still' or 'fit'; got {gyro_bias!r}")
    if gravity_m_s2 is None and lat_rad is None:
        raise ValueError("give the gravity (gravity_m_s2) or the site (lat_rad, h_m) to take "
                         "normal gravity from")
    g = float(gravity(lat_rad, h_m)) if gravity_m_s2 is None else float(gravity_m_s2)
    if not (np.isfinite(g) and 9.7 < g < 9.9):
        raise ValueError(f"gravity must be that of the Earth's surface, 9.7..9.9 m/s^2; got {g!r}")
    rec = imu.to_rates()
    still = detect_still(rec, detector)
    notes = list(still.notes)
    ranges = still.ranges
    k = len(ranges)
    n_acc = 12 if accel_k2 else 9
    if k < n_acc + 3:
        raise PoseRefused(f"{k} still poses found; the accelerometer fit has {n_acc} parameters and "
                          f"needs at least {n_acc + 3} poses (turn the IMU to more orientations, or "
                          "loosen the still detector: " + "; ".join(still.notes) + ")")
    t, a, w = rec.t_s, rec.accel, rec.gyro
    dt = float(np.median(np.diff(t)))
    # ---- pose means and their noise
    a_mean = np.array([a[s:e].mean(axis=0) for s, e in ranges])
    a_cov = np.array([np.cov(a[s:e].T) / (e - s) for s, e in ranges])
    w_mean0 = w[ranges[0, 0]:ranges[0, 1]].mean(axis=0)
    arw = float(np.sqrt(np.mean(np.var(w[ranges[0, 0]:ranges[0, 1]], axis=0)) * dt))   # rad/sqrt(s)
    # motion inside a pose: its gyro mean (less the initial one) against the window noise
    for j, (s, e) in enumerate(ranges[1:], 1):
        ang = np.linalg.norm((w[s:e] - w_mean0).sum(axis=0) * dt)
        # 6 sigma of the angle random walk over the pose, and the bias's change up to 5%
        lim = 6 * arw * np.sqrt((e - s) * dt) + 0.05 * (e - s) * dt * np.linalg.norm(w_mean0) + np.radians(0.5)
        if ang > lim:
            raise PoseRefused(f"pose {j} ({t[s]:.1f}..{t[e - 1]:.1f} s) turns by {np.degrees(ang):.2f} deg: "
                              "motion inside a detected pose; lower the detector's factors "
                              "(--still-accel, --still-gyro) or hold the IMU still longer")
    # ---- accelerometers
    def acc_res(p):
        try:
            f = _compensate_accel(p, a_mean)
        except ValueError:          # a step beyond the model's range: a wall for the optimiser
            return np.full(k, 1e12)
        nrm = np.linalg.norm(f, axis=1)
        u = f / nrm[:, None]
        sig = np.sqrt(np.einsum("ki,kij,kj->k", u, a_cov, u))
        return (nrm - g) / sig
    p0 = np.zeros(n_acc)
    J0 = least_squares(acc_res, p0, max_nfev=1).jac
    _unobservable(J0, ACCEL_NAMES[:n_acc], "accelerometer fit", k)
    # least squares first (far from the solution every pose would be an 'outlier'), then
    # the robust loss from there
    pa = least_squares(acc_res, p0, x_scale="jac", xtol=1e-12, ftol=1e-12).x
    pa = least_squares(acc_res, pa, loss="soft_l1", f_scale=3.0, x_scale="jac", xtol=1e-12, ftol=1e-12).x
    r = acc_res(pa)
    J = least_squares(acc_res, pa, max_nfev=1).jac
    dof = k - n_acc
    chi2a = float(r @ r)
    cov_a = np.linalg.inv(J.T @ J) * max(1.0, chi2a / dof)
    out = np.abs(r) > 5
    if np.any(out):
        notes.append(f"accelerometer fit: poses {np.flatnonzero(out).tolist()} off by more than 5 sigma "
                     "(down-weighted by the robust loss)")
    f_cal = _compensate_accel(pa, a_mean)
    u = f_cal / np.linalg.norm(f_cal, axis=1)[:, None]
    sig_u = np.sqrt(np.einsum("ki,kij,kj->k", u, a_cov, u)) / g     # direction noise, rad (one axis)
    # ---- gyros
    turns = _turns(t, ranges)
    basis = _perp_basis(u[1:])
    Om = WGS84.omega_ie
    u0 = u[0]
    if lat_rad is not None:
        up = Om * np.sin(lat_rad) * u0
        hb = _perp_basis(u0[None])[0]                                 # (2, 3)
        h_std = Om * abs(np.cos(lat_rad)) / np.sqrt(2)
        n_h = 2
    else:
        up, hb, h_std, n_h = np.zeros(3), np.eye(3), Om / np.sqrt(3), 3
    b_std = arw / np.sqrt((ranges[0, 1] - ranges[0, 0]) * dt)
    sig_turn = np.sqrt(arw ** 2 * turns.T_s + sig_u[:-1] ** 2 + sig_u[1:] ** 2)
    n_g = 12 + n_h

    def gyro_parts(q):
        earth0 = up + q[12:12 + n_h] @ hb
        M = np.diag(1 + q[0:3])
        N = np.zeros((3, 3))
        for (i, j), v in zip(_OFF, q[3:9]):
            N[i, j] = v
        M = M @ (np.eye(3) + N)
        bias = w_mean0 - M @ earth0 + q[9:12]
        return earth0, bias

    used = np.unique(turns.idx)
    w_used = w[used]
    zeros = np.zeros_like(w_used)

    def gyro_rates(q):
        # the compensated rates at the turns' samples (other rows are not read)
        earth0, bias = gyro_parts(q)
        out = np.zeros_like(w)
        out[used] = _errors(gyro=q, gyro_bias=bias).compensate(w_used, zeros)[0]
        return out, earth0

    C0 = None      # pose 0 -> body(t) at the turns' samples, from a first fit without the Earth

    def gyro_res(q):
        try:
            wc, earth0 = gyro_rates(q)
        except ValueError:          # a step beyond the model's range: a wall for the optimiser
            return np.full(2 * (k - 1) + n_h + (3 if gyro_bias == "still" else 0), 1e12)
        R = _integrate(wc, turns, None if C0 is None else C0 @ earth0)
        pred = _qrotate_inv(R, u[:-1])
        e = np.cross(u[1:], pred)
        res = np.einsum("kij,kj->ki", basis, e) / sig_turn[:, None]
        prior = q[12:12 + n_h] / h_std
        if gyro_bias == "still":
            prior = np.r_[q[9:12] / b_std, prior]
        return np.r_[res.ravel(), prior]

    q0 = np.zeros(n_g)
    Jg0 = least_squares(gyro_res, q0, max_nfev=1).jac
    _unobservable(Jg0[:, :9 if gyro_bias == "still" else 12], GYRO_NAMES[:9 if gyro_bias == "still" else 12],
                  "gyro fit", k)
    q = least_squares(gyro_res, q0, x_scale="jac", xtol=1e-10, ftol=1e-10).x
    # the Earth's rotating image in the turns from the first fit's attitude, then the fit again
    C0 = _to_pose0(gyro_rates(q)[0], turns)
    q = least_squares(gyro_res, q, loss="soft_l1", f_scale=3.0, x_scale="jac", xtol=1e-12, ftol=1e-12).x
    rg = gyro_res(q)
    Jg = least_squares(gyro_res, q, max_nfev=1).jac
    dofg = 2 * (k - 1) - (9 if gyro_bias == "still" else 12)
    n_data = 2 * (k - 1)
    chi2g = float(rg[:n_data] @ rg[:n_data])
    cov_q = np.linalg.inv(Jg.T @ Jg) * max(1.0, chi2g / max(dofg, 1))
    earth0, bias = gyro_parts(q)
    # the bias's covariance: bias = w_mean0 - M earth0 + db (linearised in q)
    eps = 1e-7
    G = np.zeros((3, n_g))
    for j in range(n_g):
        dq = np.zeros(n_g)
        dq[j] = eps
        G[:, j] = (gyro_parts(q + dq)[1] - gyro_parts(q - dq)[1]) / (2 * eps)
    T9 = np.zeros((12, n_g))
    T9[:9, :9] = np.eye(9)
    T9[9:] = G
    gyro_vec = np.r_[q[:9], bias]
    gyro_cov = T9 @ cov_q @ T9.T
    errors = _errors(accel=pa, gyro=q[:9], gyro_bias=bias)
    # ---- tables: before (nominal) and after
    raw = np.linalg.norm(a_mean, axis=1) - g
    after = np.linalg.norm(f_cal, axis=1) - g
    pose_table = {"t0_s": t[ranges[:, 0]], "t1_s": t[ranges[:, 1] - 1], "accel_mean_m_s2": a_mean,
                  "norm_minus_g_nominal_m_s2": raw, "norm_minus_g_m_s2": after,
                  "sigma_m_s2": sig_u * g}
    w_raw = w - w_mean0
    R_raw = _integrate(w_raw, turns)
    u_raw = a_mean / np.linalg.norm(a_mean, axis=1)[:, None]
    before = np.linalg.norm(np.cross(u_raw[1:], _qrotate_inv(R_raw, u_raw[:-1])), axis=1)
    wc, e0 = gyro_rates(q)
    R_cal = _integrate(wc, turns, C0 @ e0)
    after_g = np.linalg.norm(np.cross(u[1:], _qrotate_inv(R_cal, u[:-1])), axis=1)
    angle = 2 * np.arccos(np.clip(np.abs(R_cal[:, 0]), 0, 1))
    turn_table = {"t0_s": t[ranges[:-1, 1] - 1], "t1_s": t[ranges[1:, 0]], "angle_rad": angle,
                  "residual_nominal_rad": before, "residual_rad": after_g, "sigma_rad": sig_turn}
    notes.append(f"accelerometers: {k} poses, chi-square {chi2a:.1f} for {dof} degrees of freedom; "
                 f"RMS |f| - g {np.sqrt(np.mean(raw ** 2)):.3g} m/s^2 nominal -> {np.sqrt(np.mean(after ** 2)):.3g} "
                 f"m/s^2 (noise of a pose mean {np.sqrt(np.mean((sig_u * g) ** 2)):.3g} m/s^2)")
    notes.append(f"gyros: {k - 1} turns, chi-square {chi2g:.1f} for {dofg} degrees of freedom; RMS gravity-"
                 f"direction residual {np.degrees(np.sqrt(np.mean(before ** 2))):.3g} deg (initial mean removed) "
                 f"-> {np.degrees(np.sqrt(np.mean(after_g ** 2))):.3g} deg (noise {np.degrees(np.sqrt(np.mean(2 * sig_turn ** 2))):.3g} deg)")
    return PoseCalibration(errors, pa, cov_a, gyro_vec, gyro_cov, g, still, pose_table, turn_table,
                           (chi2a, dof), (chi2g, dofg), notes)
