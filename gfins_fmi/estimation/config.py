"""Configuration of the integrated-navigation filter: :class:`FilterConfig` (datasheet
units in, the C struct out), :class:`InitialState` (the start and its 1-sigma per error
block), the names of measurement kinds, update outcomes and sensor estimates, and
:class:`FilterError`. Equations, state layout and conventions: ``csrc/est/gf_ins_gnss.h`` and
``docs/estimation.md``.
"""
from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field, make_dataclass
from typing import Optional

import numpy as np

from gfins_fmi._lib import GfinsError, check_status, ffi, lib, ptr, status_text
from gfins_fmi.estimation.error_model import ins_state_names
from gfins_fmi.estimation.settings import SETTINGS, Setting, by_member, python_settings
from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.imu_errors import DEG_H, ImuNoise
from gfins_fmi.nav.strapdown import NavState

__all__ = ["FilterConfig", "InitialState", "FilterError", "MEAS_TYPES", "UPDATE_STATUS",
           "SENSOR_NAMES", "N_SENSORS", "TRANSFER_NAMES", "N_TRANSFER", "state_names", "vector3"]

#: 1 ug in m/s^2 as the filter's noise model converts it. Not gfins_fmi.nav.imu_errors.UG
#: (1e-6 * G0 = 9.806649999999999e-06, one unit in the last place below): kept, so that
#: the filter's process noise stays bit for bit what it was
UG = 9.80665e-6
DEG = deg

#: names of the measurement types in the innovation log (gf_ins_gnss.h GF_INS_MEAS_*)
MEAS_TYPES = {int(lib.GF_INS_MEAS_GNSS_POS): "gnss_pos", int(lib.GF_INS_MEAS_GNSS_VEL): "gnss_vel",
              int(lib.GF_INS_MEAS_BARO): "baro", int(lib.GF_INS_MEAS_ODO): "odometer",
              int(lib.GF_INS_MEAS_NHC): "nhc", int(lib.GF_INS_MEAS_ZUPT): "zupt",
              int(lib.GF_INS_MEAS_ZARU): "zaru", int(lib.GF_INS_MEAS_SPEED): "speed",
              int(lib.GF_INS_MEAS_MASTER_VEL): "master_vel", int(lib.GF_INS_MEAS_MASTER_ATT): "master_att",
              int(lib.GF_INS_MEAS_MASTER_POS): "master_pos"}
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
#: the transfer-alignment estimates, in the order of every ``transfer`` array: corrections
#: to the configured mounting (heading, pitch, roll), lever arm (master axes) and time
#: offset, then the flexure angles and rates (gf_ins_gnss.h GF_INS_N_TRANSFER)
TRANSFER_NAMES = ("mount_heading_rad", "mount_pitch_rad", "mount_roll_rad", "lever_x_m", "lever_y_m",
                  "lever_z_m", "time_offset_s", "flex_heading_rad", "flex_pitch_rad", "flex_roll_rad",
                  "flex_heading_rate_rad_s", "flex_pitch_rate_rad_s", "flex_roll_rate_rad_s")
N_TRANSFER = int(lib.GF_INS_N_TRANSFER)


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
                           config.odometer_mount, master_mount=config.master_mount,
                           master_lever=config.master_lever,
                           master_time_offset=config.master_time_offset, flexure=config.flexure)


def vector3(name, value, unit):
    """A finite (3,) float array of a scalar (all axes) or three values; ValueError naming
    ``name`` and ``unit`` otherwise."""
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite ({unit}); got {value!r}")
    return arr


def _show(value) -> str:
    """A value as a message shows it: plain numbers (no numpy reprs), lists for arrays."""
    if isinstance(value, (np.ndarray, list, tuple)):
        return "[" + ", ".join(_show(v) for v in np.asarray(value, dtype=object).ravel()) + "]"
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return repr(value)


def _refuse(st: Setting, value, why: str = "") -> ValueError:
    unit = f" {st.unit}" if st.unit else ""
    bounds = "None (no gate) or in (0, 1)" if st.bounds == "probability" else st.describe_bounds()
    return ValueError(f"FilterConfig.{st.python_name} = {_show(value)}{unit}: must be {bounds}{why}")


def _checked(st: Setting, value):
    """A FilterConfig field's value in its Python form, checked against the row's kind and
    bounds (the C core checks the same again, and names what it refuses)."""
    if st.kind == "flag":
        if not (isinstance(value, (bool, np.bool_)) or (isinstance(value, (int, np.integer))
                                                       and value in (0, 1))):
            raise _refuse(st, value, " (True or False)")
        return bool(value)
    if st.kind == "enum":
        if not isinstance(value, str) or value not in st.choices:
            raise _refuse(st, value)
        return value
    if st.kind == "int":
        lowest = 1 if st.bounds == "subsamples" else 0
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
                or value < lowest or (st.bounds == "subsamples" and value > 4):
            raise _refuse(st, value)
        return int(value)
    if st.kind == "vector":
        arr = np.asarray(value, dtype=float) if not isinstance(value, str) else np.array(np.nan)
        if arr.shape != (st.size,) and not (st.size == 3 and arr.ndim == 0):
            raise _refuse(st, value, f" ({st.size} values)")
        arr = np.broadcast_to(arr, (st.size,))
        ok = np.isfinite(arr) & {"half_pi": np.abs(arr) < np.pi / 2, "nonneg_each": arr >= 0,
                                 "mount": (np.arange(st.size) != 1) | (np.abs(arr) < np.pi / 2)}.get(
            st.bounds, True)
        if not np.all(ok):
            raise _refuse(st, value)
        return tuple(float(x) for x in arr)
    # a float
    if st.bounds == "probability" and value is None:
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise _refuse(st, value) from None
    ok = {"finite": math.isfinite(x), "nonneg": math.isfinite(x) and x >= 0,
          "positive": math.isfinite(x) and x > 0,
          "probability": 0 < x < 1}[st.bounds]
    if not ok:
        raise _refuse(st, value)
    return value


class _FilterConfigMethods:
    """What FilterConfig does with its fields (the fields come from the settings table)."""

    def __post_init__(self):
        if not isinstance(self.imu, ImuNoise):
            raise TypeError(f"FilterConfig.imu must be an ImuNoise (datasheet units); got "
                            f"{type(self.imu).__name__}")
        for st in python_settings():
            setattr(self, st.python_name, _checked(st, getattr(self, st.python_name)))
        self._c()   # the C checks, which name what they refuse

    @property
    def n_states(self) -> int:
        """Number of error states (15 .. 25), from the C core's layout."""
        return int(self.layout().n_states)

    def layout(self):
        """The C core's state layout (``gf_ins_layout``: n_states, idx_* of every block,
        -1 for blocks this configuration has not)."""
        lay = ffi.new("gf_ins_layout *")
        check_status(lib.gf_ins_state_layout(self._c(), lay), "gf_ins_state_layout")
        return lay

    def noise_si(self) -> dict:
        """The process noise in SI, as the C filter takes it (``gf_ins_noise``, keyed by its
        members; see :class:`ImuNoise` for the datasheet conventions: a one-sided
        accelerometer noise density ASD has the white-noise intensity ASD²/2)."""
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
        out = dict(gyro_arw_rad_sqrt_s=m.gyro_arw_deg_sqrt_h * DEG / 60.0,
                   accel_vrw_m_s_sqrt_s=m.accel_vrw_ug_sqrt_hz * UG / math.sqrt(2.0),
                   gyro_bias_std_rad_s=gb, gyro_bias_tau_s=gyro_tau,
                   accel_bias_std_m_s2=ab, accel_bias_tau_s=accel_tau)
        for st in SETTINGS:   # the other noise members are FilterConfig fields
            if st.member.startswith("noise.") and st.python_name:
                out[st.short] = getattr(self, st.python_name)
        return out

    def _c(self):
        """The C struct (``gf_ins_config``), every member set from its table row; raises
        ValueError naming the FilterConfig field (or the IMU noise) the core refuses."""
        cfg = ffi.new("gf_ins_config *")
        check_status(lib.gf_ins_config_default(cfg), "gf_ins_config_default")
        noise = self.noise_si()
        for st in SETTINGS:
            owner, _, member = st.member.rpartition(".")
            target = getattr(cfg, owner) if owner else cfg
            value = noise[member] if owner == "noise" else st.c_value(getattr(self, st.python_name))
            setattr(target, member, float(value) if owner == "noise" else value)
        bad = ffi.new("int32_t *")
        if lib.gf_ins_config_check(cfg, bad) != lib.GF_OK:
            member = ffi.string(lib.gf_ins_config_field(bad[0])).decode()
            st = by_member(member)
            if not st.python_name:
                raise ValueError(f"FilterConfig.imu gives {st.short} = {_show(noise[st.short])}: "
                                 f"must be {st.describe_bounds()} (check the ImuNoise figures)")
            raise _refuse(st, getattr(self, st.python_name))
        return cfg


def _filter_config_doc() -> str:
    lines = ["Configuration of the integrated-navigation filter (units in the names).", "",
             "Every field but ``imu`` is a row of the settings table",
             "(:mod:`gfins_fmi.estimation.settings`): the same name in C (``gf_ins_config``) and",
             "as the ``gfins_ins_gnss`` FMU parameter.", "", "Parameters", "----------",
             "imu : ImuNoise",
             "    The IMU's random errors in datasheet units: angle/velocity random walk become",
             "    the white process noise, bias instability and correlation time the first-order",
             "    Gauss–Markov bias model (a rate random walk adds to its driving noise); in SI",
             "    as the C filter takes them: :meth:`noise_si`."]
    for st in python_settings():
        kind = {"flag": "bool", "enum": " | ".join(repr(c) for c in st.choices) if st.choices else "str",
                "int": "int", "float": "float", "vector": f"{st.size} floats"}[st.kind]
        unit = f", {st.unit}" if st.unit else ""
        lines.append(f"{st.python_name} : {kind}{unit}, default {st.default!r}")
        text = f"{st.meaning[0].upper() + st.meaning[1:]}; {st.describe_bounds()}."
        lines += textwrap.wrap(text, 84, initial_indent="    ", subsequent_indent="    ")
    return "\n    ".join(lines) + "\n    "


def _filter_config_fields() -> list:
    out = [("imu", ImuNoise, field(default_factory=ImuNoise))]
    types = {"flag": bool, "enum": str, "int": int, "float": float, "vector": tuple}
    for st in python_settings():
        typ = Optional[float] if st.bounds == "probability" else types[st.kind]
        out.append((st.python_name, typ, field(default=st.default)))
    return out


#: The filter's configuration: a dataclass whose fields (but ``imu``) are the rows of the
#: settings table, so that adding a setting is one row there
FilterConfig = make_dataclass("FilterConfig", _filter_config_fields(), bases=(_FilterConfigMethods,),
                              namespace={"__doc__": _filter_config_doc()})
FilterConfig.__module__ = __name__


#: the largest initial 1-sigma of each block (InitialState.std_blocks): unit, why
_STD_LIMITS = {
    "velocity_std_m_s": (1e4, "m/s", "faster than any vehicle"),
    "position_std_m": (1e7, "m", "more than the Earth's radius"),
    "attitude_std_rad": (math.pi, "rad", "more than a half turn; the error-state filter assumes "
                                         "small attitude errors"),
    "gyro_bias_std_rad_s": (50.0, "rad/s", "the gyro limit of the mechanization"),
    "accel_bias_std_m_s2": (1000.0, "m/s^2", "the accelerometer limit of the mechanization"),
    "gyro_scale_std": (1.0, "", "a scale error of 100 %"),
    "accel_scale_std": (1.0, "", "a scale error of 100 %"),
    "baro_bias_std_m": (1e5, "m", "more than the atmosphere"),
    "odometer_scale_std": (1.0, "", "a scale error of 100 %"),
    "odometer_mount_std_rad": (math.pi / 2, "rad", "a quarter turn, the boresight's range"),
    "master_mount_std_rad": (math.pi / 2, "rad", "a quarter turn; the mounting's error is taken as "
                                                 "small angles"),
    "master_lever_std_m": (1000.0, "m", "a lever arm longer than any host"),
    "master_time_offset_std_s": (10.0, "s", "streams this far apart are not one host's; align "
                                            "their time scales first"),
}


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
    #: transfer alignment (random constants): mounting (heading, pitch, roll, rad), lever
    #: arm (master axes, m) and time offset (s) about the configured nominal ones
    master_mount_std_rad: object = 0.02
    master_lever_std_m: object = 0.1
    master_time_offset_std_s: float = 0.02
    #: the start attitude is a master's turned by the configured mounting (transfer
    #: alignment): with mounting states, the attitude and mounting errors start correlated
    #: (``gf_ins_master_start_covariance``) and ``attitude_std_rad`` is then the
    #: uncertainty beyond the mounting's (the master's own attitude error)
    attitude_from_master: bool = False

    def std_blocks(self, config: FilterConfig) -> dict:
        """The 1-sigma of every error block as ``gf_ins_initial_std`` holds it (its member
        names; lists for the 3- and 2-element blocks), the defaults filled in from the
        configuration (the IMU's bias instability, the scale/bias/boresight stds)."""
        noise = config.noise_si()

        def given(x, default):
            return default if x is None else x

        values = {
            "velocity_std_m_s": self.velocity_std_m_s, "position_std_m": self.position_std_m,
            "attitude_std_rad": self.attitude_std_rad,
            "gyro_bias_std_rad_s": given(self.gyro_bias_std_rad_s, noise["gyro_bias_std_rad_s"]),
            "accel_bias_std_m_s2": given(self.accel_bias_std_m_s2, noise["accel_bias_std_m_s2"]),
            "gyro_scale_std": given(self.gyro_scale_std, config.gyro_scale_std),
            "accel_scale_std": given(self.accel_scale_std, config.accel_scale_std),
            "baro_bias_std_m": given(self.baro_bias_std_m, config.baro_bias_std_m),
            "odometer_scale_std": given(self.odometer_scale_std, config.odometer_scale_std),
            "odometer_mount_std_rad": given(self.odometer_mount_std_rad, config.odometer_mount_std_rad),
            "master_mount_std_rad": self.master_mount_std_rad,
            "master_lever_std_m": self.master_lever_std_m,
            "master_time_offset_std_s": self.master_time_offset_std_s,
        }
        sizes = {"baro_bias_std_m": 0, "odometer_scale_std": 0, "odometer_mount_std_rad": 2,
                 "master_time_offset_std_s": 0}
        out = {}
        for name, value in values.items():
            size = sizes.get(name, 3)
            arr = np.asarray(value, dtype=float)
            if size == 0:
                if arr.shape != ():
                    raise ValueError(f"InitialState.{name} must be one number; got {_show(value)}")
                out[name] = float(arr)
            else:
                if arr.shape not in ((), (size,)):
                    raise ValueError(f"InitialState.{name} must be one number or {size}; got "
                                     f"{_show(value)}")
                out[name] = np.broadcast_to(arr, (size,)).tolist()
            top, unit, why = _STD_LIMITS[name]
            worst = np.max(np.abs(arr)) if arr.size else 0.0
            if np.isfinite(worst) and worst > top:
                # before: the variance overflowed in C, "gf_ins_init: an input sample is not
                # finite" (issue 21)
                raise ValueError(f"InitialState.{name} = {_show(value)}{' ' + unit if unit else ''} "
                                 f"is above {top:g}{' ' + unit if unit else ''} ({why}): give the "
                                 "1-sigma of the error at the start")
        return out

    def covariance(self, config: FilterConfig) -> np.ndarray:
        """P0 (n x n, diagonal) in the filter's states (position as dlat, dlon rad, dh m):
        the C core's ``gf_ins_initial_covariance``, the one P0 of the batch API, the
        smoother and the FMU."""
        nav = self.nav
        values = self.std_blocks(config)
        std = ffi.new("gf_ins_initial_std *")
        for name, value in values.items():
            setattr(std, name, value)
        n = config.n_states
        P0 = np.empty((n, n))
        bad = ffi.new("int32_t *")
        c = config._c()
        st = lib.gf_ins_initial_covariance(c, float(nav.lat_rad), float(nav.h_m), std,
                                           ptr(P0, P0.size), bad)
        if st == lib.GF_OK and self.attitude_from_master and config.master_mount:
            q = np.ascontiguousarray(nav.q_bn, dtype=float)
            check_status(lib.gf_ins_master_start_covariance(c, ptr(q, 4), ptr(P0, P0.size)),
                         "gf_ins_master_start_covariance")
        if st == lib.GF_OK:
            return P0
        if bad[0]:
            name = ffi.string(lib.gf_ins_initial_std_field(bad[0])).decode()
            hint = ""
            if name in ("gyro_bias_std_rad_s", "accel_bias_std_m_s2") and getattr(self, name) is None:
                hint = (" (it defaults to the IMU model's bias instability, which is 0 here: give "
                        f"InitialState.{name} explicitly)")
            raise ValueError(f"InitialState.{name} = {_show(values[name])}: every element must be "
                             f"finite and > 0{hint}")
        if st == lib.GF_ERR_OUT_OF_RANGE:
            raise ValueError(f"initial latitude {math.degrees(float(nav.lat_rad)):.6g} deg is beyond "
                             "+-89 deg: the ENU error model is singular near the poles")
        raise ValueError(f"initial.nav: height {float(nav.h_m)!r} m is outside the Earth model "
                         f"({status_text(st)})")
