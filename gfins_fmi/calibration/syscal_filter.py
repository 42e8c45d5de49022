"""The system-level calibration filter of a rotating INS (seed 001, steps S3-S5) on the C
core (``gf_syscal``; equations in csrc/est/gf_syscal.h), in two models, its parameters
in datasheet units and their mapping to the IMU error model, the prior and the
configuration.

Models (``SyscalConfig.model``):

* ``"full"`` (the default): 39 states, 40 with the accelerometer delay (the default).
  The inner lever arms are the x and y accelerometers' positions in all three
  directions relative to the z accelerometer (``lever_rx_x`` ... ``lever_ry_z``): what a
  calibration at rest can observe of the three accelerometers' positions (a common
  translation only moves the reference point; docs/rotating_ins.md).
* ``"seed"``: seed 001's 36 states (37 with the delay): one lever arm per accelerometer
  along its own axis (``lever_arm_x/y/z``).

Parameters (the filter works in SI, reports in datasheet units): gyro scale (ppm),
misalignment angles gamma_yz, gamma_zy, gamma_zx (arcsec), bias (deg/h); accelerometer
scale (ppm), angles alpha_xz, alpha_xy, alpha_yz, alpha_yx, alpha_zy, alpha_zx (arcsec),
bias (ug); K_a2 (ug/g^2); inner lever arms (cm); delay (ms). A parameter vector in
"model order" lists the model's parameter states (state 9 on); the C filter keeps the
superset ``param[]`` of gf_syscal.h (34 values), mapped by :func:`param_index`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (GfinsError, as_array, as_scalar, check_status, ffi, lib, ptr,
                            struct_columns, struct_doubles)
from gfins_fmi.nav.earth import radii
from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors

__all__ = ["NAV_NAMES", "SEED_PARAM_NAMES", "FULL_PARAM_NAMES", "PARAM_NAMES", "PARAM_UNITS",
           "N_PARAMS", "N_C_PARAMS", "MODELS", "CalibrationInputError", "param_names",
           "param_units", "param_index", "params_to_c", "params_from_c", "params_to_imu_errors",
           "imu_errors_to_params", "Prior", "SyscalConfig", "SyscalFilter", "core_gravity_m_s2"]

NAV_NAMES = ("phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "dv_U", "dL", "dlon", "dh")
_SHARED = ("gyro_scale_x", "gyro_scale_y", "gyro_scale_z",
           "gyro_gamma_yz", "gyro_gamma_zy", "gyro_gamma_zx",
           "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
           "accel_scale_x", "accel_scale_y", "accel_scale_z",
           "accel_alpha_xz", "accel_alpha_xy", "accel_alpha_yz", "accel_alpha_yx",
           "accel_alpha_zy", "accel_alpha_zx",
           "accel_bias_x", "accel_bias_y", "accel_bias_z",
           "accel_k2_x", "accel_k2_y", "accel_k2_z")
#: seed 001's parameters (27) and the delay
SEED_PARAM_NAMES = _SHARED + ("lever_arm_x", "lever_arm_y", "lever_arm_z", "accel_delay")
#: the full model's parameters (30) and the delay: r_x and r_y, the x and y accelerometers'
#: positions relative to the z accelerometer
FULL_PARAM_NAMES = _SHARED + ("lever_rx_x", "lever_rx_y", "lever_rx_z",
                              "lever_ry_x", "lever_ry_y", "lever_ry_z", "accel_delay")
#: seed 001's names (the default of the functions that take a model)
PARAM_NAMES = SEED_PARAM_NAMES
MODELS = ("full", "seed")

_K2 = 1e-6 / G0                      # 1 ug/g^2 in (m/s^2)^-1
_UNITS = (("ppm", PPM),) * 3 + (("arcsec", ARCSEC),) * 3 + (("deg/h", DEG_H),) * 3 + \
         (("ppm", PPM),) * 3 + (("arcsec", ARCSEC),) * 6 + (("ug", UG),) * 3 + (("ug/g^2", _K2),) * 3
#: (unit label, SI value of one unit) of each seed parameter
PARAM_UNITS = _UNITS + (("cm", 0.01),) * 3 + (("ms", 1e-3),)
N_PARAMS = len(SEED_PARAM_NAMES)          # 28: seed 001's 27 and the delay
N_C_PARAMS = int(lib.GF_SYSCAL_N_PARAMS)  # 34: the C filter's param[]
_P_LEVER, _P_DELAY = int(lib.GF_SYSCAL_P_LEVER), int(lib.GF_SYSCAL_P_DELAY)
_PRIOR_FIELDS = ("gyro_scale_ppm",) * 3 + ("gyro_misalignment_arcsec",) * 3 + ("gyro_bias_deg_h",) * 3 + \
                ("accel_scale_ppm",) * 3 + ("accel_misalignment_arcsec",) * 6 + ("accel_bias_ug",) * 3 + \
                ("accel_k2_ug_g2",) * 3


class CalibrationInputError(ValueError):
    """The record cannot be calibrated as given (units, sampling, no rest, motion too fast,
    site); the message says what was found and what to change."""


def _check_model(model: str) -> str:
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}; got {model!r}")
    return model


def n_states(model: str, delay: bool) -> int:
    """The filter's state count: 36 / 37 (seed), 39 / 40 (full)."""
    return (39 if _check_model(model) == "full" else 36) + (1 if delay else 0)


def param_names(model: str = "seed", delay: bool = False) -> tuple:
    """The parameter names of a model, model order."""
    names = FULL_PARAM_NAMES if _check_model(model) == "full" else SEED_PARAM_NAMES
    return names if delay else names[:-1]


def param_units(model: str = "seed", delay: bool = False) -> tuple:
    """(unit label, SI value of one unit) of each parameter, model order."""
    lever = (("cm", 0.01),) * (6 if _check_model(model) == "full" else 3)
    return _UNITS + lever + ((("ms", 1e-3),) if delay else ())


def prior_fields(model: str = "seed", delay: bool = False) -> tuple:
    """The :class:`Prior` field that sets each parameter's prior, model order."""
    lever = ("lever_arm_cm",) * (6 if _check_model(model) == "full" else 3)
    return _PRIOR_FIELDS + lever + (("accel_delay_ms",) if delay else ())


def param_index(model: str, delay: bool) -> np.ndarray:
    """The C filter's param[] index of each parameter, model order (gf_syscal_param_index)."""
    n = n_states(model, delay)
    return np.array([lib.gf_syscal_param_index(n, k) for k in range(9, n)], dtype=int)


def params_to_c(values_si, model: str = "seed", delay: bool = False, base=None) -> np.ndarray:
    """The C param[] (34, SI) of parameters in model order, on top of ``base`` (34; default 0)."""
    idx = param_index(model, delay)
    v = as_array("params_si", values_si, (idx.size,), "SI")
    p = np.zeros(N_C_PARAMS) if base is None else np.array(base, float)
    p[idx] = v
    return p


def params_from_c(p_c, model: str = "seed", delay: bool = False) -> np.ndarray:
    """Model-order parameters of a C param[] (34)."""
    return np.asarray(p_c, float)[param_index(model, delay)]


# ---- parameters <-> the IMU error model ---------------------------------------------------

def _model_of_size(size: int) -> tuple:
    sizes = {27: ("seed", False), 28: ("seed", True), 30: ("full", False), 31: ("full", True)}
    if size not in sizes:
        raise ValueError(f"a parameter vector holds 27 or 28 (seed model) or 30 or 31 (full model) "
                         f"values; got {size}")
    return sizes[size]


def c_params_to_imu_errors(p_c) -> ImuErrors:
    """The :class:`ImuErrors` of a C param[] (34, SI), through the C mapping gf_syscal_errors."""
    p = as_array("param", p_c, (N_C_PARAMS,), "SI")
    e = ffi.new("gf_imu_errors *")
    st = lib.gf_syscal_errors(ptr(p, N_C_PARAMS), e)
    if st == lib.GF_ERR_BAD_PARAMETER:
        raise ValueError("the parameters are outside the IMU error model's range (|scale| < 0.5, "
                         "|angles| < 0.1 rad, |K2| < 1e-4 s^2/m, |lever arms| < 1 m, |delay| < 1 s)")
    check_status(st, "gf_syscal_errors")
    return ImuErrors(gyro_bias_deg_h=np.array(list(e.g_bias_rad_s)) / DEG_H,
                     gyro_scale_ppm=np.array(list(e.g_scale)) / PPM,
                     gyro_misalignment_arcsec=np.array(list(e.g_misalign_rad)).reshape(3, 3) / ARCSEC,
                     accel_bias_ug=np.array(list(e.a_bias_m_s2)) / UG,
                     accel_scale_ppm=np.array(list(e.a_scale)) / PPM,
                     accel_misalignment_arcsec=np.array(list(e.a_misalign_rad)).reshape(3, 3) / ARCSEC,
                     accel_k2_ug_g2=np.array(list(e.a_k2_s2_m)) / _K2,
                     lever_arm_cm=_lever_for_errors(np.array(list(e.a_lever_pos_m)).reshape(3, 3)),
                     accel_delay_ms=float(e.a_delay_s) * 1e3)


def _lever_for_errors(pos_m: np.ndarray):
    """(3,) along the axes when the positions have no transverse part (seed 001's form, as
    before), else (3, 3); cm."""
    off = pos_m[~np.eye(3, dtype=bool)]
    return np.diag(pos_m) / 0.01 if not np.any(off) else pos_m / 0.01


def params_to_imu_errors(params_si) -> ImuErrors:
    """The :class:`ImuErrors` (datasheet units) of a parameter vector (SI, model order: 27 or
    28 values of the seed model, 30 or 31 of the full model; the last of 28/31 is the
    accelerometer delay), through the C mapping gf_syscal_errors."""
    v = as_array("params_si", params_si, (None,), "SI")
    model, delay = _model_of_size(v.size)
    return c_params_to_imu_errors(params_to_c(v, model, delay))


#: round-off above the diagonal of a lower-triangular misalignment (rad): treated as zero
_ROUND_OFF_RAD = 1e-15


def imu_errors_to_params(errors: ImuErrors, model: str = "seed", delay: bool = False) -> np.ndarray:
    """The parameters (SI, model order) of an :class:`ImuErrors` whose gyro misalignment
    is lower triangular — the frame m of seed 001 (x_m = x_g, y_m in the x_g-y_g plane);
    entries above the diagonal within round-off (1e-15 rad) count as zero. A model in
    another frame (e.g. a laboratory tool's accelerometer frame) is first rotated with
    :func:`gfins_fmi.calibration.compensation.to_gyro_frame`. The accelerometer
    misalignment: any, first order (seed001_accel_misalignment). Lever arms: the seed
    model takes the offsets along the axes (positions across the axes raise ValueError);
    the full model the x and y accelerometers' positions relative to the z accelerometer."""
    _check_model(model)
    c = errors._c
    Ng = np.array(list(c.g_misalign_rad)).reshape(3, 3)
    Na = np.array(list(c.a_misalign_rad)).reshape(3, 3)
    if np.any(np.abs(Ng[np.triu_indices(3, 1)]) > _ROUND_OFF_RAD):
        raise ValueError("the gyro misalignment has entries above the diagonal: seed 001's frame m "
                         "is defined by the gyro axes (x_m = x_g, y_m in the x_g-y_g plane), so its "
                         "three angles make a lower-triangular N_g; rotate the model to that frame "
                         "with gfins_fmi.calibration.compensation.to_gyro_frame(errors)")
    pos = np.array(list(c.a_lever_pos_m)).reshape(3, 3)
    if model == "seed":
        if np.any(pos[~np.eye(3, dtype=bool)] != 0.0):
            raise ValueError("the accelerometers are offset across their axes: seed 001's model has "
                             "lever arms along the axes only; use model='full'")
        lever = np.diag(pos)
    else:
        lever = np.r_[pos[0] - pos[2], pos[1] - pos[2]]
    p = np.concatenate([list(c.g_scale), [-Ng[1, 0], Ng[2, 0], -Ng[2, 1]], list(c.g_bias_rad_s),
                        list(c.a_scale), [Na[0, 1], -Na[0, 2], -Na[1, 0], Na[1, 2], Na[2, 0], -Na[2, 1]],
                        list(c.a_bias_m_s2), list(c.a_k2_s2_m), lever])
    return np.r_[p, float(c.a_delay_s)] if delay else p


# ---- configuration ------------------------------------------------------------------------

@dataclass(frozen=True)
class Prior:
    """Prior 1-sigma of the states, one value per block in its datasheet unit. The
    defaults are seed 001's initial values where it gives them (gyro misalignment 10
    arcsec, bias 0.01 deg/h, accelerometer misalignment 10 arcsec, K_a2 20 ug/g^2, bias
    1000 ug, inner lever arm 3 cm; scale factors are not given (the seed quotes the
    nominal pulse weights): 50 ppm for the gyros, 100 ppm for the accelerometers); the
    grades of :mod:`gfins_fmi.calibration.grades` give wider ones. The attitude prior
    covers a coarse alignment: ``attitude_deg`` the tilt (and the heading unless
    ``heading_deg`` is given: gyrocompassing with gyro biases eps leaves eps / (W cos L),
    1.4 deg for 0.3 deg/h at 34 deg); the position is the known site. Keep the tilt prior
    near what a levelling gives (bias / g): a tilt prior of degrees beside accelerometer
    biases of mg makes the covariance of their combination (observed to 1e-12 at rest)
    the difference of numbers eleven orders larger, and the filter over-confident
    (measured: NEES 70-90 for 31 dof with 3 deg, 27-39 with 0.5 deg).

    Gravity: the filter's height error is also its gravity error (dg = 2 g dh / R, the
    free vertical channel), and at rest a vertical specific-force error along n is the
    same for an axis pointing up and down, exactly like a scale factor: a gravity error
    dg not in the model becomes a common scale factor dg / g on the three
    accelerometers (no path of static positions separates them). ``gravity_ug`` is the
    uncertainty of the site's gravity (against WGS-84 normal gravity, or against the value
    given to :func:`gfins_fmi.calibration.system.calibrate`; an unsurveyed anomaly of tens
    of ug is common; 0: gravity known); it widens the height prior to
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
    heading_deg: float | None = None

    def _check(self) -> None:
        for f in dataclasses.fields(self):
            if f.name not in ("gravity_ug", "heading_deg"):
                as_scalar(f"Prior.{f.name}", getattr(self, f.name), "its unit", above=0.0)
        if self.heading_deg is not None:
            as_scalar("Prior.heading_deg", self.heading_deg, "deg", above=0.0, at_most=30.0)

    def params_std(self, model: str = "seed", delay: bool = True) -> np.ndarray:
        """Prior 1-sigma of the parameters, SI, model order (default: seed 001's 27 and the
        delay, as before the full model)."""
        self._check()
        return np.array([getattr(self, f) * u[1] for f, u in zip(prior_fields(model, delay),
                                                                  param_units(model, delay))])

    def states_std(self, lat_rad: float, h_m: float, model: str = "seed", delay: bool = True) -> np.ndarray:
        """Prior 1-sigma of the states, SI."""
        RM, RN, _, _ = radii(lat_rad)
        g = as_scalar("Prior.gravity_ug", self.gravity_ug, "ug", at_least=0.0) * UG
        dh = np.hypot(self.position_m, g * np.sqrt(RM * RN) / (2.0 * core_gravity_m_s2(lat_rad, h_m)))
        self._check()
        head = self.attitude_deg if self.heading_deg is None else self.heading_deg
        nav = [np.radians(self.attitude_deg)] * 2 + [np.radians(head)] + [self.velocity_m_s] * 3 + \
              [self.position_m / (RM + h_m), self.position_m / ((RN + h_m) * np.cos(lat_rad)), dh]
        return np.concatenate([nav, self.params_std(model, delay)])

    def widened(self, fields, factor: float) -> "Prior":
        """This prior with the named fields multiplied by ``factor``."""
        return dataclasses.replace(self, **{f: getattr(self, f) * factor for f in set(fields)})


@dataclass(frozen=True)
class SyscalConfig:
    """Filter settings (csrc/est/gf_syscal.h).

    Parameters
    ----------
    model : "full" (default: lever arms in all directions, 39 states) or "seed" (seed 001's
        36 states).
    estimate_delay : add the state of the accelerometer sample delay (default True).
    prop_interval_s, update_interval_s : covariance propagation and zero-velocity update
        intervals (s).
    vel_std_m_s : std of the zero-velocity measurement (base sway, m/s).
    gyro_arw_deg_sqrt_h, accel_vrw_ug_sqrt_hz : the IMU's white noise (the conventions of
        :class:`gfins_fmi.ImuNoise`: angle random walk; one-sided accelerometer ASD);
        default seed 001's class (0.002 deg/sqrt(h) laser gyros, 10 ug/sqrt(Hz)). Give
        your IMU's: a filter that assumes less noise than the data hold becomes
        overconfident.
    prior : :class:`Prior`.
    gravity_anomaly_m_s2 : the site's gravity minus WGS-84 normal gravity (set by
        ``calibrate(gravity_m_s2=...)``).
    param_feedback : "pass" (default): within a pass the compensation stays at the pass's
        linearisation point and the filter carries the parameter corrections as states
        (the navigation states are fed back after every update); the next pass starts from
        the result (Gauss-Newton). "update": seed 001's S304, the parameters fed back after
        every update. With wide priors (the grades') "update" lets weakly observed
        parameters wander by thousands of ppm before the turns separate them, and the
        model's second-order terms in those excursions bias the result by several sigma on
        noisy records (docs/rotating_ins.md, "Feedback"); "pass" does not.
    """
    prop_interval_s: float = 0.1
    update_interval_s: float = 1.0
    vel_std_m_s: float = 1e-3
    gyro_arw_deg_sqrt_h: float = 0.002
    accel_vrw_ug_sqrt_hz: float = 10.0
    estimate_delay: bool = True
    prior: Prior = field(default_factory=Prior)
    model: str = "full"
    gravity_anomaly_m_s2: float = 0.0
    param_feedback: str = "pass"

    def __post_init__(self):
        _check_model(self.model)
        if self.param_feedback not in ("pass", "update"):
            raise ValueError(f"param_feedback must be 'pass' or 'update'; got {self.param_feedback!r}")

    @property
    def n_states(self) -> int:
        return n_states(self.model, self.estimate_delay)

    @property
    def names(self) -> tuple:
        return param_names(self.model, self.estimate_delay)

    @property
    def units(self) -> tuple:
        return param_units(self.model, self.estimate_delay)

    def params_std(self) -> np.ndarray:
        """The prior 1-sigma of the model's parameters, SI, model order."""
        return self.prior.params_std(self.model, self.estimate_delay)

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
        c.gravity_anomaly_m_s2 = as_scalar("gravity_anomaly_m_s2", self.gravity_anomaly_m_s2, "m/s^2",
                                           above=-0.1, below=0.1)
        c.feedback_params = 1 if self.param_feedback == "update" else 0
        std = self.prior.states_std(lat_rad, h_m, self.model, self.estimate_delay)
        c.p0_std = list(std) + [0.0] * (int(lib.GF_SYSCAL_MAX_STATES) - std.size)
        return c


_BAD_CONFIG = {1: "n_states must be 36, 37, 39 or 40", 2: "the site: |latitude| must be < 89 deg, "
               "the height in [-1000, 1e5] m and the gravity anomaly below 0.1 m/s^2",
               3: "prop_interval_s and update_interval_s must be > 0",
               4: "vel_std_m_s must be > 0", 5: "the noise densities must be >= 0",
               6: "every prior std must be > 0", 7: "the initial parameters are outside the error "
               "model's range", 8: "the sample limits must be > 0", 9: "feedback_params must be 0 or 1"}


class SyscalFilter:
    """The C filter (gf_syscal) on a record: :meth:`run` feeds raw increments in chunks;
    the estimates, stds and covariance are read back at any time. ``params0``: the
    linearisation point, SI, as a C param[] (34) or in model order."""

    def __init__(self, config: SyscalConfig, lat_rad: float, h_m: float, q_mn0, *,
                 lon_rad: float = 0.0, params0=None, t0_s: float = 0.0):
        self.config = config
        q = as_array("q_mn0", q_mn0, (4,), "1")
        if params0 is None:
            p0 = np.zeros(N_C_PARAMS)
        else:
            v = as_array("params0", params0, (None,), "SI")
            p0 = v if v.size == N_C_PARAMS else params_to_c(v, config.model, config.estimate_delay)
        self._s = ffi.new("gf_syscal *")
        bad = ffi.new("int *")
        st = lib.gf_syscal_init(self._s, config.c_config(lat_rad, lon_rad, h_m), ptr(q, 4),
                                ptr(p0, N_C_PARAMS), float(t0_s), bad)
        if st == lib.GF_ERR_BAD_PARAMETER:
            raise ValueError(f"calibration filter refused: {_BAD_CONFIG.get(int(bad[0]), 'a parameter')}")
        check_status(st, "gf_syscal_init")
        self._epochs = []

    @property
    def n_states(self) -> int:
        return int(self._s.cfg.n_states)

    @property
    def c_params(self) -> np.ndarray:
        """Current estimates, the C param[] (34, SI; gf_syscal_estimate)."""
        p = np.empty(N_C_PARAMS)
        check_status(lib.gf_syscal_estimate(self._s, ptr(p, N_C_PARAMS)), "gf_syscal_estimate")
        return p

    @property
    def params(self) -> np.ndarray:
        """Current parameter estimates (SI, model order)."""
        return params_from_c(self.c_params, self.config.model, self.config.estimate_delay)

    @property
    def t_s(self) -> float:
        return float(self._s.t_s)

    @property
    def n_refused(self) -> int:
        """Updates refused so far (their estimates would have left the model's range)."""
        return int(self._s.n_refused)

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
                   int(lib.GF_ERR_DIVERGED): "made the filter diverge (covariance lost or the "
                   "navigation left its domain): check the units, the site and the prior"
                   }.get(int(st), "was refused")
            raise GfinsError(f"calibration filter: sample {k} (t = {t[k]:.6g} s) {why}", int(st))
        return int(ne[0])

    def epochs(self) -> dict:
        """The updates so far: ``t_s`` (m,), ``params`` (m, model order), ``std`` (m, n_states),
        ``residual_m_s`` (m, 3), ``nis`` (m,), ``refused`` (m,) bool."""
        buf = np.concatenate(self._epochs) if self._epochs else \
            np.zeros((0, struct_doubles("gf_syscal_epoch")))
        c = struct_columns(buf, "gf_syscal_epoch")
        idx = param_index(self.config.model, self.config.estimate_delay)
        return {"t_s": np.array(c["t_s"]), "params": np.array(c["param"])[:, idx],
                "std": np.array(c["std"])[:, :self.n_states],
                "residual_m_s": np.array(c["residual_m_s"]), "nis": np.array(c["nis"]),
                "refused": np.array(c["refused"]) != 0.0}


def core_gravity_m_s2(lat_rad: float, h_m: float) -> float:
    """Normal gravity (m/s^2) of the C core's Earth model (``gf_earth_gravity``)."""
    g = ffi.new("double *")
    check_status(lib.gf_earth_gravity(lat_rad, h_m, g), "gf_earth_gravity")
    return float(g[0])
