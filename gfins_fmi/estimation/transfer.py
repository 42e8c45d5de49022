"""Transfer alignment (issue 24): a slave IMU aligned and calibrated in motion against a
master INS on the same host — its attitude, its mounting on the host (heading, pitch and
roll relative to the master's axes), its sensor biases, the lever arm between the two
IMUs and the time offset between the two data streams — by the integrated-navigation
filter of the C core with the master kinds of its measurement table (velocity, attitude,
position of the master; gf_ins_gnss.h, "Transfer alignment") and the transfer-alignment
states (FilterConfig ``master_mount``, ``master_lever``, ``master_time_offset``,
``flexure``).

    result = transfer_align(slave_imu, master, config=FilterConfig(imu=..., master_mount=True,
                            master_lever=True, master_time_offset=True), matching="velocity+attitude")
    result.final()            # mounting, lever arm, offset, biases, attitude with 1-sigma

``master`` is a navigation record (a :class:`~gfins_fmi.io.records.TruthRecord`: KF-GINS
``.nav``, our CSV or a truth record), its angular rate given or taken from its attitude
(:func:`master_rate_from_attitude`); its own errors enter as measurement noise
(:class:`MasterErrors`). docs/alignment.md, "Transfer alignment".
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from gfins_fmi._lib import lib
from gfins_fmi.estimation.config import FilterConfig, InitialState, TRANSFER_NAMES, state_names
from gfins_fmi.estimation.evaluation import reference_at
from gfins_fmi.estimation.measurements import MEAS_DTYPE
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.estimation.solution import IntegratedSolution
from gfins_fmi.nav.earth import (WGS84, attitude_error_rad, euler_to_quat, quat_multiply,
                                 quat_to_dcm, radii)
from gfins_fmi.nav.strapdown import NavState

__all__ = ["MATCHING", "MasterErrors", "master_rate_from_attitude", "master_measurements",
           "slave_initial_state", "transfer_align", "TransferAlignment", "TransferTruth"]

#: what the slave matches: the master's velocity, or its velocity and attitude (each
#: optionally with its position: ``position=True``)
MATCHING = ("velocity", "velocity+attitude")
_DEG = math.pi / 180.0


@dataclass(frozen=True)
class MasterErrors:
    """The master's own errors, as the slave filter's measurement noise (1-sigma).

    The filter takes them as white noise per epoch: give the part of the master's errors
    that changes over the alignment (a constant attitude error of the master turns the
    slave's attitude with it and leaves the mounting alone; a drifting velocity error
    looks like a slave accelerometer bias). ``attitude_bias_std_rad``, the master's
    constant attitude error, the filter cannot see: it is added to the slave's reported
    attitude 1-sigma (its attitude is only as good as the master's).

    Attributes
    ----------
    velocity_std_m_s : east, north, up (or one for all), m/s.
    attitude_std_rad : east, north tilt and heading (small angles, n frame), rad.
    position_std_m : east, north, up, m.
    attitude_bias_std_rad : the master's constant attitude error (east, north, up), rad;
        None: 0.
    """
    velocity_std_m_s: object = 0.02
    attitude_std_rad: object = (1e-4, 1e-4, 3e-4)
    position_std_m: object = 1.0
    attitude_bias_std_rad: object = None


def _three(name: str, value, unit: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, float), (3,)).copy()
    if not np.all(np.isfinite(arr) & (arr > 0)):
        raise ValueError(f"{name} must be one or three finite values > 0 ({unit}); got {value!r}")
    return arr


def master_rate_from_attitude(master) -> np.ndarray:
    """The master's angular rate w_im^m (m, 3; rad/s, master axes) at its epochs from its
    attitude record: the body rate w.r.t. the navigation frame by central differences of
    the attitude (log(C_(k-1)^T C_(k+1)) / (t_(k+1) - t_(k-1)), one-sided at the ends;
    truncation error dt^2 / 6 of the rate's second derivative: 1.7e-3 rad/s for a +-30
    deg roll at 1.3 rad/s sampled at 10 Hz), plus the Earth and transport rates turned
    into master axes. Give the master's own rates when it records them."""
    t = np.asarray(master.t_s, float)
    if len(t) < 2:
        raise ValueError("the master record needs at least two epochs to give its rate")
    q = euler_to_quat(*np.asarray(master.euler_rad, float).T)
    lo = np.r_[0, np.arange(len(t) - 2), len(t) - 2]
    hi = np.r_[1, np.arange(2, len(t)), len(t) - 1]
    qc = q[lo] * np.array([1.0, -1.0, -1.0, -1.0])
    rel = quat_multiply(qc, q[hi])                           # C_lo^T C_hi (body axes)
    rel *= np.where(rel[:, :1] < 0, -1.0, 1.0)
    s = np.linalg.norm(rel[:, 1:], axis=1)
    k = np.where(s > 1e-12, 2.0 * np.arctan2(s, rel[:, 0]) / np.maximum(s, 1e-300), 2.0)
    w_nm = rel[:, 1:] * (k / (t[hi] - t[lo]))[:, None]
    lat, h = np.asarray(master.lat_rad, float), np.asarray(master.h_m, float)
    v = np.asarray(master.v_enu_m_s, float)
    RM, RN = radii(lat)[:2]
    w_in = np.stack([-v[:, 1] / (RM + h), WGS84.omega_ie * np.cos(lat) + v[:, 0] / (RN + h),
                     WGS84.omega_ie * np.sin(lat) + v[:, 0] * np.tan(lat) / (RN + h)], 1)
    C = quat_to_dcm(q)
    return w_nm + np.einsum("nji,nj->ni", C, w_in)


def _master_rate(master, rate_rad_s) -> np.ndarray:
    """The master's rates given, checked, or from its attitude."""
    n = len(np.asarray(master.t_s))
    rate = master_rate_from_attitude(master) if rate_rad_s is None else np.asarray(rate_rad_s, float)
    if rate.shape != (n, 3) or not np.all(np.isfinite(rate)):
        raise ValueError(f"the master's rates must be finite, one row of three (rad/s, master axes) "
                         f"per epoch: ({n}, 3); got {rate.shape}")
    return rate


def master_measurements(master, rate_rad_s=None, *, matching: str = "velocity+attitude",
                        position: bool = False, errors: MasterErrors = MasterErrors(),
                        t_from_s: float = -math.inf, t_to_s: float = math.inf) -> np.ndarray:
    """The master's epochs in [t_from_s, t_to_s] as measurements of the slave filter
    (``MEAS_DTYPE`` rows of the master kinds, with the master's rate in ``aux``): its
    velocity, with ``matching="velocity+attitude"`` its attitude (heading, pitch, roll),
    with ``position`` its position; the stds from ``errors``."""
    if matching not in MATCHING:
        raise ValueError(f"matching must be one of {MATCHING}; got {matching!r}")
    t = np.asarray(master.t_s, float)
    rate = _master_rate(master, rate_rad_s)
    sel = (t >= t_from_s) & (t <= t_to_s)
    kinds = [(lib.GF_INS_MEAS_MASTER_VEL, np.asarray(master.v_enu_m_s, float),
              _three("MasterErrors.velocity_std_m_s", errors.velocity_std_m_s, "m/s"))]
    if matching == "velocity+attitude":
        kinds.append((lib.GF_INS_MEAS_MASTER_ATT, np.asarray(master.euler_rad, float),
                      _three("MasterErrors.attitude_std_rad", errors.attitude_std_rad, "rad")))
    if position:
        kinds.append((lib.GF_INS_MEAS_MASTER_POS, np.c_[master.lat_rad, master.lon_rad, master.h_m],
                      _three("MasterErrors.position_std_m", errors.position_std_m, "m")))
    m = int(np.count_nonzero(sel))
    out = np.zeros(m * len(kinds), MEAS_DTYPE)
    for j, (kind, z, std) in enumerate(kinds):   # at one epoch: velocity, attitude, position
        rows = slice(j, None, len(kinds))
        out["type"][rows] = kind
        out["t_s"][rows] = t[sel]
        out["z"][rows] = z[sel]
        out["std"][rows] = std
        out["aux"][rows] = rate[sel]
    return out


def slave_initial_state(master, rate_rad_s, t0_s: float, config: FilterConfig, *,
                        attitude_std_rad=1e-3, velocity_std_m_s=0.1, position_std_m=1.0,
                        gyro_bias_std_rad_s=1e-3, accel_bias_std_m_s2=0.03,
                        mount_std_rad=0.02, lever_std_m=0.1, time_offset_std_s=0.02) -> InitialState:
    """The slave's start from the master at t0_s (interpolated; attitude by slerp): the
    master's attitude turned by the configured mounting (C_s^n = C_m^n C_s^m), its
    velocity plus the lever arm's (C_m^n (w_em^m x r)), its position plus C_m^n r.

    Its attitude error is then the mounting's: with mounting states the two start
    correlated (``InitialState.attitude_from_master``, the prior that they cancel in the
    master's attitude) and ``attitude_std_rad`` is what the start adds (the master's own
    attitude error; default 1 mrad); without them the attitude std is that combined with
    ``mount_std_rad``. (Uncorrelated, an EKF that pins the master's attitude in its
    first epochs can trade the mounting against the slave's tilt and lock a wrong time
    offset: 2 of 100 runs of bench/study_transfer.py did.)"""
    t = np.asarray(master.t_s, float)
    ref = reference_at(master, np.array([t0_s])) if t[0] <= t0_s <= t[-1] else {"inside": [False]}
    if not ref["inside"][0] or ref["q"] is None or ref["v"] is None:
        raise ValueError(f"the slave's start t = {t0_s!r} s is outside the master record "
                         f"[{master.t_s[0]!r}, {master.t_s[-1]!r}] s (or it has no attitude or "
                         "velocity): the master must cover the slave record's start")
    w = np.array([np.interp(t0_s, t, np.asarray(rate_rad_s)[:, i]) for i in range(3)])
    q_m = ref["q"][0]
    C = quat_to_dcm(q_m)
    lat, h = float(ref["lat"][0]), float(ref["h"][0])
    r = np.asarray(config.master_lever_arm_m, float)
    w_ie = WGS84.omega_ie * np.array([0.0, math.cos(lat), math.sin(lat)])
    v = ref["v"][0] + C @ np.cross(w - C.T @ w_ie, r)
    u = C @ r
    RM, RN = radii(lat)[:2]
    a = np.asarray(config.master_mount_rad, float)
    q_s = quat_multiply(q_m, euler_to_quat(a[0], a[1], a[2]))
    nav = NavState(q_s, v, lat + u[1] / (RM + h), float(ref["lon"][0]) + u[0] / ((RN + h) * math.cos(lat)),
                   h + u[2], float(t0_s))
    att = np.asarray(attitude_std_rad, float)
    if not config.master_mount:
        att = np.hypot(att, np.asarray(mount_std_rad, float))
    return InitialState(nav, position_std_m=position_std_m, velocity_std_m_s=velocity_std_m_s,
                        attitude_std_rad=att, gyro_bias_std_rad_s=gyro_bias_std_rad_s,
                        accel_bias_std_m_s2=accel_bias_std_m_s2, master_mount_std_rad=mount_std_rad,
                        master_lever_std_m=lever_std_m, master_time_offset_std_s=time_offset_std_s,
                        attitude_from_master=True)


@dataclass(frozen=True)
class TransferTruth:
    """What a simulation (or a calibration) knows: the installation and the slave's
    biases, and optionally the slave's true navigation record (a TruthRecord at the
    slave's stamps) for its attitude."""
    mount_rad: object = None
    lever_arm_m: object = None
    time_offset_s: Optional[float] = None
    gyro_bias_rad_s: object = None
    accel_bias_m_s2: object = None
    slave: object = None


#: the estimates a TransferAlignment reports, with their units for the report
_QUANTITIES = (("mount_rad", "mounting heading, pitch, roll", "arcmin", 60.0 / _DEG),
               ("lever_arm_m", "lever arm x, y, z", "m", 1.0),
               ("time_offset_s", "time offset", "ms", 1e3),
               ("gyro_bias_rad_s", "gyro bias x, y, z", "deg/h", 3600.0 / _DEG),
               ("accel_bias_m_s2", "accelerometer bias x, y, z", "mg", 1e3 / 9.80665),
               ("euler_rad", "attitude heading, pitch, roll", "deg", 1.0 / _DEG))


@dataclass
class TransferAlignment:
    """The transfer alignment over time (row k: after slave sample k).

    Attributes
    ----------
    t_s (n,); mount_rad (n, 3) heading, pitch, roll of the slave in the master's axes and
    mount_std_rad; lever_arm_m (n, 3) and lever_std_m; time_offset_s (n,) and
    time_offset_std_s; gyro_bias_rad_s, accel_bias_m_s2 (n, 3) and their stds;
    euler_rad (n, 3) the slave's attitude and attitude_std_rad (n, 3: east, north, up;
    the filter's combined with the master's constant attitude error,
    ``MasterErrors.attitude_bias_std_rad``); solution: the filter's IntegratedSolution;
    config; matching. Blocks the configuration does not estimate hold the configured
    values with std NaN. Without mounting states or attitude matching the mounting is the
    one between the slave's estimated attitude and the master's (``mount_derived``
    True), its std from the slave's attitude std and the master's.
    """
    t_s: np.ndarray
    mount_rad: np.ndarray
    mount_std_rad: np.ndarray
    lever_arm_m: np.ndarray
    lever_std_m: np.ndarray
    time_offset_s: np.ndarray
    time_offset_std_s: np.ndarray
    gyro_bias_rad_s: np.ndarray
    gyro_bias_std_rad_s: np.ndarray
    accel_bias_m_s2: np.ndarray
    accel_bias_std_m_s2: np.ndarray
    euler_rad: np.ndarray
    attitude_std_rad: np.ndarray
    solution: IntegratedSolution
    config: FilterConfig
    matching: str
    mount_derived: bool = False

    def _stds(self) -> dict:
        return {"mount_rad": self.mount_std_rad, "lever_arm_m": self.lever_std_m,
                "time_offset_s": self.time_offset_std_s, "gyro_bias_rad_s": self.gyro_bias_std_rad_s,
                "accel_bias_m_s2": self.accel_bias_std_m_s2, "euler_rad": self.attitude_std_rad}

    def final(self) -> dict:
        """The estimates at the end, ``{name: (value, 1-sigma)}`` in SI units (mount_rad,
        lever_arm_m, time_offset_s, gyro_bias_rad_s, accel_bias_m_s2, euler_rad: attitude
        with its east/north/up 1-sigma); std NaN for what the configuration fixes."""
        stds = self._stds()
        return {name: (np.asarray(getattr(self, name))[-1], np.asarray(stds[name])[-1])
                for name, *_ in _QUANTITIES}

    def report(self) -> list:
        """Lines: each estimate at the end with its 1-sigma, in engineering units."""
        stds = self._stds()
        lines = [f"transfer alignment ({self.matching} matching), t = {self.t_s[-1]:.3f} s:"]
        for name, what, unit, k in _QUANTITIES:
            x = np.atleast_1d(np.asarray(getattr(self, name))[-1]) * k
            s = np.atleast_1d(np.asarray(stds[name])[-1]) * k
            if name == "euler_rad":
                vals = ", ".join(f"{a:.4f}" for a in x)
                lines.append(f"  {what}: {vals} deg; 1-sigma E/N/U "
                             + "/".join(f"{60 * b:.3g}" for b in s) + " arcmin")
                continue
            vals = ", ".join(("{:.4g} +- {:.2g}".format(a, b) if np.isfinite(b) else f"{a:.4g} (fixed)")
                             for a, b in zip(x, s))
            lines.append(f"  {what}: {vals} {unit}")
        return lines

    def errors(self, truth: TransferTruth) -> dict:
        """Errors against a truth and the share outside 3 sigma, per quantity the truth
        gives: ``{name: {"error": (n, k), "sigma": (n, k), "outside_3sigma": fraction over
        rows and axes, "final_error": (k,)}}`` (attitude: the rotation vector of estimate
        vs truth in the n frame against the east/north/up stds)."""
        out = {}
        pairs = (("mount_rad", truth.mount_rad, self.mount_std_rad),
                 ("lever_arm_m", truth.lever_arm_m, self.lever_std_m),
                 ("time_offset_s", truth.time_offset_s, self.time_offset_std_s),
                 ("gyro_bias_rad_s", truth.gyro_bias_rad_s, self.gyro_bias_std_rad_s),
                 ("accel_bias_m_s2", truth.accel_bias_m_s2, self.accel_bias_std_m_s2))
        for name, true, std in pairs:
            if true is None:
                continue
            est = np.asarray(getattr(self, name), float).reshape(len(self.t_s), -1)
            err = est - np.asarray(true, float).reshape(1, -1)
            sig = np.asarray(std, float).reshape(len(self.t_s), -1)
            ok = np.isfinite(sig)
            out[name] = {"error": err, "sigma": sig, "final_error": err[-1],
                         "outside_3sigma": float(np.mean(np.abs(err[ok]) > 3 * sig[ok])) if ok.any() else math.nan}
        if truth.slave is not None:
            ref = reference_at(truth.slave, self.t_s)
            inside = ref["inside"]
            q_est = self.solution.q_bn[inside]
            err = attitude_error_rad(q_est, ref["q"][inside])
            sig = self.attitude_std_rad[inside]
            out["attitude"] = {"error": err, "sigma": sig, "final_error": err[-1],
                               "outside_3sigma": float(np.mean(np.abs(err) > 3 * sig))}
        return out

    def plot(self, path, truth: Optional[TransferTruth] = None, title: str = "") -> None:
        """The convergence over time: mounting (arcmin), time offset (ms), lever arm (m) and
        the biases, each with +-3 sigma (and its error when a truth is given)."""
        import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        rows = [("mount_rad", self.mount_std_rad, "mounting (arcmin)", 60.0 / _DEG, ("heading", "pitch", "roll")),
                ("time_offset_s", self.time_offset_std_s, "time offset (ms)", 1e3, ("offset",)),
                ("lever_arm_m", self.lever_std_m, "lever arm (m)", 1.0, ("x", "y", "z")),
                ("gyro_bias_rad_s", self.gyro_bias_std_rad_s, "gyro bias (deg/h)", 3600 / _DEG, ("x", "y", "z")),
                ("accel_bias_m_s2", self.accel_bias_std_m_s2, "accel. bias (mg)", 1e3 / 9.80665, ("x", "y", "z"))]
        fig, ax = plt.subplots(len(rows), 1, figsize=(9, 11), sharex=True)
        t = self.t_s - self.t_s[0]
        for a, (name, std, label, k, axes) in zip(ax, rows):
            x = np.asarray(getattr(self, name), float).reshape(len(t), -1) * k
            s = np.asarray(std, float).reshape(len(t), -1) * k
            true = None if truth is None else getattr(truth, name, None)
            if true is not None:
                x = x - np.asarray(true, float).reshape(1, -1) * k
                label = label.replace(" (", " error (")
            for i, nm in enumerate(axes):
                line, = a.plot(t, x[:, i], lw=1, label=nm)
                a.plot(t, 3 * s[:, i], lw=0.6, ls="--", color=line.get_color())
                a.plot(t, -3 * s[:, i], lw=0.6, ls="--", color=line.get_color())
            a.set_ylabel(label)
            a.legend(loc="upper right", fontsize=7, ncol=3)
            a.grid(alpha=0.3)
        ax[-1].set_xlabel("time since the start (s); dashed: +-3 sigma")
        ax[0].set_title(title or f"transfer alignment, {self.matching} matching")
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)


def _euler_rows(q: np.ndarray) -> np.ndarray:
    """(heading, pitch, roll) of (n, 4) quaternions, the Euler convention of the core
    (heading not wrapped: the mounting's is near 0)."""
    C = quat_to_dcm(q)
    pitch = np.arcsin(np.clip(C[:, 2, 1], -1.0, 1.0))
    return np.stack([np.arctan2(C[:, 0, 1], C[:, 1, 1]), pitch, np.arctan2(-C[:, 2, 0], C[:, 2, 2])], 1)


def _derived_mount(sol: IntegratedSolution, master, offset_s: np.ndarray, att_std: np.ndarray,
                   master_std: np.ndarray):
    """The mounting between the slave's attitude and the master's at the instant each row
    describes (master time = slave time - offset; slerp), and its std: the attitude stds
    (the slave's and the master's, n frame) through the derivative of the Euler angles
    of C_m^n^T exp([phi x]) C_s^n with respect to phi (central differences)."""
    ref = reference_at(master, sol.t_s - offset_s)
    n = len(sol.t_s)
    out, std = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    ok = ref["inside"]
    if not np.any(ok) or ref["q"] is None:
        return out, std
    qm_c = ref["q"][ok] * np.array([1.0, -1.0, -1.0, -1.0])
    q_s = sol.q_bn[ok]
    out[ok] = _euler_rows(quat_multiply(qm_c, q_s))
    var = att_std[ok] ** 2 + master_std[None, :] ** 2
    acc = np.zeros((int(ok.sum()), 3))
    h = 1e-6
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        qp = quat_multiply(qm_c, quat_multiply(np.r_[1.0, 0.5 * e], q_s))
        qn = quat_multiply(qm_c, quat_multiply(np.r_[1.0, -0.5 * e], q_s))
        d = (_euler_rows(qp) - _euler_rows(qn)) / (2 * h)
        acc += d ** 2 * var[:, j:j + 1]
    std[ok] = np.sqrt(acc)
    return out, std


def _block(sol: IntegratedSolution, names: tuple, first: str, size: int):
    """Columns of a state block in the per-row stds (NaN when the block is absent)."""
    n = len(sol.t_s)
    if first not in names:
        return np.full((n, size), np.nan)
    i = names.index(first)
    return sol.state_std[:, i:i + size]


def transfer_align(slave_imu, master, *, config: FilterConfig, master_rate_rad_s=None,
                   matching: str = "velocity+attitude", position: bool = False,
                   master_errors: MasterErrors = MasterErrors(), initial: Optional[InitialState] = None,
                   progress: bool = False, **initial_std) -> TransferAlignment:
    """Align and calibrate a slave IMU against a master INS (module docstring).

    Parameters
    ----------
    slave_imu : ImuRecord of the slave (increments or rates as ``config.input``).
    master : the master's navigation record (TruthRecord: t_s, lat_rad, lon_rad, h_m,
        v_enu_m_s, euler_rad), stamped by the master's clock.
    config : FilterConfig with the slave's noise, the transfer-alignment states to
        estimate and the nominal ``master_mount_rad``, ``master_lever_arm_m``,
        ``master_time_offset_s``.
    master_rate_rad_s : (m, 3) the master's angular rate at its epochs (master axes);
        None: from its attitude (:func:`master_rate_from_attitude`).
    matching : "velocity" or "velocity+attitude"; ``position``: the master's position too.
    master_errors : the master's errors as measurement noise.
    initial : the slave's start; None: :func:`slave_initial_state` from the master at the
        start of the slave record's first interval, with ``initial_std`` (its keywords).
    progress : a progress bar.
    """
    if not isinstance(config, FilterConfig):
        raise TypeError("config must be a FilterConfig")
    if matching not in MATCHING:
        raise ValueError(f"matching must be one of {MATCHING}; got {matching!r}")
    rate = _master_rate(master, master_rate_rad_s)
    t = np.asarray(slave_imu.t_s, float)
    if len(t) < 2:
        raise ValueError("the slave record needs at least two samples")
    if initial is None:
        t0 = t[0] - (t[1] - t[0]) if config.input == "increments" else t[0]
        initial = slave_initial_state(master, rate, t0, config, **initial_std)
    elif initial_std:
        raise ValueError(f"give either initial or the initial stds ({sorted(initial_std)}), not both")
    meas = master_measurements(master, rate, matching=matching, position=position, errors=master_errors,
                               t_from_s=initial.nav.t_s + 1e-9, t_to_s=t[-1])
    if len(meas) == 0:
        raise ValueError(f"no master epoch inside the slave record ([{t[0]!r}, {t[-1]!r}] s; the master "
                         f"covers [{master.t_s[0]!r}, {master.t_s[-1]!r}] s): check the time scales")
    nav = IntegratedNavigator(config, initial)
    sol = nav.run(slave_imu, master=meas, state_std=True, progress=progress)
    names = state_names(config)
    n = len(sol.t_s)
    tr = sol.transfer if sol.transfer is not None else np.zeros((n, len(TRANSFER_NAMES)))
    lever = np.asarray(config.master_lever_arm_m, float) + tr[:, 3:6]
    offset = config.master_time_offset_s + tr[:, 6]
    bias = np.zeros(3) if master_errors.attitude_bias_std_rad is None else \
        np.broadcast_to(np.asarray(master_errors.attitude_bias_std_rad, float), (3,))
    att_std = np.hypot(sol.std[:, 6:9], bias[None, :])
    derived = not (config.master_mount and matching == "velocity+attitude")
    if derived:
        noise = np.broadcast_to(np.asarray(master_errors.attitude_std_rad, float), (3,))
        mount, mount_std = _derived_mount(sol, master, offset, sol.std[:, 6:9], np.hypot(noise, bias))
    else:
        mount = np.asarray(config.master_mount_rad, float) + tr[:, 0:3]
        mount_std = _block(sol, names, "mount_heading", 3)
    return TransferAlignment(
        sol.t_s, mount, mount_std, lever, _block(sol, names, "lever_x", 3),
        offset, _block(sol, names, "time_offset", 1)[:, 0], sol.sensors[:, 0:3],
        _block(sol, names, "bg_x", 3), sol.sensors[:, 3:6], _block(sol, names, "ba_x", 3),
        sol.euler_rad, att_std, sol, config, matching, derived)
