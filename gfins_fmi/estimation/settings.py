"""The integrated-navigation filter's settings, each said once.

One row per field of the C core's ``gf_ins_config`` (csrc/est/gf_ins_gnss.h): its name —
the same in C, in :class:`gfins_fmi.estimation.FilterConfig` and as the ``gfins_ins_gnss``
FMU parameter —, its unit, its bounds, its default and what it means. Everything else
derives from this table: ``FilterConfig``'s fields, defaults, docstring, conversion to C
and error messages; the FMU's parameters (fmu/models/ins_gnss/model_spec.py) and the
messages with which it refuses them (a table generated into the FMU); the tests that set
every field to a bad value. The C core names a refused field by its member
(``gf_ins_config_field``), which is looked up here (:func:`by_member`).

The process-noise rows (``noise.*``) are in SI, as the C filter takes them. In Python the
IMU's six come from ``FilterConfig.imu`` (an :class:`~gfins_fmi.nav.imu_errors.ImuNoise`
in datasheet units, converted by ``FilterConfig.noise_si``) and have no field of their own
(``python`` is ``""``); the other noise rows are ``FilterConfig`` fields.

Adding a setting: one row here, the member in ``gf_ins_config`` with its default
(``gf_ins_config_default``) and its check (``config_check``, which names it), and its use
(docs/contributing.md).

This module imports nothing from the package: the FMU build reads it by path.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

#: what each bound means, in the words of the messages (C checks the same)
BOUNDS = {
    "flag": "0 or 1",
    "enum": "one of {choices}",
    "finite": "finite",
    "nonneg": "finite and >= 0",
    "positive": "finite and > 0",
    "probability": "0 (no gate) or in (0, 1)",
    "count": "an integer >= 0",
    "half_pi": "finite and inside (-pi/2, pi/2) (each element)",
    "nonneg_each": "finite and >= 0 (each element)",
    "subsamples": "an integer in 1..4 (more than 1 only with input 'increments')",
    "mount": "finite, the pitch (the second) inside (-pi/2, pi/2)",
}

_DEG = math.pi / 180.0
_UG = 9.80665e-6
#: the FMU's default IMU (consumer-grade MEMS: gyro ARW 0.3 deg/sqrt(h), bias 10 deg/h
#: over 1 h; accelerometer noise density 100 ug/sqrt(Hz), bias 100 ug over 1 h), in SI as
#: ``FilterConfig(imu=ImuNoise(...)).noise_si()`` gives it; the C default is no noise
FMU_IMU_NOISE = {
    "gyro_arw_rad_sqrt_s": 0.3 * _DEG / 60.0,
    "accel_vrw_m_s_sqrt_s": 100 * _UG / math.sqrt(2.0),
    "gyro_bias_std_rad_s": 10.0 * _DEG / 3600.0,
    "gyro_bias_tau_s": 3600.0,
    "accel_bias_std_m_s2": 100 * _UG,
    "accel_bias_tau_s": 3600.0,
}


@dataclass(frozen=True)
class Setting:
    """One field of ``gf_ins_config``.

    Attributes
    ----------
    name : the member (``noise.`` before the process-noise members), the FilterConfig
        field (unless ``python`` differs) and the FMU parameter (without ``noise.``).
    unit : SI unit in the FMU's spelling ("m/s2"; "" dimensionless, None for flags,
        enumerations and counts).
    kind : "flag" (Python bool, C int32 0/1), "enum" (Python str, C int32), "int",
        "float", "vector" (``size`` floats; Python tuple).
    bounds : a key of :data:`BOUNDS`.
    default : FilterConfig's default = the C default (``gf_ins_config_default``), in
        Python's form (str for an enum, None for "no gate").
    meaning : one line, for docstrings, help texts and the FMU's description.
    size : elements of a vector.
    choices : an enum's Python values -> C values.
    python : the FilterConfig field when it is not ``name`` ("" = none: from ``imu``).
    fmu : an FMU parameter (False: what the FMU cannot use).
    fmu_default : the FMU's start value when it is not the C default.
    when : the flag without which the setting is not checked nor used (C skips its check).
    transfer : a setting of transfer alignment against a master INS (issue 24): a parameter
        of the transfer-alignment FMU, not of ``gfins_ins_gnss`` (which has no master inputs).
    """
    name: str
    unit: Optional[str]
    kind: str
    bounds: str
    default: object
    meaning: str
    size: int = 1
    choices: Optional[dict] = None
    python: Optional[str] = None
    fmu: bool = True
    fmu_default: object = None
    when: Optional[str] = None
    transfer: bool = False

    @property
    def member(self) -> str:
        """The member of gf_ins_config (``noise.x`` for process noise)."""
        return self.name

    @property
    def short(self) -> str:
        """The FMU parameter's name: the member without ``noise.``."""
        return self.name.rsplit(".", 1)[-1]

    @property
    def python_name(self) -> str:
        """The FilterConfig field ("" when there is none)."""
        return self.short if self.python is None else self.python

    def c_value(self, value):
        """Python value -> what the C member holds."""
        if self.kind == "flag":
            return int(bool(value))
        if self.kind == "enum":
            return int(self.choices[value])
        if self.kind == "int":
            return int(value)
        if self.kind == "vector":
            return [float(x) for x in value]
        if self.bounds == "probability" and value is None:
            return 0.0
        return float(value)

    def describe_bounds(self) -> str:
        text = BOUNDS[self.bounds]
        if self.choices:
            text = text.format(choices=", ".join(repr(k) for k in self.choices))
        return text

    @property
    def fmu_start(self):
        """The FMU's start value (C form)."""
        if self.fmu_default is not None:
            return self.fmu_default
        return self.c_value(self.default)


def _flag(name, default, meaning, **kw):
    return Setting(name, None, "flag", "flag", default, meaning, **kw)


def _float(name, unit, bounds, default, meaning, **kw):
    return Setting(name, unit, "float", bounds, default, meaning, **kw)


def _noise(name, unit, meaning, python=None, default=0.0, when=None):
    return Setting("noise." + name, unit, "float", "nonneg", default, meaning,
                   python="" if python is None else python,
                   fmu_default=FMU_IMU_NOISE.get(name), when=when)


#: every setting, in the order of ``gf_ins_config`` (and of the FMU's parameters)
SETTINGS = (
    Setting("input", None, "enum", "enum", "increments",
            "what the IMU record holds: increments (rad, m/s over each interval) or rates "
            "(rad/s, m/s2 at the sample times)", choices={"increments": 0, "rates": 1}),
    _flag("coning", True, "two-sample coning and sculling corrections in the mechanization"),
    Setting("filter", None, "enum", "enum", "ekf",
            "extended Kalman filter, or unscented (sigma points through the mechanization "
            "and the nonlinear measurement models)", choices={"ekf": 0, "ukf": 1}),
    _flag("scale_factors", False, "gyro and accelerometer scale-factor states (21 states)"),
    _flag("baro_bias", False, "barometer bias state"),
    _flag("odometer_scale", False, "odometer scale-factor state"),
    _flag("odometer_mount", False, "odometer boresight states (pitch, heading corrections "
          "to odometer_mount_rad), observed through the odometer and NHC updates"),
    _float("propagation_interval_s", "s", "nonneg", 0.1,
           "covariance propagation interval (0: every IMU sample); measurements propagate "
           "to their own instant in any case"),
    _float("max_imu_gap_s", "s", "positive", 0.5, "a longer IMU interval stops the run"),
    _float("max_rate_rad_s", "rad/s", "positive", 50.0,
           "samples with a larger angular rate are refused as absurd"),
    _float("max_specific_force_m_s2", "m/s2", "positive", 1000.0,
           "samples with a larger specific force are refused as absurd"),
    _float("ukf_alpha", "", "positive", 0.5, "UKF sigma-point spread (seed 004: small; 0.5 "
           "keeps the points within ~2 sigma)"),
    _float("ukf_beta", "", "finite", 2.0, "UKF beta (2: Gaussian)"),
    _float("ukf_kappa", "", "finite", 0.0, "UKF kappa (number of states + kappa > 0)"),
    _noise("gyro_arw_rad_sqrt_s", None, "gyro white noise (angle random walk), rad/sqrt(s)"),
    _noise("accel_vrw_m_s_sqrt_s", None, "accelerometer white noise (velocity random walk), "
           "m/s/sqrt(s)"),
    _noise("gyro_bias_std_rad_s", "rad/s", "gyro bias, first-order Gauss-Markov: "
           "steady-state std"),
    _noise("gyro_bias_tau_s", "s", "gyro bias correlation time (0: random constant)"),
    _noise("accel_bias_std_m_s2", "m/s2", "accelerometer bias, Gauss-Markov steady-state std"),
    _noise("accel_bias_tau_s", "s", "accelerometer bias correlation time (0: random constant)"),
    _noise("gyro_scale_std", "", "gyro scale-factor error, Gauss-Markov std",
           python="gyro_scale_std", default=1e-3),
    _noise("gyro_scale_tau_s", "s", "gyro scale-factor correlation time (0: random constant)",
           python="gyro_scale_tau_s"),
    _noise("accel_scale_std", "", "accelerometer scale-factor error, Gauss-Markov std",
           python="accel_scale_std", default=1e-3),
    _noise("accel_scale_tau_s", "s", "accelerometer scale-factor correlation time",
           python="accel_scale_tau_s"),
    _noise("baro_bias_std_m", "m", "barometer bias, Gauss-Markov std",
           python="baro_bias_std_m", default=1.0),
    _noise("baro_bias_tau_s", "s", "barometer bias correlation time",
           python="baro_bias_tau_s", default=3600.0),
    _noise("odometer_scale_std", "", "odometer scale-factor error, Gauss-Markov std",
           python="odometer_scale_std", default=0.01),
    _noise("odometer_scale_tau_s", "s", "odometer scale-factor correlation time",
           python="odometer_scale_tau_s"),
    _noise("odometer_mount_std_rad", "rad", "odometer boresight (pitch, heading), "
           "Gauss-Markov std", python="odometer_mount_std_rad", default=0.035),
    _noise("odometer_mount_tau_s", "s", "odometer boresight correlation time (0: random "
           "constant)", python="odometer_mount_tau_s"),
    Setting("noise.flexure_std_rad", "rad", "float", "positive", 1e-3,
            "structural flexure between master and slave (second-order Gauss-Markov per "
            "axis, added to the mounting angles): stationary std of each angle",
            python="flexure_std_rad", when="flexure", transfer=True),
    Setting("noise.flexure_tau_s", "s", "float", "positive", 1.0,
            "flexure correlation time: b = 2.146 / tau in f'' + 2 b f' + b^2 f = w",
            python="flexure_tau_s", when="flexure", transfer=True),
    Setting("gnss_lever_arm_m", "m", "vector", "finite", (0.0, 0.0, 0.0),
            "IMU -> GNSS antenna phase centre, body axes right, front, up", size=3),
    Setting("odometer_lever_arm_m", "m", "vector", "finite", (0.0, 0.0, 0.0),
            "IMU -> odometer wheel contact point, body axes right, front, up", size=3),
    Setting("gnss_position_std_floor_m", "m", "vector", "nonneg_each", (0.0, 0.0, 0.0),
            "GNSS position stds (east, north, up) below this are raised to it: receivers "
            "report RTK stds of millimetres that multipath and a moving antenna do not keep; "
            "0: as reported", size=3),
    _float("gate_probability", None, "probability", 0.9999,
           "innovation gate: a measurement whose NIS exceeds the chi-square quantile of "
           "this probability is rejected (Python None, C and FMU 0: no gate)"),
    Setting("gate_reset_count", None, "int", "count", 5,
            "after this many consecutive gate rejections of one measurement kind the next "
            "one is applied (logged as forced), so that a filter that drifted away "
            "recovers; 0: never"),
    _flag("nhc", False, "non-holonomic constraint updates (lateral and vertical velocity of "
          "the odometer point 0), for ground vehicles"),
    _float("nhc_std_m_s", "m/s", "positive", 0.1, "NHC measurement std", when="nhc"),
    _float("nhc_interval_s", "s", "nonneg", 0.1, "at most one NHC update per interval",
           when="nhc"),
    _flag("zupt", False, "zero-velocity updates when the standstill detector says the IMU "
          "is still"),
    _float("zupt_std_m_s", "m/s", "positive", 0.01, "ZUPT measurement std", when="zupt"),
    _float("zaru_std_rad_s", "rad/s", "nonneg", 0.0,
           "> 0: also zero-angular-rate updates at standstill, with this std", when="zupt"),
    _float("zupt_interval_s", "s", "nonneg", 0.1, "at most one ZUPT (and ZARU) per interval",
           when="zupt"),
    _float("standstill_window_s", "s", "positive", 0.5, "standstill detector: averaging time"),
    _float("standstill_accel_std_m_s2", "m/s2", "positive", 0.05,
           "standstill detector: the std of |f| over the window must be below this"),
    _float("standstill_gyro_rad_s", "rad/s", "positive", 0.01,
           "standstill detector: the mean |w| over the window must be below this"),
    _float("max_latency_s", "s", "nonneg", 0.0,
           "measurements handed in after their time of validity (a receiver's latency) are "
           "used up to this late (from the nominal state kept at their time, the last 128 "
           "IMU samples); 0: such measurements are stale"),
    _float("speed_min_m_s", "m/s", "nonneg", 0.5,
           "tachometer speed updates (seed 003) are refused at or below this INS horizontal "
           "speed (the direction of the velocity is undefined there)", fmu=False),
    Setting("odometer_mount_rad", "rad", "vector", "half_pi", (0.0, 0.0),
            "odometer boresight: pitch (nose-up +) and heading (clockwise +) of its "
            "measuring axes in the body frame; the odometer and NHC act along those axes "
            "(with odometer_mount the filter estimates a correction)", size=2),
    Setting("subsamples", None, "int", "subsamples", 1,
            "IMU samples per navigation update in the batch run (increments only): groups "
            "of this many samples with the matching multi-sample coning and sculling between "
            "measurement and propagation instants, one output row per update", fmu=False),
    _flag("master_mount", False, "transfer alignment: mounting-error states (heading, pitch, "
          "roll of the slave's axes in the master's; random constants)", transfer=True),
    _flag("master_lever", False, "transfer alignment: lever-arm error states (the slave IMU "
          "from the master IMU, master axes; random constants)", transfer=True),
    _flag("master_time_offset", False, "transfer alignment: time-offset error state (slave "
          "stamp - master stamp of one instant; a random constant)", transfer=True),
    _flag("flexure", False, "transfer alignment: structural flexure states (3 angles and "
          "their rates, second-order Gauss-Markov)", transfer=True),
    Setting("master_mount_rad", "rad", "vector", "mount", (0.0, 0.0, 0.0),
            "nominal mounting: heading, pitch, roll of the slave's axes in the master's "
            "(gf_sins.h's Euler convention); with master_mount the filter estimates a "
            "correction", size=3, transfer=True),
    Setting("master_lever_arm_m", "m", "vector", "finite", (0.0, 0.0, 0.0),
            "nominal lever arm: the slave IMU from the master IMU, master axes right, front, "
            "up", size=3, transfer=True),
    _float("master_time_offset_s", "s", "finite", 0.0,
           "nominal time offset: slave stamp - master stamp of one instant (the master's "
           "outputs stamped t describe the slave's t + offset)", transfer=True),
)

_BY_MEMBER = {s.member: s for s in SETTINGS}


def by_member(member: str) -> Setting:
    """The row of a gf_ins_config member (as ``gf_ins_config_field`` names it)."""
    return _BY_MEMBER[member]


def python_settings() -> tuple:
    """The rows that are FilterConfig fields."""
    return tuple(s for s in SETTINGS if s.python_name)


def fmu_settings(transfer: bool = False) -> tuple:
    """The rows that are FMU parameters: of ``gfins_ins_gnss``, or with ``transfer`` of the
    transfer-alignment FMU (every FMU row, the transfer rows included)."""
    return tuple(s for s in SETTINGS if s.fmu and (transfer or not s.transfer))
