"""System-level calibration of a rotating INS (seed 001, steps S3-S5): the 36-state Kalman
filter of the C core (``gf_syscal``; equations in csrc/gf_syscal.h) with an optional 37th
state for the accelerometer sample delay, run on a raw multi-position record.

:func:`calibrate` takes a raw record (any rate, increments or rates) of an IMU turned
through any sequence of rotations at a known site: it checks units and sampling, finds
the static intervals and the turns, aligns coarsely on the first static interval, runs
the filter (``passes`` > 1 re-runs it from the previous estimates), and reports every
parameter with its standard deviation and the ones the path cannot observe.
:func:`simulate_record` is the forward model (gf_rotation's exact increments, the
gf_imu_error model with seed 001's angles, white noise) for tests and studies;
:func:`covariance_study` tells what a path can observe before anything is recorded.

Parameters (state order 9..36; the filter works in SI, reports in datasheet units):
gyro scale (ppm), misalignment angles gamma_yz, gamma_zy, gamma_zx (arcsec), bias
(deg/h); accelerometer scale (ppm), angles alpha_xz, alpha_xy, alpha_yz, alpha_yx,
alpha_zy, alpha_zx (arcsec), bias (ug); K_a2 (ug/g^2); inner lever arms (cm); delay (ms).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (GfinsError, as_array, as_scalar, check_status, ffi, lib, ptr,
                            struct_columns, struct_doubles)
from gfins_fmi.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors, ImuNoise

__all__ = ["STATE_NAMES", "PARAM_NAMES", "PARAM_UNITS", "Prior", "SyscalConfig", "SyscalFilter",
           "Segment", "segment_record", "CalibrationReport", "calibrate", "simulate_record",
           "params_to_imu_errors", "imu_errors_to_params", "random_params", "covariance_study",
           "CalibrationInputError", "plot_report"]

NAV_NAMES = ("phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "dv_U", "dL", "dlon", "dh")
PARAM_NAMES = ("gyro_scale_x", "gyro_scale_y", "gyro_scale_z",
               "gyro_gamma_yz", "gyro_gamma_zy", "gyro_gamma_zx",
               "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
               "accel_scale_x", "accel_scale_y", "accel_scale_z",
               "accel_alpha_xz", "accel_alpha_xy", "accel_alpha_yz", "accel_alpha_yx",
               "accel_alpha_zy", "accel_alpha_zx",
               "accel_bias_x", "accel_bias_y", "accel_bias_z",
               "accel_k2_x", "accel_k2_y", "accel_k2_z",
               "lever_arm_x", "lever_arm_y", "lever_arm_z", "accel_delay")
#: the 37 states (gf_syscal.h order); the seed's filter is the first 36
STATE_NAMES = NAV_NAMES + PARAM_NAMES

_K2 = 1e-6 / G0                      # 1 ug/g^2 in (m/s^2)^-1
_BLOCK_UNITS = (("ppm", PPM), ("arcsec", ARCSEC), ("deg/h", DEG_H), ("ppm", PPM), ("arcsec", ARCSEC),
                ("ug", UG), ("ug/g^2", _K2), ("cm", 0.01), ("ms", 1e-3))
_BLOCK_SIZES = (3, 3, 3, 3, 6, 3, 3, 3, 1)
#: (unit label, SI value of one unit) of each parameter
PARAM_UNITS = tuple(u for u, k in zip(_BLOCK_UNITS, _BLOCK_SIZES) for _ in range(k))
N_PARAMS = len(PARAM_NAMES)
assert N_PARAMS == int(lib.GF_SYSCAL_N_PARAMS)


class CalibrationInputError(ValueError):
    """The record cannot be calibrated as given (units, sampling, no rest, motion too fast,
    site); the message says what was found and what to change."""


# ---- parameters <-> the IMU error model ---------------------------------------------------

def params_to_imu_errors(params_si) -> ImuErrors:
    """The :class:`ImuErrors` (datasheet units) of a parameter vector (SI, 27 or 28 values,
    PARAM_NAMES order; the delay is not part of it), through the C mapping gf_syscal_errors."""
    p = np.zeros(N_PARAMS)
    v = as_array("params_si", params_si, (None,), "SI")
    if v.size not in (N_PARAMS - 1, N_PARAMS):
        raise ValueError(f"params_si must hold {N_PARAMS - 1} or {N_PARAMS} values; got {v.size}")
    p[:v.size] = v
    e = ffi.new("gf_imu_errors *")
    st = lib.gf_syscal_errors(ptr(p, N_PARAMS), e)
    if st == lib.GF_ERR_BAD_PARAMETER:
        raise ValueError("the parameters are outside the IMU error model's range (|scale| < 0.5, "
                         "|angles| < 0.1 rad, |K2| < 1e-4 s^2/m, |lever arm| < 1 m)")
    check_status(st, "gf_syscal_errors")
    return ImuErrors(gyro_bias_deg_h=np.array(list(e.g_bias_rad_s)) / DEG_H,
                     gyro_scale_ppm=np.array(list(e.g_scale)) / PPM,
                     gyro_misalignment_arcsec=np.array(list(e.g_misalign_rad)).reshape(3, 3) / ARCSEC,
                     accel_bias_ug=np.array(list(e.a_bias_m_s2)) / UG,
                     accel_scale_ppm=np.array(list(e.a_scale)) / PPM,
                     accel_misalignment_arcsec=np.array(list(e.a_misalign_rad)).reshape(3, 3) / ARCSEC,
                     accel_k2_ug_g2=np.array(list(e.a_k2_s2_m)) / _K2,
                     lever_arm_cm=np.array(list(e.a_lever_m)) / 0.01)


def imu_errors_to_params(errors: ImuErrors) -> np.ndarray:
    """The 27 seed-001 parameters (SI) of an :class:`ImuErrors` whose misalignment
    matrices have seed 001's form (gyro: lower triangle; accelerometer: the six angles
    of gfins_fmi.imu_errors.seed001_accel_misalignment). Raises ValueError otherwise."""
    c = errors._c
    Ng = np.array(list(c.g_misalign_rad)).reshape(3, 3)
    Na = np.array(list(c.a_misalign_rad)).reshape(3, 3)
    if np.any(Ng[np.triu_indices(3, 1)] != 0.0):
        raise ValueError("the gyro misalignment has entries above the diagonal: seed 001's frame m "
                         "is defined by the gyro axes (x_m = x_g, y_m in the x_g-y_g plane), so its "
                         "three angles make a lower-triangular N_g; rotate the model to that frame")
    p = np.concatenate([list(c.g_scale), [-Ng[1, 0], Ng[2, 0], -Ng[2, 1]], list(c.g_bias_rad_s),
                        list(c.a_scale), [Na[0, 1], -Na[0, 2], -Na[1, 0], Na[1, 2], Na[2, 0], -Na[2, 1]],
                        list(c.a_bias_m_s2), list(c.a_k2_s2_m), list(c.a_lever_m)])
    return p


# ---- configuration ------------------------------------------------------------------------

@dataclass(frozen=True)
class Prior:
    """Prior 1-sigma of the states (seed 001's initial values where it gives them: gyro
    misalignment 10 arcsec, bias 0.01 deg/h, accelerometer misalignment 10 arcsec, K_a2
    20 ug/g^2, bias 1000 ug, inner lever arm 3 cm; scale factors are not given (the
    seed quotes the nominal pulse weights): 50 ppm for the gyros, 100 ppm for the
    accelerometers). The attitude prior covers a coarse alignment; the position is the
    known site.

    Gravity: the filter's height error is also its gravity error (dg = 2 g dh / R, the
    free vertical channel), and at rest a vertical specific-force error along n is the
    same for an axis pointing up and down, exactly like a scale factor: a gravity error
    dg not in the model becomes a common scale factor dg / g on the three
    accelerometers (no path of static positions separates them). ``gravity_ug`` is the
    uncertainty of the site's gravity against WGS-84 normal gravity (an anomaly of tens
    of ug is common; 0: gravity known, e.g. surveyed); it widens the height prior to
    sqrt(position_m^2 + (gravity_ug R / 2 g)^2)."""
    attitude_deg: float = 0.5
    velocity_m_s: float = 0.01
    position_m: float = 1.0
    gyro_scale_ppm: float = 50.0
    gyro_misalignment_arcsec: float = 10.0
    gyro_bias_deg_h: float = 0.01
    accel_scale_ppm: float = 100.0
    accel_misalignment_arcsec: float = 10.0
    accel_bias_ug: float = 1000.0
    accel_k2_ug_g2: float = 20.0
    lever_arm_cm: float = 3.0
    accel_delay_ms: float = 5.0
    gravity_ug: float = 0.0

    def params_std(self) -> np.ndarray:
        """Prior 1-sigma of the 28 parameters, SI."""
        vals = (self.gyro_scale_ppm, self.gyro_misalignment_arcsec, self.gyro_bias_deg_h,
                self.accel_scale_ppm, self.accel_misalignment_arcsec, self.accel_bias_ug,
                self.accel_k2_ug_g2, self.lever_arm_cm, self.accel_delay_ms)
        for f in dataclasses.fields(self):
            if f.name != "gravity_ug":
                as_scalar(f"Prior.{f.name}", getattr(self, f.name), "its unit", above=0.0)
        return np.concatenate([np.full(k, v * u[1]) for v, u, k in zip(vals, _BLOCK_UNITS, _BLOCK_SIZES)])

    def states_std(self, lat_rad: float, h_m: float) -> np.ndarray:
        """Prior 1-sigma of the 37 states, SI."""
        from gfins_fmi.trajectory import radii
        RM, RN, _, _ = radii(lat_rad)
        g = as_scalar("Prior.gravity_ug", self.gravity_ug, "ug", at_least=0.0) * UG
        dh = np.hypot(self.position_m, g * np.sqrt(RM * RN) / (2.0 * _gravity(lat_rad, h_m)))
        nav = [np.radians(self.attitude_deg)] * 3 + [self.velocity_m_s] * 3 + \
              [self.position_m / (RM + h_m), self.position_m / ((RN + h_m) * np.cos(lat_rad)), dh]
        return np.concatenate([nav, self.params_std()])


@dataclass(frozen=True)
class SyscalConfig:
    """Filter settings (csrc/gf_syscal.h).

    Parameters
    ----------
    prop_interval_s, update_interval_s : covariance propagation and zero-velocity update
        intervals (s).
    vel_std_m_s : std of the zero-velocity measurement (base sway, m/s).
    gyro_arw_deg_sqrt_h, accel_vrw_ug_sqrt_hz : the IMU's white noise (the conventions of
        :class:`gfins_fmi.ImuNoise`: angle random walk; one-sided accelerometer ASD);
        default seed 001's class (0.002 deg/sqrt(h) laser gyros, 10 ug/sqrt(Hz)). Give
        your IMU's: a filter that assumes less noise than the data hold becomes
        overconfident.
    estimate_delay : add the 37th state (accelerometer sample delay).
    prior : :class:`Prior`.
    """
    prop_interval_s: float = 0.1
    update_interval_s: float = 1.0
    vel_std_m_s: float = 1e-3
    gyro_arw_deg_sqrt_h: float = 0.002
    accel_vrw_ug_sqrt_hz: float = 10.0
    estimate_delay: bool = False
    prior: Prior = field(default_factory=Prior)

    @property
    def n_states(self) -> int:
        return 37 if self.estimate_delay else 36

    def c_config(self, lat_rad: float, lon_rad: float, h_m: float):
        c = ffi.new("gf_syscal_config *")
        lib.gf_syscal_config_default(c)
        c.n_states = self.n_states
        c.lat_rad, c.lon_rad, c.h_m = float(lat_rad), float(lon_rad), float(h_m)
        c.prop_interval_s = as_scalar("prop_interval_s", self.prop_interval_s, "s", above=0.0)
        c.update_interval_s = as_scalar("update_interval_s", self.update_interval_s, "s", above=0.0)
        c.vel_std_m_s = as_scalar("vel_std_m_s", self.vel_std_m_s, "m/s", above=0.0)
        c.gyro_arw_rad_sqrt_s = as_scalar("gyro_arw_deg_sqrt_h", self.gyro_arw_deg_sqrt_h, "deg/sqrt(h)",
                                          at_least=0.0) * np.pi / 180.0 / 60.0
        # one-sided ASD A: velocity random walk density A^2 / 2 (ImuNoise's per-sample convention)
        c.accel_vrw_m_s_sqrt_s = as_scalar("accel_vrw_ug_sqrt_hz", self.accel_vrw_ug_sqrt_hz, "ug/sqrt(Hz)",
                                           at_least=0.0) * UG / np.sqrt(2.0)
        std = self.prior.states_std(lat_rad, h_m)
        c.p0_std = list(std) + [0.0] * (37 - std.size)
        return c


_BAD_CONFIG = {1: "n_states must be 36 or 37", 2: "the site: |latitude| must be < 89 deg and the "
               "height in [-1000, 1e5] m", 3: "prop_interval_s and update_interval_s must be > 0",
               4: "vel_std_m_s must be > 0", 5: "the noise densities must be >= 0",
               6: "every prior std must be > 0", 7: "the initial parameters are outside the error "
               "model's range", 8: "the sample limits must be > 0"}


class SyscalFilter:
    """The C filter (gf_syscal) on a record: :meth:`run` feeds raw increments in chunks;
    the estimates, stds and covariance are read back at any time."""

    def __init__(self, config: SyscalConfig, lat_rad: float, h_m: float, q_mn0, *,
                 lon_rad: float = 0.0, params0=None, t0_s: float = 0.0):
        self.config = config
        q = as_array("q_mn0", q_mn0, (4,), "1")
        p0 = np.zeros(N_PARAMS) if params0 is None else as_array("params0", params0, (N_PARAMS,), "SI")
        self._s = ffi.new("gf_syscal *")
        bad = ffi.new("int *")
        st = lib.gf_syscal_init(self._s, config.c_config(lat_rad, lon_rad, h_m), ptr(q, 4),
                                ptr(p0, N_PARAMS), float(t0_s), bad)
        if st == lib.GF_ERR_BAD_PARAMETER:
            raise ValueError(f"calibration filter refused: {_BAD_CONFIG.get(int(bad[0]), 'a parameter')}")
        check_status(st, "gf_syscal_init")
        self._epochs = []

    @property
    def n_states(self) -> int:
        return int(self._s.cfg.n_states)

    @property
    def params(self) -> np.ndarray:
        """Current parameter estimates (SI, PARAM_NAMES order)."""
        return np.array(list(self._s.param))

    @property
    def t_s(self) -> float:
        return float(self._s.t_s)

    def covariance(self) -> np.ndarray:
        n = self.n_states
        P = np.empty(n * n)
        check_status(lib.gf_syscal_covariance(self._s, ptr(P, n * n), ffi.NULL), "gf_syscal_covariance")
        return P.reshape(n, n)

    def std(self) -> np.ndarray:
        return np.sqrt(np.diag(self.covariance()))

    def run(self, t_s, dtheta_rad, dv_m_s) -> int:
        """Feed increments over intervals ending at ``t_s``; returns the number of updates
        made. Raises GfinsError naming the sample where the filter stopped."""
        t = as_array("t_s", t_s, (None,), "s", finite=False)
        n = t.size
        th = as_array("dtheta_rad", dtheta_rad, (n, 3), "rad", finite=False)
        dv = as_array("dv_m_s", dv_m_s, (n, 3), "m/s", finite=False)
        dt_up = float(self._s.cfg.update_interval_s)
        cap = int(np.ceil((t[-1] - self.t_s) / dt_up)) + 4 if n else 0
        buf = np.zeros((cap, struct_doubles("gf_syscal_epoch")))
        ne, done = ffi.new("size_t *"), ffi.new("size_t *")
        st = lib.gf_syscal_run(self._s, n, ptr(t, n), ptr(th, 3 * n), ptr(dv, 3 * n),
                               ffi.cast("gf_syscal_epoch *", ptr(buf, buf.size)), cap, ne, done)
        self._epochs.append(buf[:ne[0]].copy())
        if st != lib.GF_OK:
            k = int(done[0])
            why = {int(lib.GF_ERR_NONFINITE_INPUT): "is not finite",
                   int(lib.GF_ERR_BAD_TIME): "does not follow the previous one (times must "
                   "increase, gaps at most 0.5 s)",
                   int(lib.GF_ERR_OUT_OF_RANGE): "is beyond the sample limits (|w| 50 rad/s, "
                   "|f| 1000 m/s^2)",
                   int(lib.GF_ERR_DIVERGED): "made the filter diverge (estimates out of the "
                   "model's range or covariance lost): check the units, the site and the prior"
                   }.get(int(st), "was refused")
            raise GfinsError(f"calibration filter: sample {k} (t = {t[k]:.6g} s) {why}", int(st))
        return int(ne[0])

    def epochs(self) -> dict:
        """The updates so far: ``t_s`` (m,), ``params`` (m, 28), ``std`` (m, 37),
        ``residual_m_s`` (m, 3), ``nis`` (m,)."""
        buf = np.concatenate(self._epochs) if self._epochs else \
            np.zeros((0, struct_doubles("gf_syscal_epoch")))
        c = struct_columns(buf, "gf_syscal_epoch")
        return {"t_s": np.array(c["t_s"]), "params": np.array(c["param"]), "std": np.array(c["std"]),
                "residual_m_s": np.array(c["residual_m_s"]), "nis": np.array(c["nis"])}


# ---- the record: segments, checks ------------------------------------------------------------

@dataclass(frozen=True)
class Segment:
    """A static interval or a turn of a record: samples [i0, i1), times (t0_s, t1_s];
    for a turn, the rotation's axis in IMU axes at its start and its angle (deg)."""
    kind: str
    i0: int
    i1: int
    t0_s: float
    t1_s: float
    axis: tuple = (0.0, 0.0, 0.0)
    angle_deg: float = 0.0

    @property
    def duration_s(self) -> float:
        return self.t1_s - self.t0_s

    def describe(self) -> str:
        if self.kind == "static":
            return f"static {self.duration_s:.1f} s"
        ax = np.asarray(self.axis)
        k = int(np.argmax(np.abs(ax)))
        name = f"{'+' if ax[k] > 0 else '-'}{'xyz'[k]}" if abs(ax[k]) > 0.99 else \
            "[" + ", ".join(f"{v:.2f}" for v in ax) + "]"
        return f"turn {self.angle_deg:.1f} deg about {name} ({self.duration_s:.1f} s)"


def _increments(record):
    """(t_end (n,), dt (n,), dtheta (n, 3), dv (n, 3)) of an ImuRecord of increments or rates
    (rates: trapezoidal increments between samples; the first sample starts the record)."""
    t = np.asarray(record.t_s)
    if record.kind == "increments":
        if t.size < 2:
            raise CalibrationInputError("the record has fewer than 2 samples")
        dt = np.diff(t)
        return t[1:], dt, np.asarray(record.gyro)[1:], np.asarray(record.accel)[1:]
    g, a = np.asarray(record.gyro), np.asarray(record.accel)
    dt = np.diff(t)
    return t[1:], dt, 0.5 * (g[1:] + g[:-1]) * dt[:, None], 0.5 * (a[1:] + a[:-1]) * dt[:, None]


def _composed_rotation(rotvecs: np.ndarray) -> np.ndarray:
    """The quaternion of the ordered product q(v_0) (x) q(v_1) (x) ... of the rotations of
    the increments ``rotvecs`` (m, 3), by pairwise products (log2(m) vectorised passes)."""
    a = np.linalg.norm(rotvecs, axis=1)
    k = np.where(a > 1e-12, np.sin(0.5 * a) / np.where(a > 0, a, 1.0), 0.5)
    q = np.c_[np.cos(0.5 * a), rotvecs * k[:, None]]
    while q.shape[0] > 1:
        if q.shape[0] % 2:
            q = np.r_[q, [[1.0, 0.0, 0.0, 0.0]]]
        p, r = q[0::2], q[1::2]
        q = np.c_[p[:, 0] * r[:, 0] - np.sum(p[:, 1:] * r[:, 1:], axis=1),
                  p[:, [0]] * r[:, 1:] + r[:, [0]] * p[:, 1:] + np.cross(p[:, 1:], r[:, 1:])]
    return q[0] if q.shape[0] else np.array([1.0, 0.0, 0.0, 0.0])


def segment_record(t_s, dtheta_rad, rate_threshold_deg_s: float = 0.5, smooth_s: float = 0.2,
                   min_static_s: float = 5.0, margin_s: float = 1.0) -> list:
    """Static intervals and turns of a record of increments (interval ends ``t_s``): the
    rate magnitude, averaged over ``smooth_s``, above ``rate_threshold_deg_s`` is a turn;
    a quiet stretch of at least ``min_static_s`` is a static interval (shorter ones join
    the neighbouring turn), less ``margin_s`` at each end that borders a turn (a turn
    starts and ends below any threshold: the slow ends of its ramps, left in a static
    interval, would tilt the coarse alignment's gyrocompass by degrees). Each turn's axis
    and angle come from the product of its increments' rotations (IMU axes at its
    start)."""
    t = np.asarray(t_s, float)
    th = np.asarray(dtheta_rad, float)
    dt = np.diff(np.r_[t[0] - (t[1] - t[0]) if t.size > 1 else t[0] - 1.0, t])
    rate = np.linalg.norm(th, axis=1) / dt
    k = max(1, int(round(smooth_s / np.median(dt))))
    sm = np.convolve(rate, np.ones(k) / k, mode="same")
    moving = sm > np.radians(rate_threshold_deg_s)
    # runs of equal state
    edges = np.flatnonzero(np.diff(moving.astype(int))) + 1
    starts, ends = np.r_[0, edges], np.r_[edges, t.size]
    runs = [(bool(moving[a]), a, b) for a, b in zip(starts, ends)]
    # quiet runs lose the margin next to turns; short ones join the turns around them
    m = int(round(margin_s / np.median(dt)))
    trimmed = []
    for j, (mv, a, b) in enumerate(runs):
        if not mv:
            a2 = a + (m if j > 0 else 0)
            b2 = b - (m if j + 1 < len(runs) else 0)
            if b2 <= a2:
                trimmed.append((True, a, b))
                continue
            if a2 > a:
                trimmed.append((True, a, a2))
            trimmed.append((False, a2, b2))
            if b2 < b:
                trimmed.append((True, b2, b))
        else:
            trimmed.append((mv, a, b))
    runs = trimmed
    merged = []
    for mv, a, b in runs:
        quiet_short = (not mv) and (t[b - 1] - (t[a] - dt[a])) < min_static_s
        mv = mv or quiet_short
        if merged and merged[-1][0] == mv:
            merged[-1] = (mv, merged[-1][1], b)
        else:
            merged.append((mv, a, b))
    segs = []
    for mv, a, b in merged:
        t0 = float(t[a] - dt[a])
        if not mv:
            segs.append(Segment("static", a, b, t0, float(t[b - 1])))
            continue
        q = _composed_rotation(th[a:b])
        if q[0] < 0:
            q = -q
        ang = 2 * np.arctan2(np.linalg.norm(q[1:]), q[0])
        axis = q[1:] / max(np.linalg.norm(q[1:]), 1e-300)
        segs.append(Segment("turn", a, b, t0, float(t[b - 1]), tuple(axis), float(np.degrees(ang))))
    return segs


def _gravity(lat_rad: float, h_m: float) -> float:
    g = ffi.new("double *")
    check_status(lib.gf_earth_gravity(lat_rad, h_m, g), "gf_earth_gravity")
    return float(g[0])


def _check_record(t_end, dt, dth, dv, segs, lat_rad, h_m, min_align_s, max_angle_per_sample_rad):
    """Units, sampling and rest: CalibrationInputError with what was found."""
    if not (dt > 0).all():
        k = int(np.flatnonzero(~(dt > 0))[0])
        raise CalibrationInputError(f"sample times must increase: interval {k} is {dt[k]!r} s")
    stat = [s for s in segs if s.kind == "static"]
    if not stat:
        raise CalibrationInputError("the record has no static interval (rate below the threshold for "
                                    "at least min_static_s): the filter needs rest to align and to "
                                    "observe the sensors (is the turntable running all the time?)")
    if stat[0].duration_s < min_align_s:
        raise CalibrationInputError(f"the first static interval lasts {stat[0].duration_s:.1f} s; the "
                                    f"coarse alignment needs at least {min_align_s:g} s at rest "
                                    "(seed 001 rests 10 min)")
    sel = np.concatenate([np.arange(s.i0, s.i1) for s in stat])
    f = np.linalg.norm(dv[sel] / dt[sel, None], axis=1).mean()
    g = _gravity(lat_rad, h_m)
    if abs(f / g - 1.0) > 0.05:
        hint = (" (dv looks like a specific force in m/s^2 rather than increments in m/s over "
                "each interval: build the record with kind='rates'; or the increments are in "
                "other units than m/s)" if abs(f * np.median(dt) / g - 1) < 0.05 else
                " (increments in cm/s or ft/s? accelerations in g?)" if f < 0.5 * g or f > 2 * g else
                " (a site far from where the record was made?)")
        raise CalibrationInputError(f"at rest the accelerometers read {f:.6g} m/s^2, but gravity at "
                                    f"the site is {g:.6g} m/s^2{hint}")
    w = np.linalg.norm(dth[sel] / dt[sel, None], axis=1).mean()
    W = 7.292115e-5
    if w > 30 * W:
        hint = " (are the gyro increments in degrees? np.radians)" if abs(w / (W * 180 / np.pi) - 1) < 0.5 else ""
        raise CalibrationInputError(f"at rest the gyros read {w:.3g} rad/s = {w / W:.1f} x the Earth "
                                    f"rate{hint}: the filter needs rad and a gyro that sees the Earth rate")
    worst = float(np.max(np.linalg.norm(dth, axis=1)))
    if worst > max_angle_per_sample_rad:
        k = int(np.argmax(np.linalg.norm(dth, axis=1)))
        raise CalibrationInputError(
            f"the IMU turns {np.degrees(worst):.3g} deg within one sample (sample {k}, t = "
            f"{t_end[k]:.6g} s): faster than the sample rate resolves (limit "
            f"{np.degrees(max_angle_per_sample_rad):.3g} deg per sample); record at a higher rate "
            "or turn slower")


# ---- the report ---------------------------------------------------------------------------------

@dataclass
class CalibrationReport:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    estimate, std, prior_std : (n_params,) SI, PARAM_NAMES order (27 or 28)
    ratio : std / prior_std (1: the record says nothing about the parameter)
    unobservable, weak : names with ratio > 0.9 and 0.3 < ratio <= 0.9
    errors : ImuErrors of the estimates (use it to compensate: ImuErrors.compensate)
    accel_delay_s : estimated delay (0 unless estimated)
    epochs : the updates of the last pass (SyscalFilter.epochs)
    pass_epochs : the updates of every pass (the first shows the convergence from the prior)
    segments : the static intervals and turns found
    positions : per static interval, the RMS velocity residual (m/s) of the last pass
    passes, q_mn0, notes
    """
    estimate: np.ndarray
    std: np.ndarray
    prior_std: np.ndarray
    names: tuple
    errors: ImuErrors
    accel_delay_s: float
    epochs: dict
    segments: list
    positions: list
    passes: int
    q_mn0: np.ndarray
    covariance: np.ndarray
    pass_epochs: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def ratio(self) -> np.ndarray:
        return self.std / self.prior_std

    @property
    def unobservable(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if r > 0.9]

    @property
    def weak(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if 0.3 < r <= 0.9]

    def in_units(self, values_si) -> np.ndarray:
        """Values in the datasheet units of PARAM_UNITS."""
        return np.asarray(values_si) / np.array([u[1] for u in PARAM_UNITS[:len(self.names)]])

    def table(self) -> str:
        """Markdown: parameter, estimate, 1-sigma, prior 1-sigma, std/prior, note."""
        lines = ["| parameter | unit | estimate | 1-sigma | prior 1-sigma | std/prior |",
                 "|---|---|---|---|---|---|"]
        est, sd, pr = self.in_units(self.estimate), self.in_units(self.std), self.in_units(self.prior_std)
        for k, name in enumerate(self.names):
            note = " (not observed)" if self.ratio[k] > 0.9 else " (weak)" if self.ratio[k] > 0.3 else ""
            lines.append(f"| {name} | {PARAM_UNITS[k][0]} | {est[k]:.5g} | {sd[k]:.3g} | {pr[k]:.3g} | "
                         f"{self.ratio[k]:.3g}{note} |")
        return "\n".join(lines)


def calibrate(record, lat_rad: float, h_m: float, *, lon_rad: float = 0.0,
              config: SyscalConfig | None = None, passes: int = 2, params0=None,
              rate_threshold_deg_s: float = 0.5, min_static_s: float = 5.0,
              min_align_s: float = 30.0, max_angle_per_sample_deg: float = 3.0,
              heading_rad: float | None = None) -> CalibrationReport:
    """System-level calibration of a raw multi-position record (seed 001 S4-S5).

    Parameters
    ----------
    record : gfins_fmi.io.ImuRecord
        Raw IMU samples (increments or rates, any rate) in the IMU frame m, at rest on a
        turntable or the rotating INS's own mechanism, starting at rest.
    lat_rad, h_m, lon_rad : the site (known; seed 001 S501), |lat| < 89 deg.
    config : SyscalConfig (noise densities, prior, 36 or 37 states).
    passes : runs of the filter; each pass is linearised about the previous pass's
        estimates (iterated linearisation), with the prior of ``config.prior`` centred on
        ``params0``: a pass that starts from estimates x_lin has its prior centred there
        instead, and its result is re-centred exactly (linear-Gaussian posterior:
        x += P_pp P0^-1 (params0 - x_lin)); without this the prior would be replaced by
        the previous pass's estimates, the data counted twice where the prior matters
        (weakly observed parameters: their reported sigma too small).
    params0 : prior mean of the parameters, SI, 27 or 28 (default 0: nominal IMU).
    rate_threshold_deg_s, min_static_s : segmentation (:func:`segment_record`).
    min_align_s : shortest first static interval (the coarse alignment).
    max_angle_per_sample_deg : turning faster than this per sample is refused.
    heading_rad : not used for the alignment (gyrocompassing gives it); kept for records
        whose gyros cannot see the Earth rate: then the first position's heading.

    Returns
    -------
    CalibrationReport

    Raises
    ------
    CalibrationInputError
        Units, sampling, no rest, motion too fast, site (the message says what to change).
    GfinsError
        The filter diverged (the message names the sample).
    """
    from gfins_fmi.estimation.alignment import attitude_from_gravity_and_earth_rate
    config = config or SyscalConfig()
    lat = float(lat_rad)
    if not (np.isfinite(lat) and abs(lat) < np.radians(89.0)):
        raise CalibrationInputError(f"lat_rad = {lat_rad!r}: the site's latitude must be within +-89 deg "
                                    "(in radians: np.radians)")
    h = as_scalar("h_m", h_m, "m", at_least=-1000.0, at_most=1e5)
    if not (isinstance(passes, int) and 1 <= passes <= 10):
        raise ValueError(f"passes must be an integer in 1..10; got {passes!r}")
    t_end, dt, dth, dv = _increments(record)
    segs = segment_record(t_end, dth, rate_threshold_deg_s, min_static_s=min_static_s)
    _check_record(t_end, dt, dth, dv, segs, lat, h, min_align_s, np.radians(max_angle_per_sample_deg))
    n_p = config.n_states - 9
    p = np.zeros(N_PARAMS)
    if params0 is not None:
        v = as_array("params0", params0, (None,), "SI")
        p[:v.size] = v
    mu = p.copy()                                   # the prior's mean
    prior_var = config.prior.params_std()[:n_p] ** 2
    first = next(s for s in segs if s.kind == "static")
    notes = []
    t0 = float(t_end[0] - dt[0])
    pass_epochs = []
    for k in range(passes):
        # coarse alignment on the first static interval, with the current compensation
        errs = params_to_imu_errors(p)
        sl = slice(first.i0, first.i1)
        w_c, f_c = errs.compensate_increments(dth[sl], dv[sl], dt[sl])
        q0 = attitude_from_gravity_and_earth_rate(f_c.sum(axis=0), w_c.sum(axis=0))
        filt = SyscalFilter(config, lat, h, q0, lon_rad=lon_rad, params0=p, t0_s=t0)
        filt.run(t_end, dth, dv)
        P = filt.covariance()
        # the filter's prior was N(p, P0); the prior is N(mu, P0): the parameters are
        # constant states, so moving the prior's mean by d moves the posterior mean by
        # P_pp P0^-1 d (the covariance does not change)
        d = mu[:n_p] - p[:n_p]
        p = filt.params
        p[:n_p] += P[9:, 9:] @ (d / prior_var)
        pass_epochs.append(filt.epochs())
    est = p[:n_p].copy()
    std = np.sqrt(np.diag(P))[9:]
    prior = config.prior.params_std()[:n_p]
    ep = pass_epochs[-1]
    positions = []
    for s in segs:
        if s.kind != "static":
            continue
        m = (ep["t_s"] > s.t0_s) & (ep["t_s"] <= s.t1_s)
        rms = float(np.sqrt(np.mean(ep["residual_m_s"][m] ** 2))) if m.any() else float("nan")
        positions.append({"t0_s": s.t0_s, "t1_s": s.t1_s, "rms_residual_m_s": rms})
    return CalibrationReport(est, std, prior, PARAM_NAMES[:n_p], params_to_imu_errors(est),
                             float(p[-1]) if config.estimate_delay else 0.0, ep, segs,
                             positions, passes, q0, P, pass_epochs, notes)


# ---- forward model and studies ---------------------------------------------------------------

def random_params(rng: np.random.Generator, prior: Prior | None = None, n_params: int = 27) -> np.ndarray:
    """A random error set drawn from the prior (zero mean, the prior's 1-sigma), SI."""
    prior = prior or Prior()
    return rng.normal(0.0, prior.params_std()[:n_params])


def simulate_record(schedule, params_si, lat_rad: float, h_m: float, dt_s: float = 0.01, *,
                    duration_s: float | None = None, heading_rad: float = 0.0,
                    noise: ImuNoise | None = None, seed: int = 0, accel_delay_s: float = 0.0):
    """A raw record of an IMU with the errors ``params_si`` (27 or 28 values; a 28th is
    the accelerometer delay, overriding ``accel_delay_s``) turned by ``schedule``
    (:class:`gfins_fmi.rotation.RotationSchedule`) on a static level base: exact
    increments (gf_rotation), the error model (gf_imu_error via
    :func:`params_to_imu_errors`), white noise (``noise``: its angle random walk and
    accelerometer white noise are used), seeded. Returns an ImuRecord of increments and
    the RotatingImuRecord of the truth."""
    from gfins_fmi.rotation import simulate_static
    p = as_array("params_si", params_si, (None,), "SI")
    if p.size == N_PARAMS:
        accel_delay_s = float(p[-1])
    dur = schedule.duration_s if duration_s is None else duration_s
    truth = simulate_static(schedule, dur, dt_s, lat_rad, h_m, heading_rad=heading_rad,
                            accel_delay_s=accel_delay_s)
    errs = params_to_imu_errors(p[:N_PARAMS - 1] if p.size == N_PARAMS else p)
    th, dv = errs.apply_increments(truth.dtheta_rad, truth.dv_m_s, dt_s)
    if noise is not None:
        rng = np.random.default_rng(seed)
        n = th.shape[0]
        arw = noise.gyro_arw_deg_sqrt_h * np.pi / 180.0 / 60.0
        asd = noise.accel_vrw_ug_sqrt_hz * UG
        th = th + rng.normal(0.0, arw * np.sqrt(dt_s), (n, 3))
        dv = dv + rng.normal(0.0, asd * np.sqrt(dt_s / 2.0), (n, 3))
    return truth.imu_record(th, dv, source="gfins_fmi.estimation.calibration36.simulate_record"), truth


def covariance_study(schedule, lat_rad: float, h_m: float, config: SyscalConfig | None = None,
                     dt_s: float = 0.05) -> dict:
    """What a path can observe, before anything is recorded: the filter run on the exact
    increments of ``schedule`` (no errors, no noise; the covariance of a linear filter
    does not depend on the data) gives the final 1-sigma of each parameter. Returns
    ``{"names", "std", "prior_std", "ratio"}`` (SI)."""
    from gfins_fmi.rotation import simulate_static
    config = config or SyscalConfig()
    truth = simulate_static(schedule, schedule.duration_s, dt_s, lat_rad, h_m)
    f = SyscalFilter(config, lat_rad, h_m, truth.q_mn[0], t0_s=0.0)
    f.run(truth.t_s, truth.dtheta_rad, truth.dv_m_s)
    n_p = config.n_states - 9
    std = f.std()[9:]
    prior = config.prior.params_std()[:n_p]
    return {"names": PARAM_NAMES[:n_p], "std": std, "prior_std": prior, "ratio": std / prior}


def plot_report(rep: CalibrationReport, folder, truth=None,
                names=("gyro_scale_x", "gyro_gamma_zx", "gyro_bias_z", "accel_scale_y",
                       "accel_alpha_yx", "accel_bias_z", "accel_k2_x", "lever_arm_y", "lever_arm_z"),
                tag: str = "") -> list:
    """Two figures in ``folder``: the first pass's estimates of nine parameters with
    +-1 sigma bands (and ``truth``, SI, if known), and the zero-velocity residuals of the
    last pass with the static intervals shaded. Returns their paths."""
    import pathlib

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ep = rep.pass_epochs[0]
    t = ep["t_s"] / 60.0
    fig, axes = plt.subplots(3, 3, figsize=(13, 9), constrained_layout=True)
    for ax, name in zip(axes.ravel(), names):
        k = PARAM_NAMES.index(name)
        unit, si = PARAM_UNITS[k]
        est, sd = ep["params"][:, k] / si, ep["std"][:, 9 + k] / si
        ax.fill_between(t, est - sd, est + sd, color="C0", alpha=0.3, label="estimate +- 1 sigma")
        ax.plot(t, est, "C0", lw=1)
        centre = est[-1]
        if truth is not None:
            ax.axhline(truth[k] / si, color="k", ls="--", lw=1, label="truth")
            centre = truth[k] / si
        ax.set_ylim(centre - 1.5 * sd[0], centre + 1.5 * sd[0])
        ax.set_title(f"{name} ({unit})", fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("time (min)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("system calibration, first pass from the prior: estimates with +-1 sigma")
    f1 = folder / f"syscal_convergence{tag}.png"
    fig.savefig(f1, dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(12, 4), constrained_layout=True)
    for s in rep.segments:
        if s.kind == "static":
            ax.axvspan(s.t0_s / 60, s.t1_s / 60, color="0.9")
    last = rep.epochs
    for i, c in enumerate("ENU"):
        ax.plot(last["t_s"] / 60.0, last["residual_m_s"][:, i] * 1e3, lw=0.7, label=f"v_{c}")
    ax.set(xlabel="time (min); shaded: static intervals", ylabel="velocity residual (mm/s)",
           title="zero-velocity residual at each update (last pass)")
    ax.legend(fontsize=8)
    f2 = folder / f"syscal_residuals{tag}.png"
    fig.savefig(f2, dpi=90)
    plt.close(fig)
    return [f1, f2]
