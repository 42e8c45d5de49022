"""Plausibility of finite but absurd inputs, where the physics says what to expect
(docs/io.md, "Checks before a run"): numbers that pass every finiteness and range check
yet cannot be what the user meant — times in milliseconds read as seconds, accelerations
in g, a site latitude the gyros contradict. Each check returns a sentence (what was
found, what was expected, the likely cause) or None; :func:`report` turns sentences into
a :class:`PlausibilityWarning` or an exception, as the caller chooses.

The expectations, each with its margin:

* **specific force** (:func:`specific_force_problem`): over a whole record of a vehicle
  that is not in free fall or on a rocket, the median ``|f|`` is within a factor of two
  of gravity (9.78-9.83 m/s^2): a level vehicle reads ``g``, a turning car or an aircraft
  in a 60-degree bank at most ``2 g`` on the median. Outside [g/2, 2 g] the unit or the
  interval is wrong (increments read as rates, mg, ft/s^2, times in ms).
* **sample interval** (:func:`interval_problem`): an accelerometer array measures
  ``omega_k^2`` and ``omega_dot`` independently (seed 000 eq. 4 and 6); between two
  samples ``d(omega_k^2) = 2 omega_k omega_dot_k dt``, so the record itself says how long
  its interval is. A time column more than 20 times longer than that is implausible (ms
  read as s gives 1000); shorter proves nothing (noise makes the implied one longer).
* **latitude** (:func:`latitude_problem`): at rest the gyros measure the Earth rate, whose
  component along the measured vertical is ``Omega sin(lat)`` and across it
  ``Omega cos(lat)``; with gyro biases of ``sigma`` rad/s the latitude this gives is good
  to about ``sigma / Omega`` rad. A given latitude further than five of those (and 2 deg)
  from it is not where the record was made.
"""
from __future__ import annotations

import warnings

import numpy as np

from gfins_fmi.nav.earth import WGS84, gravity

__all__ = ["PlausibilityWarning", "specific_force_problem", "interval_problem",
           "latitude_from_earth_rate", "latitude_problem", "report", "CHECKS"]

#: the choices of what a caller does with a finding: an exception, a warning, nothing
CHECKS = ("raise", "warn", "off")

#: a plausible median |f| of a vehicle's record lies within this factor of gravity
_F_FACTOR = 2.0
#: a time column is implausible beyond this factor of the interval the record implies
_DT_FACTOR = 20.0
#: a latitude is implausible beyond max(this many sigmas, _LAT_MIN_DEG) from the gyros'
_LAT_SIGMAS, _LAT_MIN_DEG = 5.0, 2.0


class PlausibilityWarning(UserWarning):
    """A finite input that the physics says is unlikely to be what was meant (the
    message says what was found, what was expected and the likely cause)."""


def specific_force_problem(f_norm_m_s2, what: str = "the record") -> str | None:
    """``f_norm_m_s2``: |f| of every sample (m/s^2). A sentence when the median is
    outside [g/2, 2 g]."""
    f = np.asarray(f_norm_m_s2, float)
    f = f[np.isfinite(f)]
    if f.size == 0:
        return None
    med = float(np.median(f))
    g = 9.80665
    if g / _F_FACTOR <= med <= g * _F_FACTOR:
        return None
    if med < 1e-6:
        return None           # no force at all: free fall or a synthetic record, nothing to say
    ratio = med / g
    hints = []
    if abs(ratio * 1000.0 - 1.0) < 0.2:
        hints.append("the sample times in ms where s are expected (increments divided by "
                     "an interval 1000 times too long)")
    if abs(ratio / 1000.0 - 1.0) < 0.2:
        hints.append("accelerations in mg or mm/s^2 where m/s^2 are expected")
    if 0.05 < ratio < 0.2:
        hints.append("accelerations in g where m/s^2 are expected")
    if abs(ratio / 3.28084 - 1.0) < 0.1:
        hints.append("accelerations in ft/s^2 where m/s^2 are expected")
    if not hints:
        hints.append("another unit, increments read as rates (or rates as increments), or a "
                     "wrong sample interval")
    return (f"{what}: the median specific force |f| is {med:.4g} m/s^2 ({ratio:.3g} g), but a "
            f"vehicle that is not in free fall reads about g = 9.81 m/s^2 (within a factor of "
            f"{_F_FACTOR:g}); likely cause: {'; or '.join(hints)}")


def interval_problem(dt_s: float, omega_sq_rad2_s2, omega_dot_rad_s2,
                     what: str = "the record") -> str | None:
    """The interval ``dt_s`` against the one the record's own rates imply: per axis,
    ``|d(omega^2)| = 2 |omega| |omega_dot| dt`` between samples (``omega_sq`` and
    ``omega_dot``, (n, 3), as an array solver gives them). A sentence when the two differ
    by more than a factor of 20; None without enough motion to tell."""
    w2 = np.asarray(omega_sq_rad2_s2, float)
    wd = np.asarray(omega_dot_rad_s2, float)
    if w2.ndim != 2 or w2.shape[0] < 8 or not np.isfinite(dt_s) or dt_s <= 0:
        return None
    ok = np.all(np.isfinite(w2), axis=1) & np.all(np.isfinite(wd), axis=1)
    w2, wd = w2[ok], wd[ok]
    if w2.shape[0] < 8:
        return None
    change = np.abs(np.diff(w2, axis=0))                      # per sample, rad^2/s^2
    w_mid = np.sqrt(np.maximum(0.5 * (w2[1:] + w2[:-1]), 0.0))
    rate = 2.0 * w_mid * np.abs(0.5 * (wd[1:] + wd[:-1]))     # d(omega^2)/dt, rad^2/s^3
    moving = rate > 1e-3 * max(float(np.max(rate)), 1e-300)
    if np.count_nonzero(moving) < 8 or not np.any(rate > 0):
        return None
    implied = float(np.median(change[moving] / rate[moving]))
    if not implied > 0:
        return None
    ratio = dt_s / implied
    # one way only: noise in omega^2 (a noisy or slowly turning record, or rows that are
    # not consecutive samples) makes the implied interval longer, never shorter, so a
    # given interval far SHORTER than implied proves nothing (tests/gyrofree's random
    # and noise-only records); far longer is the unit error (ms read as s: 1000)
    if ratio <= _DT_FACTOR:
        return None
    hint = ("times in ms where s are expected" if abs(ratio / 1000.0 - 1.0) < 0.3 else
            "a time column in another unit, or a --dt that is not the sampling interval")
    return (f"{what}: the sample interval is {dt_s:.6g} s, but the record's own rates imply "
            f"about {implied:.3g} s (the change of omega^2 between samples against "
            f"2 omega omega_dot): the interval given is {ratio:.4g} times longer; likely "
            f"cause: {hint}. The signs of omega come from integrating omega_dot over this "
            "interval: with a wrong one they are wrong")


def latitude_from_earth_rate(w_mean_rad_s, f_mean_m_s2) -> float:
    """The latitude (rad) the Earth rate gives at rest: ``w`` the mean gyro rate, ``f``
    the mean specific force (its direction is up): atan2 of the rate's components along
    and across the vertical (Omega sin(lat), Omega cos(lat))."""
    w = np.asarray(w_mean_rad_s, float)
    f = np.asarray(f_mean_m_s2, float)
    up = f / np.linalg.norm(f)
    along = float(w @ up)
    across = float(np.linalg.norm(w - along * up))
    return float(np.arctan2(along, across))


def latitude_problem(lat_rad: float, w_mean_rad_s, f_mean_m_s2, gyro_std_rad_s: float,
                     what: str = "the record") -> str | None:
    """A given latitude against the one the Earth rate gives at rest (see
    :func:`latitude_from_earth_rate`), with ``gyro_std_rad_s`` the 1-sigma of the mean
    rate per axis (bias and noise over the interval). None when the gyros cannot tell
    (sigma above a fifth of the Earth rate) or the two agree."""
    W = WGS84.omega_ie
    if not (np.isfinite(gyro_std_rad_s) and gyro_std_rad_s < 0.2 * W):
        return None
    f = np.asarray(f_mean_m_s2, float)
    if not np.all(np.isfinite(f)) or np.linalg.norm(f) <= 0:
        return None
    measured = latitude_from_earth_rate(w_mean_rad_s, f)
    sigma = gyro_std_rad_s / W
    limit = max(_LAT_SIGMAS * sigma, np.radians(_LAT_MIN_DEG))
    if abs(measured - lat_rad) <= limit:
        return None
    g_site = float(gravity(lat_rad, 0.0))
    return (f"{what}: the latitude given, {np.degrees(lat_rad):.4f} deg, is "
            f"{np.degrees(abs(measured - lat_rad)):.3g} deg from the one the gyros measure at rest, "
            f"{np.degrees(measured):.4f} deg +- {np.degrees(sigma):.2g} deg (the Earth rate's "
            f"components along and across the vertical); the record was made elsewhere, or the "
            f"latitude is wrong (in degrees? its sign?). Normal gravity there would be "
            f"{g_site:.6g} m/s^2, the accelerometers read {float(np.linalg.norm(f)):.6g} m/s^2")


def report(problems, checks: str = "warn", error=ValueError, stacklevel: int = 3) -> list[str]:
    """Act on the sentences ``problems`` (None entries skipped) as ``checks`` says:
    ``"raise"`` the first as ``error``, ``"warn"`` each as a :class:`PlausibilityWarning`,
    ``"off"`` nothing. Returns the sentences."""
    if checks not in CHECKS:
        raise ValueError(f"checks must be one of {', '.join(map(repr, CHECKS))}; got {checks!r}")
    found = [p for p in problems if p]
    if checks == "raise" and found:
        raise error(found[0])
    if checks == "warn":
        for p in found:
            warnings.warn(p, PlausibilityWarning, stacklevel=stacklevel)
    return found
