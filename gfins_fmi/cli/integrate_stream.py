"""``gfins integrate`` in chunks: an IMU record of any format it reads
(:class:`~gfins_fmi.io.imu_stream.ImuChunks`) read, filtered and written a chunk at a time, so the memory a run needs does not grow with the
record's length (issue 20). The filter carries its state from one chunk to the next
(:meth:`~gfins_fmi.estimation.navigator.IntegratedNavigator.run` continues where it
stopped); each chunk gets the measurements valid in its own span, so the result is the
whole record's, bit for bit. The summary is accumulated as the chunks pass
(:class:`Scores`: the same figures as the whole-record summary). ``--smooth`` runs in
chunks too (:mod:`gfins_fmi.cli.integrate_smooth`); runs that need the whole solution at
once (``--plot``) read the record whole.
"""
from __future__ import annotations

import dataclasses
import types

import numpy as np

from gfins_fmi import io
from gfins_fmi.estimation.config import SENSOR_NAMES
from gfins_fmi.estimation.evaluation import gnss_residuals, navigation_errors
from gfins_fmi.io.columns import integrated_columns

__all__ = ["grouped", "time_slice", "Scores", "sensor_columns", "solution_table", "STREAM_CHUNK"]

#: IMU samples per chunk, a multiple of every --subsamples (a cut changes nothing: the result
#: is the whole record's); 4.8e4 samples make ~15 MB of solution and ~25 MB of text a chunk
STREAM_CHUNK = 48_000


def sensor_columns(cfg, all_states: bool) -> list[int]:
    """The sensor estimates written: the biases, and the states the configuration enables
    (the others stay exactly 0: ten all-zero columns by default before), or all."""
    keep = list(range(6))
    for on, idx in ((cfg.scale_factors, range(6, 12)), (cfg.baro_bias, [12]), (cfg.odometer_scale, [13]),
                    (cfg.odometer_mount, [14, 15])):
        if on or all_states:
            keep += list(idx)
    return keep


def solution_table(sol, all_states: bool) -> tuple:
    """Our solution table's names and columns: position, velocity and attitude in degrees,
    the 1-sigma (attitude in degrees), the estimates of the sensor states the filter has."""
    to_deg = 180.0 / np.pi
    e = sol.euler_rad * to_deg
    keep = sensor_columns(sol.config, all_states)
    cols = [sol.t_s, sol.lat_rad * to_deg, sol.lon_rad * to_deg, sol.h_m, *sol.v_n_m_s.T, *e.T,
            *sol.std[:, 0:6].T, *(sol.std[:, 6:9] * to_deg).T, *(sol.sensors[:, k] for k in keep)]
    return integrated_columns([SENSOR_NAMES[k] for k in keep]), cols


def grouped(records, n: int):
    """ImuRecords regrouped so that each holds a multiple of ``n`` samples (the last
    excepted): the C core groups ``--subsamples`` samples on the grid of its sample count,
    so a call that ends inside a group would process it as the whole record does not. The
    samples left over from one record start the next."""
    rest = None
    for rec in records:
        if rest is not None:
            rec = io.ImuRecord(np.r_[rest.t_s, rec.t_s], np.vstack([rest.gyro, rec.gyro]),
                               np.vstack([rest.accel, rec.accel]), rec.kind, rec.source)
            rest = None
        m = len(rec) - len(rec) % n
        if m < len(rec):
            rest = io.ImuRecord(rec.t_s[m:], rec.gyro[m:], rec.accel[m:], rec.kind, rec.source)
            if m == 0:
                continue
            rec = io.ImuRecord(rec.t_s[:m], rec.gyro[:m], rec.accel[:m], rec.kind, rec.source)
        yield rec
    if rest is not None:
        yield rest


def time_slice(rec, lo: float, hi: float):
    """The rows of a measurement record with lo < t <= hi (None when none or no record)."""
    if rec is None:
        return None
    t = np.asarray(rec.t_s)
    sel = (t > lo) & (t <= hi)
    if not np.any(sel):
        return None
    rows = {f.name: getattr(rec, f.name) for f in dataclasses.fields(rec)}
    n = len(t)
    out = {k: (np.asarray(v)[sel] if isinstance(v, np.ndarray) and v.ndim >= 1 and len(v) == n else v)
           for k, v in rows.items()}
    return type(rec)(**out)


class Scores:
    """The run's summary, accumulated chunk by chunk: errors against the truth (sums of
    squares), or residuals to the GNSS fixes used at the antenna (the fixes between two
    chunks interpolated with the previous chunk's last row), and the outage protocol's
    maximum drift per window; the same figures as the whole solution's summary."""

    def __init__(self, gnss, used, truth, windows, lever_arm_m):
        self.gnss, self.used, self.truth, self.windows, self.arm = gnss, used, truth, windows, lever_arm_m
        self.sums = {"h": 0.0, "u": 0.0, "hd": 0.0}
        self.counts = {"h": 0, "hd": 0}
        self.drift = None if windows is None else np.full(len(windows), np.nan)
        self.prev = None      # the last row of the previous chunk

    def _with_prev(self, sol):
        keys = ("t_s", "lat_rad", "lon_rad", "h_m", "q_bn")
        cur = {k: np.asarray(getattr(sol, k)) for k in keys}
        if self.prev is not None:
            cur = {k: np.concatenate([self.prev[k], cur[k]]) for k in keys}
        self.prev = {k: v[-1:] for k, v in cur.items()}
        return types.SimpleNamespace(**cur)

    def _max(self, t, hz):
        for i, (a, b) in enumerate(self.windows):
            sel = (t > a) & (t < b) & np.isfinite(hz)
            if np.any(sel):
                self.drift[i] = np.nanmax([self.drift[i], hz[sel].max()])

    def add(self, sol) -> None:
        if len(sol) == 0:
            return
        lo = float(self.prev["t_s"][0]) if self.prev is not None else -np.inf
        rows = self._with_prev(sol)
        if self.truth is not None:
            e = navigation_errors(sol, self.truth)
            hz = e.horizontal_m
            ok = np.isfinite(hz)
            self.sums["h"] += float(np.sum(hz[ok] ** 2))
            self.sums["u"] += float(np.sum(e.pos_enu_m[ok, 2] ** 2))
            self.counts["h"] += int(ok.sum())
            if e.heading_rad is not None:
                okh = np.isfinite(e.heading_rad)
                self.sums["hd"] += float(np.sum(e.heading_rad[okh] ** 2))
                self.counts["hd"] += int(okh.sum())
            if self.windows is not None:
                self._max(e.t_s, hz)
            return
        hi = float(rows.t_s[-1])
        used = time_slice(self.used, lo, hi)
        if used is not None:
            r = gnss_residuals(rows, used, self.arm)
            self.sums["h"] += float(np.sum(r.horizontal_m ** 2))
            self.sums["u"] += float(np.sum(r.enu_m[:, 2] ** 2))
            self.counts["h"] += len(r.t_s)
        if self.windows is not None:
            removed = time_slice(self.gnss, lo, hi)
            if removed is not None:
                r = gnss_residuals(rows, removed, self.arm)
                self._max(r.t_s, r.horizontal_m)

    def lines(self, name: str = "filter") -> list[str]:
        """The summary's lines, as the whole-record summary prints them."""
        n = max(self.counts["h"], 1)
        hz, up = np.sqrt(self.sums["h"] / n), np.sqrt(self.sums["u"] / n)
        arm = ",".join(f"{x:g}" for x in self.arm)
        if self.truth is not None:
            hd = (f", heading RMS {np.degrees(np.sqrt(self.sums['hd'] / self.counts['hd'])):.4f} deg"
                  if self.counts["hd"] else "")
            out = [f"{name}: error to the truth: horizontal RMS {hz:.3f} m, vertical RMS {up:.3f} m{hd}"]
        else:
            out = [f"{name}: residuals to the GNSS fixes used ({self.counts['h']}, at the antenna: lever arm "
                   f"{arm} m): horizontal RMS {hz:.3f} m, vertical RMS {up:.3f} m (residuals, not errors: the "
                   "fixes carry their own noise)"]
        if self.windows is not None:
            ok = self.drift[np.isfinite(self.drift)]
            against = "the truth" if self.truth is not None else "the removed fixes at the antenna"
            if len(ok):
                out.append(f"{name}: outage protocol ({len(self.windows)} outages, against {against}): RMS of the "
                           f"maximum horizontal drift per outage {np.sqrt(np.mean(ok ** 2)):.3f} m "
                           f"(max {ok.max():.3f} m)")
        return out
