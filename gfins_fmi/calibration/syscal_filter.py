"""The system-level calibration filter of a rotating INS (seed 001, steps S3-S5): the
36-state Kalman filter of the C core (``gf_syscal``; equations in csrc/est/gf_syscal.h) with
an optional 37th state for the accelerometer sample delay, its parameters in datasheet
units and their mapping to the IMU error model, the prior and the configuration.

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
from gfins_fmi.nav.earth import radii
from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors

__all__ = ["NAV_NAMES", "STATE_NAMES", "PARAM_NAMES", "PARAM_UNITS", "N_PARAMS",
           "CalibrationInputError", "params_to_imu_errors", "imu_errors_to_params", "Prior",
           "SyscalConfig", "SyscalFilter", "core_gravity_m_s2"]

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
    of gfins_fmi.nav.imu_errors.seed001_accel_misalignment). Raises ValueError otherwise."""
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
        RM, RN, _, _ = radii(lat_rad)
        g = as_scalar("Prior.gravity_ug", self.gravity_ug, "ug", at_least=0.0) * UG
        dh = np.hypot(self.position_m, g * np.sqrt(RM * RN) / (2.0 * core_gravity_m_s2(lat_rad, h_m)))
        nav = [np.radians(self.attitude_deg)] * 3 + [self.velocity_m_s] * 3 + \
              [self.position_m / (RM + h_m), self.position_m / ((RN + h_m) * np.cos(lat_rad)), dh]
        return np.concatenate([nav, self.params_std()])


@dataclass(frozen=True)
class SyscalConfig:
    """Filter settings (csrc/est/gf_syscal.h).

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



def core_gravity_m_s2(lat_rad: float, h_m: float) -> float:
    """Normal gravity (m/s^2) of the C core's Earth model (``gf_earth_gravity``)."""
    g = ffi.new("double *")
    check_status(lib.gf_earth_gravity(lat_rad, h_m, g), "gf_earth_gravity")
    return float(g[0])
