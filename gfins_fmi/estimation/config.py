"""Configuration of the integrated-navigation filter: :class:`FilterConfig` (datasheet
units in, the C struct out), :class:`InitialState` (the start and its 1-sigma per error
block), the names of measurement kinds, update outcomes and sensor estimates, and
:class:`FilterError`. Equations, state layout and conventions: ``csrc/gf_ins_gnss.h`` and
``docs/estimation.md``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Optional

import numpy as np

from gfins_fmi._lib import GfinsError, check_status, ffi, lib
from gfins_fmi.estimation.error_model import ins_state_names
from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.imu_errors import DEG_H, ImuNoise
from gfins_fmi.nav.strapdown import NavState

__all__ = ["FilterConfig", "InitialState", "FilterError", "MEAS_TYPES", "UPDATE_STATUS",
           "SENSOR_NAMES", "N_SENSORS", "state_names", "vector3"]

#: 1 ug in m/s^2 as the filter's noise model converts it. Not gfins_fmi.nav.imu_errors.UG
#: (1e-6 * G0 = 9.806649999999999e-06, one unit in the last place below): kept, so that
#: the filter's process noise stays bit for bit what it was
UG = 9.80665e-6
DEG = deg

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


class FilterError(GfinsError, ValueError):
    """The filter stopped at IMU sample ``index`` (bad sample, IMU gap, divergence);
    ``partial`` holds the solution of the samples before it."""

    def __init__(self, message: str, status: int, index: int, partial=None):
        super().__init__(message, status)
        self.index = index
        self.partial = partial


def state_names(config: "FilterConfig") -> tuple:
    """The error-state names of a configuration (see
    :func:`gfins_fmi.estimation.error_model.ins_state_names`)."""
    return ins_state_names(config.scale_factors, config.baro_bias, config.odometer_scale,
                           config.odometer_mount)


def vector3(name, value, unit):
    """A finite (3,) float array of a scalar (all axes) or three values; ValueError naming
    ``name`` and ``unit`` otherwise."""
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
        self.gnss_lever_arm_m = tuple(vector3("gnss_lever_arm_m", self.gnss_lever_arm_m, "m"))
        self.odometer_lever_arm_m = tuple(vector3("odometer_lever_arm_m", self.odometer_lever_arm_m, "m"))
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
        pos = vector3("position_std_m", self.position_std_m, "m")
        d = [*vector3("velocity_std_m_s", self.velocity_std_m_s, "m/s"),
             pos[1] / (e.R_M_m + nav.h_m), pos[0] / ((e.R_N_m + nav.h_m) * e.cos_lat), pos[2],
             *vector3("attitude_std_rad", self.attitude_std_rad, "rad"),
             *vector3("gyro_bias_std_rad_s", self.gyro_bias_std_rad_s if self.gyro_bias_std_rad_s
                    is not None else noise["gyro_bias_std_rad_s"], "rad/s"),
             *vector3("accel_bias_std_m_s2", self.accel_bias_std_m_s2 if self.accel_bias_std_m_s2
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
