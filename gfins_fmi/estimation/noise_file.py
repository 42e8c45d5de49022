"""The IMU's blocks of the configuration file, in TOML: its random errors (the noise block,
read by ``gfins integrate --noise-file`` and written by ``gfins noise``) and its
deterministic errors (``[imu_errors]``, read by ``gfins integrate --imu-errors`` and written
by ``gfins calibrate poses``); the full configuration file of the own-data issue will
take these blocks as they are.

Two tables, each key carrying its unit:

``[imu]``
    :class:`~gfins_fmi.nav.imu_errors.ImuNoise` fields in datasheet units — what the
    filter is configured from (``FilterConfig(imu=...)``).
``[noise]``
    The same in SI under the settings table's names (:mod:`gfins_fmi.estimation.settings`,
    the ``noise.*`` rows: ``gyro_arw_rad_sqrt_s``, ``accel_vrw_m_s_sqrt_s``,
    ``gyro_bias_std_rad_s``, ``gyro_bias_tau_s``, ``accel_bias_std_m_s2``,
    ``accel_bias_tau_s``), as ``FilterConfig.noise_si()`` gives them to the C filter.

A file may hold either or both; when both, they must agree (1e-6 relative), so a value
edited in one table and not the other is refused, naming it. Other tables (``gfins
noise`` writes ``[identified]``, the per-axis fit) are kept for people, not read.

Density conventions, both ways (white noise of per-sample std s at interval dt):

* gyro ``gyro_arw_deg_sqrt_h`` N: Allan deviation N / sqrt(tau), N = s sqrt(dt) = the
  square root of the two-sided PSD; in deg/s/sqrt(Hz) as a two-sided density N / 60, as a
  one-sided density sqrt(2) N / 60.
* accelerometer ``accel_vrw_ug_sqrt_hz`` S: the ONE-sided amplitude density, S = sqrt(2) N
  with N = s sqrt(dt) the Allan (two-sided) velocity random walk; N in m/s/sqrt(h) =
  60 N in m/s/sqrt(s) = 60 S UG / sqrt(2).
"""
from __future__ import annotations

import dataclasses
import math
import pathlib
import sys

import numpy as np

from gfins_fmi.estimation.config import UG, FilterConfig
from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.imu_errors import DEG_H, ImuErrors, ImuNoise

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.9 and 3.10 read TOML with tomli (a dependency there)
    import tomli as tomllib

__all__ = ["read_noise_file", "write_noise_file", "noise_text", "IMU_UNITS", "NOISE_KEYS",
           "imu_errors_text", "read_imu_errors", "IMU_ERROR_KEYS"]

#: [imu_errors] keys: the ImuErrors fields (datasheet units) and their shapes
IMU_ERROR_KEYS = {"gyro_bias_deg_h": (3,), "gyro_scale_ppm": (3,), "gyro_misalignment_arcsec": (3, 3),
                  "accel_bias_ug": (3,), "accel_scale_ppm": (3,), "accel_misalignment_arcsec": (3, 3),
                  "accel_k2_ug_g2": (3,), "lever_arm_cm": (3,)}

#: [imu] keys: the ImuNoise fields and what they mean
IMU_UNITS = {
    "gyro_arw_deg_sqrt_h": "angle random walk N, deg/sqrt(h) (Allan: N / sqrt(tau))",
    "gyro_bias_instability_deg_h": "gyro bias, first-order Gauss-Markov stationary std, deg/h",
    "gyro_correlation_time_s": "its correlation time, s",
    "gyro_rrw_deg_h_sqrt_h": "gyro rate random walk K, deg/h/sqrt(h) (Allan: K sqrt(tau / 3))",
    "accel_vrw_ug_sqrt_hz": "accelerometer white noise, ONE-sided amplitude density, ug/sqrt(Hz)",
    "accel_bias_instability_ug": "accelerometer bias, Gauss-Markov stationary std, ug",
    "accel_correlation_time_s": "its correlation time, s",
    "accel_rrw_ug_sqrt_s": "accelerometer bias random walk, ug/sqrt(s)",
    "gyro_band_deg_h": "band-limited gyro noise std, deg/h (simulation only)",
    "accel_band_ug": "band-limited accelerometer noise std, ug (simulation only)",
    "band_hz": "corner of the band-limited noise, Hz (simulation only)",
}
#: [noise] keys: the settings table's names of the IMU's process noise (SI)
NOISE_KEYS = {
    "gyro_arw_rad_sqrt_s": "rad/sqrt(s)", "accel_vrw_m_s_sqrt_s": "m/s/sqrt(s) (= S UG / sqrt(2))",
    "gyro_bias_std_rad_s": "rad/s", "gyro_bias_tau_s": "s (0: random constant)",
    "accel_bias_std_m_s2": "m/s^2", "accel_bias_tau_s": "s (0: random constant)",
}


def _fmt(x: float) -> str:
    return repr(float(x))


def noise_text(imu: ImuNoise, header: str = "", identified: str = "") -> str:
    """The noise block of ``imu`` as TOML text (both tables), ``header`` as comment lines
    at the top and ``identified`` (TOML text) appended."""
    if not isinstance(imu, ImuNoise):
        raise TypeError(f"imu must be an ImuNoise; got {type(imu).__name__}")
    si = FilterConfig(imu=imu).noise_si()
    lines = [f"# {x}" if x else "#" for x in header.splitlines()]
    lines += ["# gfins_fmi noise block: read by `gfins integrate --noise-file FILE` "
              "(gfins_fmi.estimation.noise_file).",
              "# [imu] is what the filter is configured from; [noise] is the same in SI under the",
              "# settings table's names. Edit one table and delete the other, or edit both alike.",
              "# Densities: gyro N is the Allan (two-sided) ARW, = N/60 deg/s/sqrt(Hz) two-sided,",
              "# sqrt(2) N/60 one-sided; accel_vrw_ug_sqrt_hz is ONE-sided: the Allan VRW is",
              "# S/sqrt(2) ug/sqrt(Hz) = 60 S 9.80665e-6/sqrt(2) m/s/sqrt(h).", "", "[imu]"]
    for k, what in IMU_UNITS.items():
        lines.append(f"{k} = {_fmt(getattr(imu, k))}   # {what}")
    lines += ["", "[noise]   # SI, the filter's settings-table names (noise.*)"]
    for k, unit in NOISE_KEYS.items():
        lines.append(f"{k} = {_fmt(si[k])}   # {unit}")
    if identified:
        lines += ["", identified.rstrip()]
    return "\n".join(lines) + "\n"


def write_noise_file(path, imu: ImuNoise, header: str = "", identified: str = "") -> pathlib.Path:
    """Write :func:`noise_text` to ``path`` (beside it first, then renamed: nothing
    half-written is left)."""
    path = pathlib.Path(path)
    tmp = path.with_name(path.name + ".part")
    tmp.write_text(noise_text(imu, header, identified), encoding="utf-8")
    tmp.replace(path)
    return path


def _number(path, table, key, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{path}: [{table}] {key} must be a finite number; got {value!r}")
    return float(value)


def _from_si(si: dict) -> ImuNoise:
    """ImuNoise of the filter's SI noise (the inverse of FilterConfig.noise_si for a model
    without rate random walk: the filter holds it inside the Gauss-Markov std)."""
    def tau(t, std):   # 0 = a random constant: a Gauss-Markov bias that never decorrelates
        return t if t > 0 else (1e12 if std > 0 else 100.0)

    return ImuNoise(gyro_arw_deg_sqrt_h=si["gyro_arw_rad_sqrt_s"] / deg * 60.0,
                    accel_vrw_ug_sqrt_hz=si["accel_vrw_m_s_sqrt_s"] * math.sqrt(2.0) / UG,
                    gyro_bias_instability_deg_h=si["gyro_bias_std_rad_s"] / DEG_H,
                    gyro_correlation_time_s=tau(si["gyro_bias_tau_s"], si["gyro_bias_std_rad_s"]),
                    accel_bias_instability_ug=si["accel_bias_std_m_s2"] / UG,
                    accel_correlation_time_s=tau(si["accel_bias_tau_s"], si["accel_bias_std_m_s2"]))


def read_noise_file(path) -> ImuNoise:
    """The IMU noise model of a noise block (see the module docstring).

    Raises
    ------
    FileNotFoundError, ValueError
        No file; not TOML; an unknown key (the message lists the known ones); a value
        that is not a finite number or that ImuNoise refuses; [imu] and [noise] that
        disagree (the message names the key and both values).
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (a noise block, TOML, was expected: "
                                "`gfins noise RECORD --output FILE` writes one)")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not a TOML noise block: {exc}") from exc
    imu_t, noise_t = doc.get("imu"), doc.get("noise")
    if imu_t is None and noise_t is None:
        raise ValueError(f"{path}: no [imu] or [noise] table (see gfins_fmi.estimation.noise_file)")
    model = None
    if imu_t is not None:
        bad = sorted(set(imu_t) - set(IMU_UNITS))
        if bad:
            raise ValueError(f"{path}: [imu] has unknown keys {bad}; the keys are "
                             f"{', '.join(IMU_UNITS)}")
        values = {k: _number(path, "imu", k, v) for k, v in imu_t.items()}
        try:
            model = ImuNoise(**values)
        except ValueError as exc:
            raise ValueError(f"{path}: [imu]: {exc}") from exc
    if noise_t is not None:
        bad = sorted(set(noise_t) - set(NOISE_KEYS))
        missing = sorted(set(NOISE_KEYS) - set(noise_t))
        if bad or missing:
            raise ValueError(f"{path}: [noise] must have exactly the keys {', '.join(NOISE_KEYS)}"
                             + (f"; unknown {bad}" if bad else "") + (f"; missing {missing}" if missing else ""))
        si = {k: _number(path, "noise", k, v) for k, v in noise_t.items()}
        if model is None:
            try:
                return _from_si(si)
            except ValueError as exc:
                raise ValueError(f"{path}: [noise]: {exc}") from exc
        have = FilterConfig(imu=model).noise_si()
        for k in NOISE_KEYS:
            if not math.isclose(have[k], si[k], rel_tol=1e-6, abs_tol=1e-300):
                raise ValueError(f"{path}: [noise] {k} = {si[k]!r} but [imu] gives {have[k]!r}: "
                                 "edit both tables alike, or delete one of them")
    return dataclasses.replace(model)


def _toml_array(a) -> str:
    a = np.asarray(a, dtype=float)
    if a.ndim == 1:
        return "[" + ", ".join(repr(float(x)) for x in a) + "]"
    return "[" + ", ".join(_toml_array(r) for r in a) + "]"


def imu_errors_text(errors, header: str = "", std: dict | None = None) -> str:
    """``[imu_errors]`` (ImuErrors fields at the reference temperature, datasheet units)
    as TOML, with ``[imu_errors_std]`` (1-sigma, same keys) when ``std`` is given."""
    lines = [f"# {x}" if x else "#" for x in header.splitlines()]
    lines += ["# The IMU's deterministic errors (gfins_fmi.ImuErrors, w_out = (I + diag s)(I + N) w + b):",
              "# `gfins integrate --imu-errors FILE` compensates the IMU record with them first.", "",
              "[imu_errors]"]
    for k in IMU_ERROR_KEYS:
        v = getattr(errors, k)
        if v is not None:
            lines.append(f"{k} = {_toml_array(v)}")
    if std:
        lines += ["", "[imu_errors_std]   # 1-sigma of each value above (informative, not read)"]
        for k, v in std.items():
            lines.append(f"{k} = {_toml_array(v)}")
    return "\n".join(lines) + "\n"


def read_imu_errors(path):
    """The ImuErrors of a file's ``[imu_errors]`` table.

    Raises
    ------
    FileNotFoundError, ValueError
        No file, no table, an unknown key (the known ones listed), a value of the wrong
        shape or out of the model's range (named).
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (IMU errors, TOML, were expected: `gfins "
                                "calibrate poses RECORD --output FILE` writes them)")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: not TOML: {exc}") from exc
    t = doc.get("imu_errors")
    if t is None:
        raise ValueError(f"{path}: no [imu_errors] table")
    bad = sorted(set(t) - set(IMU_ERROR_KEYS))
    if bad:
        raise ValueError(f"{path}: [imu_errors] has unknown keys {bad}; the keys are {', '.join(IMU_ERROR_KEYS)}")
    kw = {}
    for k, v in t.items():
        try:
            arr = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{path}: [imu_errors] {k} must be numbers of shape {IMU_ERROR_KEYS[k]}") from None
        if arr.shape != IMU_ERROR_KEYS[k]:
            raise ValueError(f"{path}: [imu_errors] {k} must have shape {IMU_ERROR_KEYS[k]}; got {arr.shape}")
        kw[k] = arr
    try:
        return ImuErrors(**kw)
    except ValueError as exc:
        raise ValueError(f"{path}: [imu_errors]: {exc}") from exc
