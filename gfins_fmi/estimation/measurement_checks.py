"""Measurements that cannot be used, found before a run (docs/io.md, "Checks before a
run"): a sensor record none of whose epochs falls inside the IMU record the
filter is about to process would leave the run unaided while looking aided — the usual
cause is two time scales (GPS seconds of week against seconds since start, UTC against
GPS, ms against s). :func:`unusable_measurements` says which; the batch API raises
:class:`UnusableMeasurementError` or warns (:class:`UnusableMeasurementWarning`), as the
caller chooses (``checks=``), and ``gfins integrate`` refuses the run (exit 2).
"""
from __future__ import annotations

import warnings

import numpy as np

from gfins_fmi.nav.plausibility import CHECKS

__all__ = ["UnusableMeasurementError", "UnusableMeasurementWarning", "unusable_measurements",
           "check_measurements"]

#: seconds in a GPS week
_WEEK_S = 604800.0


class UnusableMeasurementError(ValueError):
    """A measurement record that the run cannot use at all (no epoch in the IMU record)."""


class UnusableMeasurementWarning(UserWarning):
    """As :class:`UnusableMeasurementError`, when the caller asked for a warning."""


def _hint(t_meas: np.ndarray, t0: float, t1: float) -> str:
    """The likely cause of records that do not overlap, from how their times compare."""
    mid_m, mid_i = float(np.median(t_meas)), 0.5 * (t0 + t1)
    offset = mid_m - mid_i
    span = max(t1 - t0, 1e-9)
    if mid_i > 0 and abs(mid_m / mid_i / 1000.0 - 1.0) < 0.05:
        return "its times are about 1000 times the IMU's: milliseconds against seconds?"
    if mid_m > 0 and abs(mid_i / mid_m / 1000.0 - 1.0) < 0.05:
        return "the IMU's times are about 1000 times its times: milliseconds against seconds?"
    weeks = round(offset / _WEEK_S)
    if weeks and abs(offset - weeks * _WEEK_S) < max(span, 3600.0):
        return (f"they are {weeks:d} GPS week{'s' if abs(weeks) != 1 else ''} apart: seconds "
                "of week against a continuous time? (KF-GINS files: --gps-week)")
    return (f"they are {offset:+.6g} s apart: put both records on one time scale (GPS seconds "
            "of week, UTC or GPS time, seconds since the start)")


def unusable_measurements(t_start_s: float, t_end_s: float, **records) -> list[str]:
    """One sentence per record (keyword: its name, e.g. ``gnss=``) that has epochs but
    none in [``t_start_s``, ``t_end_s``], the span of the IMU record the filter processes
    (its state's time, where an epoch is still applied, to the last sample). None records
    and empty ones are skipped."""
    problems = []
    t0, t1 = float(t_start_s), float(t_end_s)
    if abs(t0) < 1e-9 * max(1.0, abs(t1)):
        t0 = 0.0        # a start computed as t[0] - dt: round-off, not a time worth printing
    for name, rec in records.items():
        if rec is None:
            continue
        t = np.asarray(rec.t_s, float)
        t = t[np.isfinite(t)]
        if t.size == 0:
            continue
        inside = int(np.count_nonzero((t >= t0) & (t <= t1)))
        if inside:
            continue
        label = "GNSS" if name == "gnss" else name
        problems.append(
            f"no {label} epoch falls inside the IMU record ({t0:.10g} to {t1:.10g} s): its "
            f"{t.size} epoch{'s' if t.size != 1 else ''} cover {float(t.min()):.10g} to "
            f"{float(t.max()):.10g} s, so the run would be unaided; {_hint(t, t0, t1)}")
    return problems


def check_measurements(t_start_s: float, t_end_s: float, checks: str = "raise",
                       stacklevel: int = 3, **records) -> list[str]:
    """:func:`unusable_measurements`, acted on as ``checks`` says: ``"raise"``
    (:class:`UnusableMeasurementError`, the first problem), ``"warn"``
    (:class:`UnusableMeasurementWarning`, each) or ``"off"``. Returns the problems."""
    if checks not in CHECKS:
        raise ValueError(f"checks must be one of {', '.join(map(repr, CHECKS))}; got {checks!r}")
    if checks == "off":
        return []
    problems = unusable_measurements(t_start_s, t_end_s, **records)
    if problems and checks == "raise":
        raise UnusableMeasurementError(problems[0] + " (checks='warn' runs it all the same)")
    for p in problems:
        warnings.warn(p, UnusableMeasurementWarning, stacklevel=stacklevel)
    return problems
