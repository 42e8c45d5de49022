"""Integrated navigation: the error-state INS/GNSS filter of the C core (``gf_ins_gnss``),
EKF or UKF, with GNSS position and velocity, barometer, odometer, non-holonomic and
zero-velocity aiding, and the Rauch–Tung–Striebel smoother.

Equations, state layout and conventions: ``csrc/gf_ins_gnss.h`` and
``docs/estimation.md``. The error model's definition is
:func:`gfins_fmi.error_models.ins_error_matrices`.

A record goes to C in chunks (one call per chunk, default 2·10⁵ IMU samples) with all the
measurements that fall in it; nothing is looped per sample in Python.
"""
from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass, field, fields
from typing import Optional

import numpy as np

from gfins_fmi._lib import GfinsError, check_status, ffi, lib, ptr, status_text
from gfins_fmi.imu_errors import ImuNoise
from gfins_fmi.sins import NavState, quat_to_euler

__all__ = ["FilterConfig", "InitialState", "IntegratedNavigator", "IntegratedSolution",
           "SmoothedSolution", "FilterError", "MEAS_TYPES", "UPDATE_STATUS", "SENSOR_NAMES",
           "integrate", "state_names"]

UG = 9.80665e-6
DEG = math.pi / 180.0
DEG_H = DEG / 3600.0

#: names of the measurement types in the innovation log (gf_ins_gnss.h GF_INS_MEAS_*)
MEAS_TYPES = {int(lib.GF_INS_MEAS_GNSS_POS): "gnss_pos", int(lib.GF_INS_MEAS_GNSS_VEL): "gnss_vel",
              int(lib.GF_INS_MEAS_BARO): "baro", int(lib.GF_INS_MEAS_ODO): "odometer",
              int(lib.GF_INS_MEAS_NHC): "nhc", int(lib.GF_INS_MEAS_ZUPT): "zupt",
              int(lib.GF_INS_MEAS_ZARU): "zaru", int(lib.GF_INS_MEAS_SPEED): "speed"}
#: outcome of an update (GF_INS_ACCEPTED, GF_INS_REJECTED_*)
UPDATE_STATUS = {int(lib.GF_INS_ACCEPTED): "accepted", int(lib.GF_INS_REJECTED_GATE): "gate",
                 int(lib.GF_INS_REJECTED_SINGULAR): "singular",
                 int(lib.GF_INS_REJECTED_STALE): "stale", int(lib.GF_INS_FORCED): "forced",
                 int(lib.GF_INS_REJECTED_LOW_SPEED): "low_speed"}
#: the sensor-error estimates, in the order of every ``sensors`` array
SENSOR_NAMES = ("bg_x_rad_s", "bg_y_rad_s", "bg_z_rad_s", "ba_x_m_s2", "ba_y_m_s2", "ba_z_m_s2",
                "sg_x", "sg_y", "sg_z", "sa_x", "sa_y", "sa_z", "baro_bias_m", "odo_scale",
                "odo_pitch_rad", "odo_heading_rad")
N_SENSORS = int(lib.GF_INS_N_SENSORS)

# gf_ins_init's *bad codes -> the FilterConfig field to change
_BAD_FIELD = {1: "input", 2: "coning", 3: "filter", 4: "scale_factors/baro_bias/odometer_scale/odometer_mount",
              5: "propagation_interval_s", 6: "max_imu_gap_s",
              7: "max_rate_rad_s/max_specific_force_m_s2", 8: "ukf_alpha/ukf_beta/ukf_kappa",
              30: "gnss_lever_arm_m/odometer_lever_arm_m", 31: "gate_probability",
              32: "nhc_std_m_s/nhc_interval_s", 33: "zupt_std_m_s/zaru_std_rad_s/zupt_interval_s",
              34: "standstill_window_s/standstill_accel_std_m_s2/standstill_gyro_rad_s",
              35: "max_latency_s", 36: "speed_min_m_s", 37: "odometer_mount_rad (+ the initial correction in sensors)", 38: "subsamples"}


class FilterError(GfinsError, ValueError):
    """The filter stopped at IMU sample ``index`` (bad sample, IMU gap, divergence);
    ``partial`` holds the solution of the samples before it."""

    def __init__(self, message: str, status: int, index: int, partial=None):
        super().__init__(message, status)
        self.index = index
        self.partial = partial


def state_names(config: "FilterConfig") -> tuple:
    """The error-state names of a configuration (see ``error_models.ins_state_names``)."""
    from gfins_fmi.error_models import ins_state_names
    return ins_state_names(config.scale_factors, config.baro_bias, config.odometer_scale,
                           config.odometer_mount)


def _vec3(name, value, unit):
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite ({unit}); got {value!r}")
    return arr


@dataclass
class FilterConfig:
    """Configuration of the integrated-navigation filter (units in the names).

    Parameters
    ----------
    imu : ImuNoise
        The IMU's random errors in datasheet units: angle/velocity random walk become the
        white process noise, bias instability and correlation time the first-order
        Gauss–Markov bias model (a rate random walk adds to its driving noise).
    filter : {"ekf", "ukf"}
    input : {"increments", "rates"}
        What the IMU record holds (rad and m/s per interval, or rad/s and m/s² at the
        sample times).
    coning : two-sample coning/sculling corrections in the mechanization.
    propagation_interval_s : covariance propagation interval (0: every IMU sample);
        measurements propagate to their own instant in any case.
    scale_factors : gyro and accelerometer scale-factor states (21 states), with
        Gauss–Markov std/correlation time ``*_scale_std``/``*_scale_tau_s``
        (dimensionless; tau 0 = random constant).
    baro_bias, odometer_scale : bias state of the barometer (m) and scale-factor state of
        the odometer, with their std/tau.
    gnss_lever_arm_m, odometer_lever_arm_m : IMU -> antenna and IMU -> wheel contact point,
        body axes (right, front, up), m.
    odometer_mount_rad : (pitch, heading) of the odometer's measuring axes in the body
        frame (boresight, fixed parameters; nose-up and clockwise positive, |.| < 90 deg):
        the odometer and the non-holonomic constraints then act along those axes.
    odometer_mount, odometer_mount_std_rad, odometer_mount_tau_s : estimate the odometer
        boresight: two states (pitch, heading corrections to ``odometer_mount_rad``, rad,
        Gauss-Markov std/tau, tau 0 = random constant), observed through the odometer and
        NHC updates while the vehicle moves; the estimated correction is the output
        ``sensors`` columns ``odo_pitch_rad``, ``odo_heading_rad`` (the angles used are
        ``odometer_mount_rad`` + those).
    gate_probability : NIS gate (chi-square probability; None: no gate).
    gate_reset_count : after this many consecutive gate rejections of one measurement kind
        the next one is applied anyway (logged as "forced"), so that a filter that has
        drifted away recovers; 0: never.
    nhc, nhc_std_m_s, nhc_interval_s : non-holonomic constraint (lateral and vertical
        velocity of the odometer point = 0) for ground vehicles.
    zupt, zupt_std_m_s, zaru_std_rad_s, zupt_interval_s : zero-velocity (and, with
        zaru_std_rad_s > 0, zero-angular-rate) updates when the standstill detector
        (``standstill_*``: window, std of |f|, mean |w|) says the IMU is still. The
        detector cannot tell standstill from constant velocity on a perfectly smooth
        path; the NIS gate rejects a wrong zero-velocity update.
    ukf_alpha, ukf_beta, ukf_kappa : sigma-point parameters (seed 004: beta 2, kappa 0,
        alpha small; 0.5 keeps the points within ~2 sigma).
    max_imu_gap_s : a longer IMU interval stops the run with :class:`FilterError`.
    max_latency_s : measurements handed in after their time of validity (the FMU, a
        receiver with latency) are used up to this late (0: such measurements are stale);
        see docs/estimation.md.
    speed_min_m_s : tachometer speed updates (``speed=`` records, seed 003) are refused at
        or below this INS horizontal speed (the direction of the velocity is undefined
        there); logged as "low_speed".
    subsamples : IMU samples per navigation update in :meth:`IntegratedNavigator.run`
        (1..4; increments only): between measurement and propagation instants the
        mechanization takes groups of this many samples with the matching multi-sample
        coning and sculling corrections (``SinsConfig(subsamples=)``, docs/sins.md), the
        usual way of processing a high-rate IMU; the solution then has one row per
        navigation update (a group's end, or a sample processed alone next to a
        measurement), not one per sample. Ignored with ZUPT or ``max_latency_s > 0``
        (per-sample work) and by the FMU and the backward passes. 1: every sample.
    """

    imu: ImuNoise = field(default_factory=ImuNoise)
    filter: str = "ekf"
    input: str = "increments"
    coning: bool = True
    propagation_interval_s: float = 0.1
    scale_factors: bool = False
    gyro_scale_std: float = 1e-3
    gyro_scale_tau_s: float = 0.0
    accel_scale_std: float = 1e-3
    accel_scale_tau_s: float = 0.0
    baro_bias: bool = False
    baro_bias_std_m: float = 1.0
    baro_bias_tau_s: float = 3600.0
    odometer_scale: bool = False
    odometer_scale_std: float = 0.01
    odometer_scale_tau_s: float = 0.0
    gnss_lever_arm_m: tuple = (0.0, 0.0, 0.0)
    odometer_lever_arm_m: tuple = (0.0, 0.0, 0.0)
    odometer_mount_rad: tuple = (0.0, 0.0)
    odometer_mount: bool = False
    odometer_mount_std_rad: float = 0.035
    odometer_mount_tau_s: float = 0.0
    gate_probability: Optional[float] = 0.9999
    gate_reset_count: int = 5
    nhc: bool = False
    nhc_std_m_s: float = 0.1
    nhc_interval_s: float = 0.1
    zupt: bool = False
    zupt_std_m_s: float = 0.01
    zaru_std_rad_s: float = 0.0
    zupt_interval_s: float = 0.1
    standstill_window_s: float = 0.5
    standstill_accel_std_m_s2: float = 0.05
    standstill_gyro_rad_s: float = 0.01
    ukf_alpha: float = 0.5
    ukf_beta: float = 2.0
    ukf_kappa: float = 0.0
    max_imu_gap_s: float = 0.5
    max_latency_s: float = 0.0
    max_rate_rad_s: float = 50.0
    max_specific_force_m_s2: float = 1000.0
    speed_min_m_s: float = 0.5
    subsamples: int = 1

    def __post_init__(self):
        if not isinstance(self.imu, ImuNoise):
            raise TypeError(f"imu must be an ImuNoise (datasheet units); got {type(self.imu).__name__}")
        if self.filter not in ("ekf", "ukf"):
            raise ValueError(f"filter must be 'ekf' or 'ukf'; got {self.filter!r}")
        if self.input not in ("increments", "rates"):
            raise ValueError(f"input must be 'increments' or 'rates'; got {self.input!r}")
        if self.gate_probability is not None and not (0 < self.gate_probability < 1):
            raise ValueError(f"gate_probability must be in (0, 1) or None; got {self.gate_probability!r}")
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not (np.isfinite(v) and v >= 0):
                raise ValueError(f"{f.name} must be finite and >= 0; got {v!r}")
        self.gnss_lever_arm_m = tuple(_vec3("gnss_lever_arm_m", self.gnss_lever_arm_m, "m"))
        self.odometer_lever_arm_m = tuple(_vec3("odometer_lever_arm_m", self.odometer_lever_arm_m, "m"))
        mount = np.asarray(self.odometer_mount_rad, dtype=float)
        if mount.shape != (2,) or not np.all(np.abs(mount) < np.pi / 2):
            raise ValueError(f"odometer_mount_rad must be (pitch, heading) in rad, each inside (-pi/2, pi/2); "
                             f"got {self.odometer_mount_rad!r}")
        self.odometer_mount_rad = tuple(float(x) for x in mount)
        if isinstance(self.subsamples, bool) or not isinstance(self.subsamples, (int, np.integer)) \
                or not 1 <= self.subsamples <= 4:
            raise ValueError(f"subsamples must be an integer in 1..4; got {self.subsamples!r}")
        if self.subsamples > 1 and self.input != "increments":
            raise ValueError("subsamples > 1 needs input='increments' (the multi-sample coning "
                             "and sculling corrections are formed from increments)")
        self._c()   # the C checks, with messages naming the field

    @property
    def n_states(self) -> int:
        return 15 + 6 * bool(self.scale_factors) + bool(self.baro_bias) + bool(self.odometer_scale) \
            + 2 * bool(self.odometer_mount)

    def noise_si(self) -> dict:
        """The process noise in SI, as the C filter takes it (see :class:`ImuNoise` for
        the datasheet conventions: a one-sided accelerometer noise density ASD has the
        white-noise intensity ASD²/2)."""
        m = self.imu
        gyro_tau = m.gyro_correlation_time_s if m.gyro_bias_instability_deg_h > 0 else 0.0
        accel_tau = m.accel_correlation_time_s if m.accel_bias_instability_ug > 0 else 0.0
        gb = m.gyro_bias_instability_deg_h * DEG_H
        ab = m.accel_bias_instability_ug * UG
        # a rate random walk K adds K^2 to the bias' driving noise: express it as an
        # equivalent Gauss-Markov std for the same tau (or a random walk if tau is 0)
        K_g = m.gyro_rrw_deg_h_sqrt_h * DEG_H / 60.0
        K_a = m.accel_rrw_ug_sqrt_s * UG
        if K_g > 0:
            gyro_tau = gyro_tau or 3600.0
            gb = math.sqrt(gb * gb + K_g * K_g * gyro_tau / 2.0)
        if K_a > 0:
            accel_tau = accel_tau or 3600.0
            ab = math.sqrt(ab * ab + K_a * K_a * accel_tau / 2.0)
        return dict(gyro_arw_rad_sqrt_s=m.gyro_arw_deg_sqrt_h * DEG / 60.0,
                    accel_vrw_m_s_sqrt_s=m.accel_vrw_ug_sqrt_hz * UG / math.sqrt(2.0),
                    gyro_bias_std_rad_s=gb, gyro_bias_tau_s=gyro_tau,
                    accel_bias_std_m_s2=ab, accel_bias_tau_s=accel_tau,
                    gyro_scale_std=self.gyro_scale_std, gyro_scale_tau_s=self.gyro_scale_tau_s,
                    accel_scale_std=self.accel_scale_std, accel_scale_tau_s=self.accel_scale_tau_s,
                    baro_bias_std_m=self.baro_bias_std_m, baro_bias_tau_s=self.baro_bias_tau_s,
                    odo_scale_std=self.odometer_scale_std, odo_scale_tau_s=self.odometer_scale_tau_s,
                    odo_mount_std_rad=self.odometer_mount_std_rad,
                    odo_mount_tau_s=self.odometer_mount_tau_s)

    def _c(self):
        cfg = ffi.new("gf_ins_config *")
        check_status(lib.gf_ins_config_default(cfg), "gf_ins_config_default")
        cfg.input = lib.GF_SINS_INPUT_INCREMENTS if self.input == "increments" else lib.GF_SINS_INPUT_RATES
        cfg.coning = int(bool(self.coning))
        cfg.filter = lib.GF_INS_UKF if self.filter == "ukf" else lib.GF_INS_EKF
        cfg.scale_states = int(bool(self.scale_factors))
        cfg.baro_state = int(bool(self.baro_bias))
        cfg.odo_state = int(bool(self.odometer_scale))
        cfg.odo_mount_state = int(bool(self.odometer_mount))
        cfg.prop_interval_s = float(self.propagation_interval_s)
        cfg.max_imu_gap_s = float(self.max_imu_gap_s)
        cfg.max_rate_rad_s = float(self.max_rate_rad_s)
        cfg.max_specific_force_m_s2 = float(self.max_specific_force_m_s2)
        cfg.ukf_alpha, cfg.ukf_beta, cfg.ukf_kappa = self.ukf_alpha, self.ukf_beta, self.ukf_kappa
        for k, v in self.noise_si().items():
            setattr(cfg.noise, k, float(v))
        cfg.gnss_lever_m = list(self.gnss_lever_arm_m)
        cfg.odo_lever_m = list(self.odometer_lever_arm_m)
        cfg.odo_mount_rad = list(self.odometer_mount_rad)
        cfg.gate_prob = float(self.gate_probability or 0.0)
        if isinstance(self.gate_reset_count, bool) or not isinstance(self.gate_reset_count, (int, np.integer)) \
                or self.gate_reset_count < 0:
            raise ValueError(f"gate_reset_count must be an integer >= 0; got {self.gate_reset_count!r}")
        cfg.gate_reset_count = int(self.gate_reset_count)
        cfg.nhc, cfg.nhc_std_m_s, cfg.nhc_interval_s = int(bool(self.nhc)), self.nhc_std_m_s, self.nhc_interval_s
        cfg.zupt, cfg.zupt_std_m_s = int(bool(self.zupt)), self.zupt_std_m_s
        cfg.zaru_std_rad_s, cfg.zupt_interval_s = self.zaru_std_rad_s, self.zupt_interval_s
        cfg.still_window_s = self.standstill_window_s
        cfg.still_accel_std_m_s2 = self.standstill_accel_std_m_s2
        cfg.still_gyro_rad_s = self.standstill_gyro_rad_s
        cfg.max_latency_s = float(self.max_latency_s)
        cfg.speed_min_m_s = float(self.speed_min_m_s)
        cfg.subsamples = int(self.subsamples)
        n = ffi.new("int32_t *")
        st = lib.gf_ins_state_count(cfg, n)
        if st != lib.GF_OK:
            raise ValueError("FilterConfig rejected by the C core: check the positive "
                             "parameters (std, intervals, windows, ukf_alpha > 0)")
        return cfg


@dataclass
class InitialState:
    """The filter's start: the navigation state and the 1-sigma uncertainty of each error
    block (scalars apply to all axes). Attitude std is (east, north, up) tilt/heading in
    rad; position std (east, north, up) in m. Sensor stds default to the IMU model's
    bias instability (set them to the turn-on bias uncertainty of your IMU).
    """

    nav: NavState
    position_std_m: object = 1.0
    velocity_std_m_s: object = 0.1
    attitude_std_rad: object = (0.01, 0.01, 0.05)
    gyro_bias_std_rad_s: Optional[object] = None
    accel_bias_std_m_s2: Optional[object] = None
    gyro_scale_std: Optional[float] = None
    accel_scale_std: Optional[float] = None
    baro_bias_std_m: Optional[float] = None
    odometer_scale_std: Optional[float] = None
    odometer_mount_std_rad: Optional[object] = None   # (pitch, heading) or one for both, rad
    sensors: Optional[np.ndarray] = None      # initial estimates (SENSOR_NAMES order)

    def covariance(self, config: FilterConfig) -> np.ndarray:
        """P0 (n x n, diagonal) in the filter's states (position as dL, dlon rad, dh m)."""
        noise = config.noise_si()
        nav = self.nav
        # the radii of the C core's Earth model (gf_earth), so that the FMU, which converts
        # its position stds in C, starts from the same numbers to the last bit
        e = ffi.new("gf_earth *")
        if lib.gf_earth_update(e, float(nav.lat_rad), float(nav.h_m), ffi.NULL, 1.0) != lib.GF_OK:
            raise ValueError(f"initial.nav: latitude {nav.lat_rad!r} rad or height {nav.h_m!r} m "
                             "is outside the Earth model (|lat| < 90 deg, h > -a/2)")
        pos = _vec3("position_std_m", self.position_std_m, "m")
        d = [*_vec3("velocity_std_m_s", self.velocity_std_m_s, "m/s"),
             pos[1] / (e.R_M_m + nav.h_m), pos[0] / ((e.R_N_m + nav.h_m) * e.cos_lat), pos[2],
             *_vec3("attitude_std_rad", self.attitude_std_rad, "rad"),
             *_vec3("gyro_bias_std_rad_s", self.gyro_bias_std_rad_s if self.gyro_bias_std_rad_s
                    is not None else noise["gyro_bias_std_rad_s"], "rad/s"),
             *_vec3("accel_bias_std_m_s2", self.accel_bias_std_m_s2 if self.accel_bias_std_m_s2
                    is not None else noise["accel_bias_std_m_s2"], "m/s^2")]
        if config.scale_factors:
            d += [self.gyro_scale_std if self.gyro_scale_std is not None else config.gyro_scale_std] * 3
            d += [self.accel_scale_std if self.accel_scale_std is not None else config.accel_scale_std] * 3
        if config.baro_bias:
            d.append(self.baro_bias_std_m if self.baro_bias_std_m is not None else config.baro_bias_std_m)
        if config.odometer_scale:
            d.append(self.odometer_scale_std if self.odometer_scale_std is not None
                     else config.odometer_scale_std)
        if config.odometer_mount:
            m = self.odometer_mount_std_rad if self.odometer_mount_std_rad is not None \
                else config.odometer_mount_std_rad
            d += list(np.broadcast_to(np.asarray(m, dtype=float), (2,)))
        d = np.asarray(d, float)
        if not (np.all(np.isfinite(d)) and np.all(d > 0)):
            names = state_names(config)
            bad = [names[i] for i in np.flatnonzero(~(np.isfinite(d) & (d > 0)))]
            raise ValueError(f"initial standard deviations must be finite and > 0; not so for "
                             f"{bad} (an IMU model without bias instability needs explicit "
                             "gyro_bias_std_rad_s / accel_bias_std_m_s2)")
        return np.diag(d * d)


def _struct_dtype(cname: str, spec) -> np.dtype:
    """A numpy dtype laid out exactly as the C struct (offsets from cffi)."""
    names, formats, offsets = [], [], []
    for name, *fmt in spec:
        names.append(name)
        formats.append(tuple(fmt) if len(fmt) > 1 else fmt[0])
        offsets.append(ffi.offsetof(cname, name))
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": ffi.sizeof(cname)})


_MEAS_DTYPE = _struct_dtype("gf_ins_meas", [("type", "<i4"), ("t_s", "<f8"), ("z", "<f8", (3,)),
                                            ("std", "<f8", (3,))])
_PASS_DTYPE = _struct_dtype("gf_ins_pass", [("direction", "<i4"), ("t_s", "<f8"), ("q_bn", "<f8", (4,)),
                                            ("v_n_m_s", "<f8", (3,)), ("std9", "<f8", (9,)),
                                            ("sensors", "<f8", (N_SENSORS,)), ("n_updates", "<u8"),
                                            ("n_rejected", "<u8")])
_INNOV_DTYPE = _struct_dtype("gf_ins_innovation", [("t_s", "<f8"), ("type", "<i4"), ("status", "<i4"),
                                                   ("m", "<i4"), ("nis", "<f8"), ("r", "<f8", (3,)),
                                                   ("s_std", "<f8", (3,))])


def _gather_measurements(gnss, baro, odometer, gnss_velocity: bool, speed=None) -> np.ndarray:
    """All measurements as one array of gf_ins_meas, sorted by time (stable: position
    before velocity at the same instant)."""
    parts = []

    def block(t, type_, z, std):
        a = np.zeros(len(t), _MEAS_DTYPE)
        a["type"], a["t_s"] = type_, t
        a["z"][:, :z.shape[1]] = z
        a["std"][:, :std.shape[1]] = std
        parts.append(a)

    if gnss is not None:
        t = np.asarray(gnss.t_s, float)
        block(t, lib.GF_INS_MEAS_GNSS_POS, np.c_[gnss.lat_rad, gnss.lon_rad, gnss.h_m],
              np.asarray(gnss.pos_std_m, float))
        if gnss_velocity and getattr(gnss, "vel_enu_m_s", None) is not None:
            if getattr(gnss, "vel_std_m_s", None) is None:
                raise ValueError("the GNSS record has velocities but no vel_std_m_s: give their "
                                 "standard deviations or pass gnss_velocity=False")
            block(t, lib.GF_INS_MEAS_GNSS_VEL, np.asarray(gnss.vel_enu_m_s, float),
                  np.asarray(gnss.vel_std_m_s, float))
    if baro is not None:
        block(np.asarray(baro.t_s, float), lib.GF_INS_MEAS_BARO, np.asarray(baro.h_m, float)[:, None],
              np.asarray(baro.std_m, float)[:, None])
    if odometer is not None:
        block(np.asarray(odometer.t_s, float), lib.GF_INS_MEAS_ODO,
              np.asarray(odometer.speed_m_s, float)[:, None], np.asarray(odometer.std_m_s, float)[:, None])
    if speed is not None:
        block(np.asarray(speed.t_s, float), lib.GF_INS_MEAS_SPEED,
              np.asarray(speed.speed_m_s, float)[:, None], np.asarray(speed.std_m_s, float)[:, None])
    if not parts:
        return np.zeros(0, _MEAS_DTYPE)
    meas = np.concatenate(parts)
    bad = ~(np.isfinite(meas["t_s"]) & np.all(np.isfinite(meas["z"]), axis=1) &
            np.all(np.isfinite(meas["std"]), axis=1))
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"measurement {MEAS_TYPES[int(meas['type'][k])]} at t = {meas['t_s'][k]} s "
                         "holds NaN or Inf (value or standard deviation): remove it or mark the "
                         "epoch invalid")
    for type_, m in ((lib.GF_INS_MEAS_GNSS_POS, 3), (lib.GF_INS_MEAS_GNSS_VEL, 3),
                     (lib.GF_INS_MEAS_BARO, 1), (lib.GF_INS_MEAS_ODO, 1), (lib.GF_INS_MEAS_SPEED, 1)):
        sel = meas["type"] == type_
        if np.any(sel) and not np.all(meas["std"][sel, :m] > 0):
            k = int(np.flatnonzero(sel & ~np.all(meas["std"][:, :m] > 0, axis=1))[0])
            raise ValueError(f"{MEAS_TYPES[int(type_)]} at t = {meas['t_s'][k]} s has a standard "
                             f"deviation <= 0 ({meas['std'][k, :m].tolist()}): every std must be > 0")
    order = np.argsort(meas["t_s"], kind="stable")
    out = np.zeros(len(meas), _MEAS_DTYPE)      # concatenate drops the C padding: copy by field
    for name in _MEAS_DTYPE.names:
        out[name] = meas[name][order]
    return out


@dataclass
class IntegratedSolution:
    """Filter output, row k = the state after IMU sample k.

    Attributes
    ----------
    t_s (n,), q_bn (n, 4), v_n_m_s (n, 3) ENU, lat_rad, lon_rad, h_m (n,);
    std (n, 9): 1-sigma of velocity E, N, U (m/s), position E, N, U (m), attitude
        E, N, U (rad);
    sensors (n, 16): sensor-error estimates (``SENSOR_NAMES``);
    standstill (n,) bool: the detector's output;
    innovations: structured array, one row per update (t_s, type, status, m, nis, r[3],
        s_std[3]; ``MEAS_TYPES``, ``UPDATE_STATUS``);
    epochs: what the smoother needs (None unless the run kept it);
    config, n_states.
    """

    t_s: np.ndarray
    q_bn: np.ndarray
    v_n_m_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    std: np.ndarray
    sensors: np.ndarray
    standstill: np.ndarray
    innovations: np.ndarray
    config: FilterConfig
    epochs: Optional[dict] = None
    _euler: Optional[np.ndarray] = field(default=None, repr=False)

    def __len__(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def euler_rad(self) -> np.ndarray:
        """(heading, pitch, roll) per row, rad."""
        if self._euler is None:
            self._euler = quat_to_euler(self.q_bn) if len(self) else np.zeros((0, 3))
        return self._euler

    def rejected(self) -> np.ndarray:
        """The updates that were not applied (gate, singular, stale)."""
        st = self.innovations["status"]
        return self.innovations[(st != lib.GF_INS_ACCEPTED) & (st != lib.GF_INS_FORCED)]

    def innovations_of(self, kind: str) -> np.ndarray:
        """Rows of the innovation log of one measurement kind (``MEAS_TYPES`` values)."""
        code = {v: k for k, v in MEAS_TYPES.items()}
        if kind not in code:
            raise ValueError(f"kind must be one of {sorted(code)}; got {kind!r}")
        return self.innovations[self.innovations["type"] == code[kind]]

    def _rows(self, sl) -> "IntegratedSolution":
        return IntegratedSolution(self.t_s[sl].copy(), self.q_bn[sl].copy(), self.v_n_m_s[sl].copy(),
                                  self.lat_rad[sl].copy(), self.lon_rad[sl].copy(), self.h_m[sl].copy(),
                                  self.std[sl].copy(), self.sensors[sl].copy(), self.standstill[sl].copy(),
                                  self.innovations, self.config, self.epochs)

    def smooth(self, progress: bool = False) -> "SmoothedSolution":
        """Rauch–Tung–Striebel smoothing (backward pass over the stored epochs, one C
        call), applied to every row (corrections interpolated between epochs)."""
        if self.epochs is None:
            raise ValueError("this solution kept no epochs: run with smoother=True")
        return _smooth(self, progress)


@dataclass
class SmoothedSolution(IntegratedSolution):
    """The smoothed solution at the IMU rows (same fields; ``std`` smoothed, interpolated
    between epochs) and at the epochs themselves (``epoch_t_s``, ``epoch_std``)."""

    epoch_t_s: Optional[np.ndarray] = None
    epoch_std: Optional[np.ndarray] = None


class _Epochs:
    """Storage of the smoother's epochs: numpy arrays (or memory-mapped files beyond
    ``spill_bytes``) behind a gf_ins_epochs struct."""

    def __init__(self, n_states: int, capacity: int, spill_bytes: int, spill_dir=None):
        n = n_states
        tri = n * (n + 1) // 2
        self.n = n
        widths = {"t_s": 1, "nav": 10, "sensors": N_SENSORS, "dx": n, "P_prior": tri,
                  "P_post": tri, "Phi": n * n}
        self.bytes_per_epoch = 8 * sum(widths.values())
        total = self.bytes_per_epoch * capacity
        self._tmp = None
        self.arrays = {}
        if total > spill_bytes:
            self._tmp = tempfile.TemporaryDirectory(prefix="gfins_epochs_", dir=spill_dir)
            for k, w in widths.items():
                self.arrays[k] = np.lib.format.open_memmap(f"{self._tmp.name}/{k}.npy", "w+",
                                                           np.float64, (capacity, w))
        else:
            for k, w in widths.items():
                self.arrays[k] = np.empty((capacity, w))
        self.c = ffi.new("gf_ins_epochs *")
        self.c.capacity = capacity
        self.c.count = 0
        for k in widths:
            setattr(self.c, k, ptr(self.arrays[k], self.arrays[k].size))

    @property
    def count(self) -> int:
        return int(self.c.count)

    def trimmed(self) -> dict:
        c = self.count
        out = {k: v[:c] for k, v in self.arrays.items()}
        out["t_s"] = out["t_s"][:, 0]
        out["n_states"] = self.n
        out["bytes"] = self.bytes_per_epoch * c
        out["_keepalive"] = self
        return out


class IntegratedNavigator:
    """The integrated-navigation filter (one C state); :meth:`run` continues where it
    stopped, so a long record can be fed in pieces.

    Parameters
    ----------
    config : FilterConfig
    initial : InitialState
    """

    def __init__(self, config: FilterConfig, initial: InitialState):
        if not isinstance(config, FilterConfig):
            raise TypeError("config must be a FilterConfig")
        if not isinstance(initial, InitialState):
            raise TypeError("initial must be an InitialState")
        self.config = config
        nav = initial.nav
        q = np.ascontiguousarray(nav.q_bn, dtype=float)
        v = np.ascontiguousarray(nav.v_n_m_s, dtype=float)
        if q.shape != (4,) or v.shape != (3,):
            raise ValueError("initial.nav.q_bn must have 4 elements and initial.nav.v_n_m_s 3")
        for name in ("lat_rad", "lon_rad", "h_m", "t_s"):
            if not np.isfinite(getattr(nav, name)):
                raise ValueError(f"initial.nav.{name} = {getattr(nav, name)!r} must be finite")
        if abs(nav.lat_rad) >= np.pi / 2 * (89.0 / 90.0):
            raise ValueError(f"initial latitude {np.degrees(nav.lat_rad):.6g} deg is beyond +-89 deg: "
                             "the ENU error model is singular near the poles")
        P0 = np.ascontiguousarray(initial.covariance(config))
        sens = np.zeros(N_SENSORS) if initial.sensors is None else np.ascontiguousarray(initial.sensors, float)
        if sens.shape != (N_SENSORS,) or not np.all(np.isfinite(sens)):
            raise ValueError(f"initial.sensors must be {N_SENSORS} finite numbers ({SENSOR_NAMES})")
        self._cfg = config._c()
        self._f = ffi.new("gf_ins_filter *")
        bad = ffi.new("int32_t *")
        st = lib.gf_ins_init(self._f, self._cfg, float(nav.t_s), ptr(q, 4), ptr(v, 3), float(nav.lat_rad),
                             float(nav.lon_rad), float(nav.h_m), ptr(sens, N_SENSORS), ptr(P0, P0.size), bad)
        if st != lib.GF_OK:
            hint = f" (field {_BAD_FIELD.get(int(bad[0]), bad[0])})" if bad[0] else ""
            raise ValueError(f"gf_ins_init: {status_text(st)}{hint}")
        self.n_states = int(self._f.n_states)
        self._epochs_started = False

    @property
    def t_s(self) -> float:
        """Time of the filter's state (s)."""
        return float(self._f.t_s)

    @property
    def covariance(self) -> np.ndarray:
        """The current error covariance (n x n)."""
        n = self.n_states
        return np.frombuffer(ffi.buffer(self._f.kf.P), dtype=np.float64)[:n * n].reshape(n, n).copy()

    @property
    def counts(self) -> dict:
        """IMU samples, accepted and rejected updates so far."""
        f = self._f
        return {"imu": int(f.n_imu), "updates": int(f.n_updates), "rejected": int(f.n_rejected)}

    def error_model(self, f_b_m_s2, w_ib_b_rad_s):
        """F (n x n), G (n x n-3), q (n-3) of the C filter at its current nominal state."""
        n = self.n_states
        fb = _vec3("f_b_m_s2", f_b_m_s2, "m/s^2")
        wb = _vec3("w_ib_b_rad_s", w_ib_b_rad_s, "rad/s")
        F, G, q = np.empty((n, n)), np.empty((n, n - 3)), np.empty(n - 3)
        check_status(lib.gf_ins_error_model(self._f, ptr(fb, 3), ptr(wb, 3), ptr(F, n * n), ptr(G, n * (n - 3)),
                                             ptr(q, n - 3)),
                     "gf_ins_error_model")
        return F, G, q

    def run(self, imu, gnss=None, baro=None, odometer=None, *, speed=None, gnss_velocity: bool = True,
            smoother: bool = False, chunk: int = 200_000, progress: bool = False,
            spill_bytes: int = 1 << 30, spill_dir=None) -> IntegratedSolution:
        """Process a record.

        Parameters
        ----------
        imu : record with ``t_s`` (n,) (end of each interval), ``gyro``, ``accel`` (n, 3)
            body right-front-up, as ``config.input`` says (``gfins_fmi.io.ImuRecord``).
        gnss : record with ``t_s``, ``lat_rad``, ``lon_rad``, ``h_m``, ``pos_std_m`` (m, 3:
            E, N, U), optionally ``vel_enu_m_s``, ``vel_std_m_s`` (used unless
            ``gnss_velocity=False``). Times of validity.
        baro : record with ``t_s``, ``h_m``, ``std_m``.
        odometer : record with ``t_s``, ``speed_m_s``, ``std_m_s``.
        speed : tachometer record (horizontal speed magnitude, seed 003) with ``t_s``,
            ``speed_m_s``, ``std_m_s`` (an ``OdometerRecord`` serves).
        smoother : keep what the RTS smoother needs (at the covariance epochs: ~4 kB per
            epoch with 15 states) for :meth:`IntegratedSolution.smooth`; beyond
            ``spill_bytes`` it goes to memory-mapped files in ``spill_dir``.
        chunk : IMU samples per C call (rounded up to a multiple of ``config.subsamples``,
            so that the cut does not change the result).
        progress : a progress bar (tqdm).

        Returns
        -------
        IntegratedSolution
            One row per IMU sample, or per navigation update with ``config.subsamples``
            > 1 (``t_s`` says when).

        Raises
        ------
        FilterError
            With ``index`` (IMU sample) and ``partial`` (the solution before it).
        """
        cfg = self.config
        t, g, a = self._record(imu)
        n = t.shape[0]
        if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
            raise ValueError(f"chunk must be an integer >= 1; got {chunk!r}")
        # the C core groups samples on the grid of its sample count: chunks of a multiple
        # of the group size are processed as the whole record would be
        chunk = -(-int(chunk) // cfg.subsamples) * cfg.subsamples
        if self.reversed:
            raise ValueError("the filter is reversed in time: use run_backward(), or reverse() it again")
        meas = _gather_measurements(gnss, baro, odometer, gnss_velocity, speed)
        # capacity: one epoch per propagation and up to two per measurement
        duration = float(t[-1] - self.t_s) if n else 0.0
        if cfg.propagation_interval_s > 0:
            n_prop = int(duration / cfg.propagation_interval_s) + 2
            n_prop = min(n_prop, n + 2)
        else:
            n_prop = n + 2
        cap_epochs = n_prop + 2 * len(meas) + 4
        epochs = None
        if smoother:
            if self._epochs_started:
                raise ValueError("the smoother needs the whole record in one run() call")
            epochs = _Epochs(self.n_states, cap_epochs, spill_bytes, spill_dir)
            check_status(lib.gf_ins_epochs_begin(self._f, epochs.c), "gf_ins_epochs_begin")
            self._epochs_started = True
        internal = (int(cfg.nhc) + 2 * int(cfg.zupt)) * n_prop
        log_arr = np.zeros(len(meas) + internal + 16, _INNOV_DTYPE)
        log = ffi.new("gf_ins_log *")
        log.capacity = len(log_arr)
        log.entries = ptr(log_arr, len(log_arr), "gf_ins_innovation")
        out = {"t_s": np.empty(n), "q_bn": np.empty((n, 4)), "v_n_m_s": np.empty((n, 3)),
               "pos": np.empty((n, 3)), "std": np.empty((n, 9)), "sensors": np.empty((n, N_SENSORS)),
               "standstill": np.zeros(n, np.int8)}
        c_out = ffi.new("gf_ins_output *")
        n_done, m_done = ffi.new("size_t *"), ffi.new("size_t *")
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=n, unit="sample", unit_scale=True, desc=f"{cfg.filter.upper()} filter")
        j = row = 0
        status, bad = lib.GF_OK, n
        try:
            for lo in range(0, n, chunk):
                hi = min(n, lo + chunk)
                # the measurements valid up to the chunk's last sample
                j_hi = int(np.searchsorted(meas["t_s"], t[hi - 1] + 1e-9, side="right"))
                sub = meas[j:j_hi]
                # rows: one per sample, or fewer (subsamples > 1); written from row on
                r_hi = row + hi - lo
                c_out.t_s = ptr(out["t_s"][row:r_hi], hi - lo)
                c_out.q_bn = ptr(out["q_bn"][row:r_hi], 4 * (hi - lo))
                c_out.v_n_m_s = ptr(out["v_n_m_s"][row:r_hi], 3 * (hi - lo))
                c_out.pos = ptr(out["pos"][row:r_hi], 3 * (hi - lo))
                c_out.std = ptr(out["std"][row:r_hi], 9 * (hi - lo))
                c_out.sensors = ptr(out["sensors"][row:r_hi], N_SENSORS * (hi - lo))
                c_out.standstill = ptr(out["standstill"][row:r_hi], hi - lo, "int8_t")
                mptr = ptr(sub, len(sub), "gf_ins_meas") if len(sub) else ffi.NULL
                status = lib.gf_ins_run(self._f, hi - lo, ptr(t[lo:hi], hi - lo), ptr(g[lo:hi], 3 * (hi - lo)),
                                        ptr(a[lo:hi], 3 * (hi - lo)),
                                        len(sub), mptr, c_out, epochs.c if epochs else ffi.NULL, log,
                                        n_done, m_done)
                j += int(m_done[0])
                row += int(c_out.n_rows)
                if bar:
                    bar.update(int(n_done[0]))
                if status != lib.GF_OK:
                    bad = lo + int(n_done[0])
                    break
        finally:
            if bar:
                bar.close()
        if log.n_dropped:
            raise RuntimeError(f"innovation log overflow ({log.n_dropped} entries): please report")
        k = row
        sol = IntegratedSolution(out["t_s"][:k], out["q_bn"][:k], out["v_n_m_s"][:k],
                                 out["pos"][:k, 0].copy(), out["pos"][:k, 1].copy(), out["pos"][:k, 2].copy(),
                                 out["std"][:k], out["sensors"][:k], out["standstill"][:k].astype(bool),
                                 log_arr[:int(log.count)].copy(), cfg,
                                 epochs.trimmed() if epochs else None)
        if status != lib.GF_OK:
            hints = {
                lib.GF_ERR_BAD_TIME: (f"IMU sample {bad} at t = {t[bad]!r} s: the interval from the "
                                      f"previous sample ({self.t_s!r} s) is not in (0, "
                                      f"{cfg.max_imu_gap_s}] s (time going backwards or an IMU gap; "
                                      "raise max_imu_gap_s to bridge gaps by dead reckoning)"),
                lib.GF_ERR_NONFINITE_INPUT: f"IMU sample {bad} holds NaN or Inf",
                lib.GF_ERR_OUT_OF_RANGE: (f"IMU sample {bad} exceeds |w| <= {cfg.max_rate_rad_s} rad/s or "
                                          f"|f| <= {cfg.max_specific_force_m_s2} m/s^2 (input = "
                                          f"{cfg.input!r}: check the units)"),
                lib.GF_ERR_DIVERGED: (f"IMU sample {bad}: the filter diverged (navigation state left "
                                      "its domain or the covariance lost positive definiteness)"),
            }
            msg = hints.get(status, f"IMU sample {bad}: {status_text(status)}")
            raise FilterError(msg + "; the solution before it is in .partial", int(status), bad, sol)
        return sol


    # ---- reverse-time filtering and forward-backward processing (seed 003) ----------------

    @property
    def reversed(self) -> bool:
        """True after an odd number of :meth:`reverse` calls (time runs backward)."""
        return float(self._f.nav.earth_rate_sign) < 0

    def reverse(self) -> None:
        """Turn the filter around in time (``gf_ins_reverse``: velocity and gyro-bias
        errors change sign, the Earth rate too; see csrc/gf_ins_gnss.h). Twice = identity."""
        check_status(lib.gf_ins_reverse(self._f), "gf_ins_reverse")

    def _record(self, imu):
        cfg = self.config
        t = np.ascontiguousarray(np.asarray(imu.t_s, dtype=float))
        g = np.ascontiguousarray(np.asarray(imu.gyro, dtype=float))
        a = np.ascontiguousarray(np.asarray(imu.accel, dtype=float))
        n = t.shape[0]
        if t.ndim != 1 or g.shape != (n, 3) or a.shape != (n, 3):
            raise ValueError(f"imu.t_s must be (n,) and imu.gyro, imu.accel (n, 3); got "
                             f"{t.shape}, {g.shape}, {a.shape}")
        kind = getattr(imu, "kind", cfg.input)
        if kind != cfg.input:
            raise ValueError(f"the IMU record holds {kind!r} but the filter is configured for "
                             f"input={cfg.input!r}: convert the record (to_increments()/to_rates()) "
                             "or change FilterConfig.input")
        return t, g, a

    def _log(self, n_entries: int):
        arr = np.zeros(n_entries + 16, _INNOV_DTYPE)
        log = ffi.new("gf_ins_log *")
        log.capacity = len(arr)
        log.entries = ptr(arr, len(arr), "gf_ins_innovation")
        return arr, log

    def run_backward(self, imu, t_start_s: float, gnss=None, baro=None, odometer=None, *, speed=None,
                     gnss_velocity: bool = True) -> IntegratedSolution:
        """Walk a reversed filter (:meth:`reverse`) backward over a record stored in
        increasing time, from its last sample (the filter's time) to ``t_start_s`` (where
        the first increment interval starts). Measurements as recorded (true time). Row k
        is the state after processing sample k (true-time velocity and gyro bias); one C
        call (``gf_ins_run_backward``)."""
        if not self.reversed:
            raise ValueError("run_backward needs a reversed filter: call reverse() first")
        t, g, a = self._record(imu)
        n = len(t)
        meas = _gather_measurements(gnss, baro, odometer, gnss_velocity, speed)
        internal = (int(self.config.nhc) + 2 * int(self.config.zupt)) * \
            (int((t[-1] - t_start_s) / max(self.config.propagation_interval_s, 1e-3)) + n + 2 if n else 0)
        log_arr, log = self._log(len(meas) + internal)
        out = {"t_s": np.empty(n), "q_bn": np.empty((n, 4)), "v_n_m_s": np.empty((n, 3)),
               "pos": np.empty((n, 3)), "std": np.empty((n, 9)), "sensors": np.empty((n, N_SENSORS)),
               "standstill": np.zeros(n, np.int8)}
        c_out = ffi.new("gf_ins_output *")
        for k, w in (("t_s", 1), ("q_bn", 4), ("v_n_m_s", 3), ("pos", 3), ("std", 9), ("sensors", N_SENSORS)):
            setattr(c_out, k, ptr(out[k], w * n))
        c_out.standstill = ptr(out["standstill"], n, "int8_t")
        n_done, m_done = ffi.new("size_t *"), ffi.new("size_t *")
        mptr = ptr(meas, len(meas), "gf_ins_meas") if len(meas) else ffi.NULL
        st = lib.gf_ins_run_backward(self._f, n, ptr(t, n), ptr(g, 3 * n), ptr(a, 3 * n), float(t_start_s),
                                     len(meas), mptr, c_out, log, n_done, m_done)
        if st != lib.GF_OK:
            k = int(n_done[0])
            raise FilterError(f"backward walk stopped after {k} samples (from the last): {status_text(st)} "
                              f"(the filter's time must be the record's last sample, {t[-1] if n else None!r} s, "
                              f"and t_start_s = {t_start_s!r} before its first)", int(st), n - 1 - k)
        return IntegratedSolution(out["t_s"], out["q_bn"], out["v_n_m_s"], out["pos"][:, 0].copy(),
                                  out["pos"][:, 1].copy(), out["pos"][:, 2].copy(), out["std"], out["sensors"],
                                  out["standstill"].astype(bool), log_arr[:int(log.count)].copy(), self.config)

    def forward_backward(self, imu, passes: int, gnss=None, baro=None, odometer=None, *, speed=None,
                         gnss_velocity: bool = True):
        """Seed 003's forward-backward processing of a stored record in one C call
        (``gf_ins_forward_backward``): forward over the record, then ``passes`` times
        backward to its start and forward to its end, x and P carried across each
        reversal. The filter must be at the start of the record's first interval; it ends
        forward at the record's last sample. Returns (pass table, innovation log): the
        table holds, per pass (1 + 2 passes rows), direction (+1/-1), t_s, q_bn, v_n_m_s,
        std9 (9, as IntegratedSolution.std), sensors, n_updates, n_rejected."""
        if self.reversed:
            raise ValueError("forward_backward starts from a forward filter: reverse() it back")
        if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or not 0 <= passes <= 10000:
            raise ValueError(f"passes must be an integer in [0, 10000]; got {passes!r}")
        t, g, a = self._record(imu)
        n = len(t)
        if n < 2:
            raise ValueError(f"forward-backward processing needs a record of at least 2 IMU samples; got {n}")
        meas = _gather_measurements(gnss, baro, odometer, gnss_velocity, speed)
        np_total = 1 + 2 * int(passes)
        n_prop = int((t[-1] - self.t_s) / max(self.config.propagation_interval_s, 1e-3)) + n + 2
        internal = (int(self.config.nhc) + 2 * int(self.config.zupt)) * n_prop
        log_arr, log = self._log(np_total * (len(meas) + internal))
        table = np.zeros(np_total, _PASS_DTYPE)
        done = ffi.new("int32_t *")
        mptr = ptr(meas, len(meas), "gf_ins_meas") if len(meas) else ffi.NULL
        st = lib.gf_ins_forward_backward(self._f, n, ptr(t, n), ptr(g, 3 * n), ptr(a, 3 * n), len(meas), mptr,
                                         int(passes), ptr(table, np_total, "gf_ins_pass"), log, done)
        if log.n_dropped:
            raise RuntimeError(f"innovation log overflow ({log.n_dropped} entries): please report")
        if st != lib.GF_OK:
            raise FilterError(f"forward-backward processing stopped in pass {int(done[0])} of {np_total}: "
                              f"{status_text(st)} (the filter must start at the record's start, before "
                              f"its first sample at {t[0]!r} s)", int(st), -1)
        return table, log_arr[:int(log.count)].copy()

def _smooth(sol: IntegratedSolution, progress: bool) -> SmoothedSolution:
    ep = sol.epochs
    n = ep["n_states"]
    E = len(ep["t_s"])
    keep = ep["_keepalive"]
    c = ffi.new("gf_ins_epochs *")
    c.capacity = c.count = E
    for k in ("t_s", "nav", "sensors", "dx", "P_prior", "P_post", "Phi"):
        setattr(c, k, ptr(keep.arrays[k], keep.arrays[k].size))
    xs = np.empty((E, n))
    Ps = np.empty_like(ep["P_post"])
    check_status(lib.gf_ins_smooth(n, c, ptr(xs, xs.size), ptr(Ps, Ps.size)), "gf_ins_smooth (a prior covariance "
                 "is not positive definite)")
    # apply to the rows
    q, v = sol.q_bn.copy(), sol.v_n_m_s.copy()
    pos = np.c_[sol.lat_rad, sol.lon_rad, sol.h_m]
    sens = sol.sensors.copy()
    f = ffi.new("gf_ins_filter *")
    f.n_states = n
    cfg = sol.config
    f.idx_sg = f.idx_sa = f.idx_baro = f.idx_odo = f.idx_mount = -1
    nxt = 15
    if cfg.scale_factors:
        f.idx_sg, f.idx_sa = nxt, nxt + 3
        nxt += 6
    if cfg.baro_bias:
        f.idx_baro = nxt
        nxt += 1
    if cfg.odometer_scale:
        f.idx_odo = nxt
        nxt += 1
    if cfg.odometer_mount:
        f.idx_mount = nxt
    et = np.ascontiguousarray(ep["t_s"])
    dx = np.ascontiguousarray(ep["dx"])
    t_rows = np.ascontiguousarray(sol.t_s)
    nr = len(sol)
    check_status(lib.gf_ins_smooth_apply(f, E, ptr(et, E), ptr(xs, E * n), ptr(dx, E * n), nr,
                                         ptr(t_rows, nr), ptr(q, 4 * nr), ptr(v, 3 * nr),
                                         ptr(pos, 3 * nr), ptr(sens, N_SENSORS * nr)),
                 "gf_ins_smooth_apply")
    # smoothed std at the epochs, interpolated to the rows
    tri_idx = np.triu_indices(n)
    diag_pos = np.flatnonzero(tri_idx[0] == tri_idx[1])
    var = Ps[:, diag_pos]
    from gfins_fmi.trajectory import radii
    nav = ep["nav"]
    RM, RN, _, _ = radii(nav[:, 7])
    estd = np.empty((E, 9))
    estd[:, 0:3] = np.sqrt(var[:, 0:3])
    estd[:, 3] = np.sqrt(var[:, 4]) * (RN + nav[:, 9]) * np.cos(nav[:, 7])
    estd[:, 4] = np.sqrt(var[:, 3]) * (RM + nav[:, 9])
    estd[:, 5] = np.sqrt(var[:, 5])
    estd[:, 6:9] = np.sqrt(var[:, 6:9])
    std = np.column_stack([np.interp(sol.t_s, et, estd[:, i]) for i in range(9)])
    return SmoothedSolution(sol.t_s.copy(), q, v, pos[:, 0].copy(), pos[:, 1].copy(), pos[:, 2].copy(),
                            std, sens, sol.standstill.copy(), sol.innovations, cfg, ep,
                            epoch_t_s=et.copy(), epoch_std=estd)


def integrate(imu, gnss=None, baro=None, odometer=None, *, config: FilterConfig,
              initial: InitialState, smooth: bool = False, **kwargs):
    """One call: run the filter over a record (and smooth it with ``smooth=True``).
    Returns the :class:`IntegratedSolution` (or the :class:`SmoothedSolution`)."""
    nav = IntegratedNavigator(config, initial)
    sol = nav.run(imu, gnss, baro, odometer, smoother=smooth, **kwargs)
    return sol.smooth() if smooth else sol
