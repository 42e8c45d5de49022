"""Still intervals of a hand-turned IMU record (Tedaldi, Pretto and Menegatti, ICRA 2014,
sec. III-A, as imu_tk implements it, with a gyro test added).

The record starts at rest for ``initial_s``; that period gives the sensor's own noise:
the variance of each accelerometer axis and the gyro's mean and variance. A sample is
still when, over a centred window of ``window_s``, the summed variance of the three
accelerometer axes is below ``accel_factor`` times the initial one AND the mean gyro
rate (the initial mean removed) is below ``gyro_factor`` times the initial noise of a
window mean plus ``gyro_floor_deg_s``. Runs of still samples at least ``min_still_s``
long are the poses, trimmed by half a window at each end (samples whose window touches a
turn). What was found, and what was refused, is reported in words.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi.io.records import ImuRecord

__all__ = ["StillDetector", "StillIntervals", "detect_still"]


@dataclass(frozen=True)
class StillDetector:
    """Thresholds of :func:`detect_still` (units in the names)."""
    initial_s: float = 20.0
    window_s: float = 1.0
    accel_factor: float = 6.0
    gyro_factor: float = 6.0
    gyro_floor_deg_s: float = 0.5
    min_still_s: float = 2.0

    def __post_init__(self):
        for k, v in self.__dict__.items():
            if not (np.isfinite(v) and v > 0 or (k == "gyro_floor_deg_s" and v == 0)):
                raise ValueError(f"StillDetector.{k} must be finite and > 0; got {v!r}")
        if self.min_still_s < self.window_s:
            raise ValueError(f"StillDetector.min_still_s ({self.min_still_s:g} s) must be at least "
                             f"window_s ({self.window_s:g} s)")


@dataclass
class StillIntervals:
    """The poses found.

    Attributes
    ----------
    ranges : (k, 2) sample index ranges [start, end) of the poses
    accel_var_init, gyro_mean_init, gyro_var_init : the initial period's statistics (SI)
    accel_stat, gyro_stat : (n,) the windowed statistics, for figures
    accel_threshold, gyro_threshold : the thresholds applied (m^2/s^4, rad/s)
    rejected : list of (start, end) still runs shorter than min_still_s
    notes : what was found, in words
    """
    ranges: np.ndarray
    accel_var_init: np.ndarray
    gyro_mean_init: np.ndarray
    gyro_var_init: np.ndarray
    accel_stat: np.ndarray = field(repr=False)
    gyro_stat: np.ndarray = field(repr=False)
    accel_threshold: float = 0.0
    gyro_threshold: float = 0.0
    rejected: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.ranges)


def _window_mean(x: np.ndarray, w: int) -> np.ndarray:
    """Centred moving mean over w samples (n, k), edges over the samples available;
    the record's first row subtracted first so that the cumulative sums stay small."""
    x0 = x[0]
    c = np.cumsum(np.vstack([np.zeros((1, x.shape[1])), x - x0]), axis=0)
    n = len(x)
    lo = np.clip(np.arange(n) - w // 2, 0, n)
    hi = np.clip(np.arange(n) - w // 2 + w, 0, n)
    return (c[hi] - c[lo]) / (hi - lo)[:, None] + x0


def detect_still(imu: ImuRecord, detector: StillDetector = StillDetector()) -> StillIntervals:
    """Find the still poses of a record (rates or increments) that starts at rest.

    Raises
    ------
    ValueError
        The record is shorter than the initial period plus a window, or moves during it
        (its accelerometer variance is far above that of the rest of the record's still
        parts cannot be told: then the initial period's gyro shows rotation).
    """
    rec = imu.to_rates()
    t = rec.t_s
    dt = float(np.median(np.diff(t)))
    n_init = int(round(detector.initial_s / dt))
    w = max(3, int(round(detector.window_s / dt)))
    if len(t) < n_init + 2 * w:
        raise ValueError(f"the record ({len(t)} samples, {t[-1] - t[0]:.1f} s) is shorter than the "
                         f"initial still period ({detector.initial_s:g} s) and two windows")
    a, g = rec.accel, rec.gyro
    a_var0 = np.var(a[:n_init], axis=0)
    g_mean0 = np.mean(g[:n_init], axis=0)
    g_var0 = np.var(g[:n_init], axis=0)
    # the initial period must itself be still: its gyro mean over windows stays within
    # the noise, its accelerometer norm constant
    init_rot = np.degrees(np.abs(_window_mean(g[:n_init] - g_mean0, w)).max())
    if init_rot > max(1.0, 10 * np.degrees(np.sqrt(g_var0.max() / w))):
        raise ValueError(f"the record moves during its first {detector.initial_s:g} s (a gyro window "
                         f"mean departs {init_rot:.2f} deg/s from the period's mean): start the "
                         "record at rest, or set a shorter initial period")
    m1 = _window_mean(a, w)
    m2 = _window_mean(a * a, w)
    accel_stat = np.sum(np.maximum(m2 - m1 * m1, 0.0), axis=1) * w / max(w - 1, 1)
    gyro_stat = np.linalg.norm(_window_mean(g - g_mean0, w), axis=1)
    a_thr = detector.accel_factor * float(np.sum(a_var0))
    g_thr = detector.gyro_factor * float(np.sqrt(np.sum(g_var0) / w)) + np.radians(detector.gyro_floor_deg_s)
    still = (accel_stat <= a_thr) & (gyro_stat <= g_thr)
    still[:n_init] = True
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(np.int8), 0]))
    runs = edges.reshape(-1, 2)
    min_n = int(round(detector.min_still_s / dt))
    half = w // 2
    ranges, rejected = [], []
    for s, e in runs:
        s2, e2 = (s if s == 0 else s + half), (e if e == len(t) else e - half)
        if e2 - s2 >= min_n:
            ranges.append((s2, e2))
        else:
            rejected.append((int(s), int(e)))
    ranges = np.array(ranges, dtype=np.int64).reshape(-1, 2)
    notes = [f"{len(ranges)} still poses of at least {detector.min_still_s:g} s (window {detector.window_s:g} s; "
             f"accelerometer variance <= {detector.accel_factor:g} x the initial "
             f"{np.sum(a_var0):.3g} m^2/s^4, gyro window mean <= {np.degrees(g_thr):.3g} deg/s)"]
    if rejected:
        notes.append(f"{len(rejected)} still runs shorter than {detector.min_still_s:g} s left out "
                     f"(at {', '.join(f'{t[s]:.1f}' for s, _ in rejected[:8])}{' ...' if len(rejected) > 8 else ''} s)")
    return StillIntervals(ranges, a_var0, g_mean0, g_var0, accel_stat, gyro_stat, a_thr, g_thr, rejected, notes)
