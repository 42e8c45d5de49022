"""A raw calibration record cut into static intervals and turns (from the gyro
increments alone), and the checks of a record before the filter runs on it (units,
sampling, rest at the start, motion per sample, the site's gravity and Earth rate)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.calibration.syscal_filter import CalibrationInputError, core_gravity_m_s2
from gfins_fmi.nav.earth import WGS84
from gfins_fmi.nav.plausibility import latitude_from_earth_rate, latitude_problem, report

__all__ = ["Segment", "segment_record", "record_increments", "check_record", "lat_problem"]

@dataclass(frozen=True)
class Segment:
    """A static interval or a turn of a record: samples [i0, i1), times (t0_s, t1_s];
    for a turn, the rotation's axis in IMU axes at its start and its angle (deg)."""
    kind: str
    i0: int
    i1: int
    t0_s: float
    t1_s: float
    axis: tuple = (0.0, 0.0, 0.0)
    angle_deg: float = 0.0

    @property
    def duration_s(self) -> float:
        return self.t1_s - self.t0_s

    def describe(self) -> str:
        if self.kind == "static":
            return f"static {self.duration_s:.1f} s"
        ax = np.asarray(self.axis)
        k = int(np.argmax(np.abs(ax)))
        name = f"{'+' if ax[k] > 0 else '-'}{'xyz'[k]}" if abs(ax[k]) > 0.99 else \
            "[" + ", ".join(f"{v:.2f}" for v in ax) + "]"
        return f"turn {self.angle_deg:.1f} deg about {name} ({self.duration_s:.1f} s)"


def record_increments(record):
    """(t_end (n,), dt (n,), dtheta (n, 3), dv (n, 3)) of an ImuRecord of increments or rates
    (rates: trapezoidal increments between samples; the first sample starts the record)."""
    t = np.asarray(record.t_s)
    if record.kind == "increments":
        if t.size < 2:
            raise CalibrationInputError("the record has fewer than 2 samples")
        dt = np.diff(t)
        return t[1:], dt, np.asarray(record.gyro)[1:], np.asarray(record.accel)[1:]
    g, a = np.asarray(record.gyro), np.asarray(record.accel)
    dt = np.diff(t)
    return t[1:], dt, 0.5 * (g[1:] + g[:-1]) * dt[:, None], 0.5 * (a[1:] + a[:-1]) * dt[:, None]


def _composed_rotation(rotvecs: np.ndarray) -> np.ndarray:
    """The quaternion of the ordered product q(v_0) (x) q(v_1) (x) ... of the rotations of
    the increments ``rotvecs`` (m, 3), by pairwise products (log2(m) vectorised passes)."""
    a = np.linalg.norm(rotvecs, axis=1)
    k = np.where(a > 1e-12, np.sin(0.5 * a) / np.where(a > 0, a, 1.0), 0.5)
    q = np.c_[np.cos(0.5 * a), rotvecs * k[:, None]]
    while q.shape[0] > 1:
        if q.shape[0] % 2:
            q = np.r_[q, [[1.0, 0.0, 0.0, 0.0]]]
        p, r = q[0::2], q[1::2]
        q = np.c_[p[:, 0] * r[:, 0] - np.sum(p[:, 1:] * r[:, 1:], axis=1),
                  p[:, [0]] * r[:, 1:] + r[:, [0]] * p[:, 1:] + np.cross(p[:, 1:], r[:, 1:])]
    return q[0] if q.shape[0] else np.array([1.0, 0.0, 0.0, 0.0])


def segment_record(t_s, dtheta_rad, rate_threshold_deg_s: float = 0.5, smooth_s: float = 0.2,
                   min_static_s: float = 5.0, margin_s: float = 1.0) -> list:
    """Static intervals and turns of a record of increments (interval ends ``t_s``): the
    rate magnitude, averaged over ``smooth_s``, above ``rate_threshold_deg_s`` is a turn;
    a quiet stretch of at least ``min_static_s`` is a static interval (shorter ones join
    the neighbouring turn), less ``margin_s`` at each end that borders a turn (a turn
    starts and ends below any threshold: the slow ends of its ramps, left in a static
    interval, would tilt the coarse alignment's gyrocompass by degrees). Each turn's axis
    and angle come from the product of its increments' rotations (IMU axes at its
    start)."""
    t = np.asarray(t_s, float)
    th = np.asarray(dtheta_rad, float)
    dt = np.diff(np.r_[t[0] - (t[1] - t[0]) if t.size > 1 else t[0] - 1.0, t])
    rate = np.linalg.norm(th, axis=1) / dt
    k = max(1, int(round(smooth_s / np.median(dt))))
    sm = np.convolve(rate, np.ones(k) / k, mode="same")
    moving = sm > np.radians(rate_threshold_deg_s)
    # runs of equal state
    edges = np.flatnonzero(np.diff(moving.astype(int))) + 1
    starts, ends = np.r_[0, edges], np.r_[edges, t.size]
    runs = [(bool(moving[a]), a, b) for a, b in zip(starts, ends)]
    # quiet runs lose the margin next to turns; short ones join the turns around them
    m = int(round(margin_s / np.median(dt)))
    trimmed = []
    for j, (mv, a, b) in enumerate(runs):
        if not mv:
            a2 = a + (m if j > 0 else 0)
            b2 = b - (m if j + 1 < len(runs) else 0)
            if b2 <= a2:
                trimmed.append((True, a, b))
                continue
            if a2 > a:
                trimmed.append((True, a, a2))
            trimmed.append((False, a2, b2))
            if b2 < b:
                trimmed.append((True, b2, b))
        else:
            trimmed.append((mv, a, b))
    runs = trimmed
    merged = []
    for mv, a, b in runs:
        quiet_short = (not mv) and (t[b - 1] - (t[a] - dt[a])) < min_static_s
        mv = mv or quiet_short
        if merged and merged[-1][0] == mv:
            merged[-1] = (mv, merged[-1][1], b)
        else:
            merged.append((mv, a, b))
    segs = []
    for mv, a, b in merged:
        t0 = float(t[a] - dt[a])
        if not mv:
            segs.append(Segment("static", a, b, t0, float(t[b - 1])))
            continue
        q = _composed_rotation(th[a:b])
        if q[0] < 0:
            q = -q
        ang = 2 * np.arctan2(np.linalg.norm(q[1:]), q[0])
        axis = q[1:] / max(np.linalg.norm(q[1:]), 1e-300)
        segs.append(Segment("turn", a, b, t0, float(t[b - 1]), tuple(axis), float(np.degrees(ang))))
    return segs



def check_record(t_end, dt, dth, dv, segs, lat_rad, h_m, min_align_s, max_angle_per_sample_rad,
                 gravity_m_s2: float | None = None, earth_rate: bool = True,
                 gyro_std_rad_s: float | None = None, checks: str = "raise"):
    """Units, sampling and rest: CalibrationInputError with what was found. ``gravity_m_s2``:
    the site's gravity (default WGS-84 normal gravity); ``earth_rate``: the gyros must see
    the Earth rate (the coarse alignment gyrocompasses; False when the heading is given).
    With ``gyro_std_rad_s`` (the gyros' bias 1-sigma, rad/s) and ``earth_rate``, the site
    latitude against the one the Earth rate gives in each static interval (their median;
    ``checks`` says whether a contradiction raises, warns or passes)."""
    if not (dt > 0).all():
        k = int(np.flatnonzero(~(dt > 0))[0])
        raise CalibrationInputError(f"sample times must increase: interval {k} is {float(dt[k])!r} s")
    stat = [s for s in segs if s.kind == "static"]
    if not stat:
        raise CalibrationInputError("the record has no static interval (rate below the threshold for "
                                    "at least min_static_s): the filter needs rest to align and to "
                                    "observe the sensors (is the turntable running all the time?)")
    if stat[0].duration_s < min_align_s:
        raise CalibrationInputError(f"the first static interval lasts {stat[0].duration_s:.1f} s; the "
                                    f"coarse alignment needs at least {min_align_s:g} s at rest "
                                    "(seed 001 rests 10 min)")
    sel = np.concatenate([np.arange(s.i0, s.i1) for s in stat])
    f = np.linalg.norm(dv[sel] / dt[sel, None], axis=1).mean()
    g = core_gravity_m_s2(lat_rad, h_m) if gravity_m_s2 is None else gravity_m_s2
    if abs(f / g - 1.0) > 0.05:
        hint = (" (dv looks like a specific force in m/s^2 rather than increments in m/s over "
                "each interval: build the record with kind='rates'; or the increments are in "
                "other units than m/s)" if abs(f * np.median(dt) / g - 1) < 0.05 else
                " (increments in cm/s or ft/s? accelerations in g?)" if f < 0.5 * g or f > 2 * g else
                " (a site far from where the record was made?)")
        raise CalibrationInputError(f"at rest the accelerometers read {f:.6g} m/s^2, but gravity at "
                                    f"the site is {g:.6g} m/s^2{hint}")
    w = np.linalg.norm(dth[sel] / dt[sel, None], axis=1).mean()
    W = WGS84.omega_ie
    if earth_rate and w > 30 * W:
        hint = " (are the gyro increments in degrees? np.radians)" if abs(w / (W * 180 / np.pi) - 1) < 0.5 else ""
        raise CalibrationInputError(f"at rest the gyros read {w:.3g} rad/s = {w / W:.1f} x the Earth "
                                    f"rate{hint}: the coarse alignment needs rad and a gyro that sees the "
                                    "Earth rate (for MEMS gyros give the start heading: heading_rad, "
                                    "--heading)")
    if earth_rate and gyro_std_rad_s is not None:
        lat_problem(t_end, dt, dth, dv, stat, lat_rad, gyro_std_rad_s, checks)
    worst = float(np.max(np.linalg.norm(dth, axis=1)))
    if worst > max_angle_per_sample_rad:
        k = int(np.argmax(np.linalg.norm(dth, axis=1)))
        raise CalibrationInputError(
            f"the IMU turns {np.degrees(worst):.3g} deg within one sample (sample {k}, t = "
            f"{t_end[k]:.6g} s): faster than the sample rate resolves (limit "
            f"{np.degrees(max_angle_per_sample_rad):.3g} deg per sample); record at a higher rate "
            "or turn slower")


def lat_problem(t_end, dt, dth, dv, stat, lat_rad, gyro_std_rad_s, checks) -> None:
    """The site latitude against the Earth rate the gyros measure at rest: per static
    interval the latitude of its mean rate and specific force
    (:func:`gfins_fmi.nav.plausibility.latitude_from_earth_rate`), the median over the
    intervals (the positions turn the gyro biases different ways), its 1-sigma that of one
    interval (bias and white noise over the interval); a given latitude more than 5 sigma
    and 2 deg from it is not where the record was made (before: accepted silently, and the
    calibration fitted the wrong Earth rate into the gyro errors, issue 21)."""
    lats, sig, means = [], [], []
    for s in stat:
        sl = slice(s.i0, s.i1)
        T = float(np.sum(dt[sl]))
        w = np.sum(dth[sl], axis=0) / T            # mean rate, rad/s
        f = np.sum(dv[sl], axis=0) / T             # mean specific force, m/s^2
        means.append((w, f))
        lats.append(latitude_from_earth_rate(w, f))
        noise = np.std(dth[sl] / dt[sl, None], axis=0).max() / np.sqrt(max(s.i1 - s.i0, 1))
        sig.append(float(np.hypot(gyro_std_rad_s, noise)))
    if not lats:
        return
    k = int(np.argsort(lats)[len(lats) // 2])
    report([latitude_problem(lat_rad, *means[k], sig[k], f"the record's static interval {k + 1} of "
                             f"{len(stat)} (t = {stat[k].t0_s:.6g} to {stat[k].t1_s:.6g} s)")],
           checks, error=CalibrationInputError, stacklevel=4)
