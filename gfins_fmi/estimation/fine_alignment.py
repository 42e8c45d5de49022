"""Alignment with the integrated-navigation filter: fine alignment at rest (zero velocity
and the known position, from a coarse start) and seed 003's in-motion alignment with a
speed sensor and forward-backward passes over the stored record (docs/alignment.md).
The analytic coarse alignments they start from are in :mod:`gfins_fmi.estimation.alignment`.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Optional

import numpy as np

from gfins_fmi._lib import as_scalar, lib
from gfins_fmi.estimation.alignment import AlignmentError, CoarseAlignment
from gfins_fmi.estimation.config import MEAS_TYPES, InitialState
from gfins_fmi.estimation.measurements import PASS_DTYPE
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.io.records import GnssRecord, ImuRecord
from gfins_fmi.nav.strapdown import NavState, euler_to_quat, quat_to_euler

__all__ = ["FineAlignment", "fine_align", "InMotionAlignment", "align_in_motion"]


@dataclass
class FineAlignment:
    """Result of :func:`fine_align`: the attitude at the end of the window (q_bn, euler),
    its 1-sigma (east, north, up tilt/heading, rad), the sensor-bias estimates and their
    1-sigma, and the filter's solution over the window."""
    q_bn: np.ndarray
    euler_rad: np.ndarray
    attitude_std_rad: np.ndarray
    sensors: np.ndarray
    sensor_std: np.ndarray
    solution: object


def fine_align(imu, lat_rad: float, lon_rad: float, h_m: float, *, config, coarse: CoarseAlignment,
               t0_s: Optional[float] = None, t1_s: Optional[float] = None, rate_hz: float = 10.0,
               velocity_std_m_s: float = 1e-3, position_std_m: float = 1e-3,
               heading_std_rad: Optional[float] = None, tilt_std_rad: float = np.radians(0.5),
               gyro_bias_std_rad_s: Optional[float] = None,
               accel_bias_std_m_s2: Optional[float] = None) -> FineAlignment:
    """Fine alignment at rest: the integrated-navigation filter (``config``, e.g. EKF with
    the IMU's noise model and random-constant biases) started from ``coarse`` and updated
    with zero velocity and the known position at ``rate_hz`` over the window.

    What it can reach (the physics of a static alignment): the horizontal accelerometer
    biases are indistinguishable from tilt (level error -> bias / g) and the east gyro bias
    from heading (heading error -> east bias / (Omega cos L)); the filter's attitude sigma
    settles at those limits, its estimates of the other biases improve.
    """
    t = np.asarray(imu.t_s)
    t0 = coarse.t_s[1] if t0_s is None else float(t0_s)
    t1 = t[-1] if t1_s is None else float(t1_s)
    sel = (t > t0) & (t <= t1)
    if np.count_nonzero(sel) < 2:
        raise AlignmentError(f"no IMU samples in the fine-alignment window ({t0:.10g}, {t1:.10g}] s")
    if not np.isfinite(coarse.euler_rad[0]) and heading_std_rad is None:
        raise AlignmentError("the coarse alignment has no heading: give heading_std_rad (and a "
                             "heading through coarse.euler_rad) or gyrocompass first")
    # before: rate_hz = 0 was a bare ZeroDivisionError and 1e9 Hz a 447 GiB MemoryError
    rate_hz = as_scalar("rate_hz", rate_hz, "Hz", above=0.0)
    imu_hz = 1.0 / float(np.median(np.diff(t[sel])))
    if rate_hz > imu_hz * (1.0 + 1e-9):
        raise ValueError(f"rate_hz = {rate_hz:g} Hz is above the IMU's sampling rate "
                         f"({imu_hz:.6g} Hz): a zero-velocity update comes at most once per IMU "
                         f"sample; give rate_hz <= {imu_hz:.6g} (10 Hz is the usual choice)")
    tg = np.arange(t0 + 1.0 / rate_hz, t1 + 1e-9, 1.0 / rate_hz)
    m = len(tg)
    zero = GnssRecord(t_s=tg, lat_rad=np.full(m, lat_rad), lon_rad=np.full(m, lon_rad),
                      h_m=np.full(m, h_m), pos_std_m=np.full((m, 3), position_std_m),
                      vel_enu_m_s=np.zeros((m, 3)), vel_std_m_s=np.full((m, 3), velocity_std_m_s),
                      source="fine alignment: at rest at a known position")
    # the coarse attitude errors ARE the biases seen through the same physics (tilt =
    # -bias/g, heading = -east gyro bias/(W cos L)): starting the filter with the coarse
    # sigmas as if independent of the bias sigmas would count that information twice and
    # make it overconfident; it starts instead from a wide attitude sigma (tilt_std_rad,
    # heading_std_rad) and learns the attitude from the window's data alone
    nav0 = NavState(euler_to_quat(coarse.euler_rad), np.zeros(3), lat_rad, lon_rad, h_m, t0)
    hstd = heading_std_rad if heading_std_rad is not None else max(10 * coarse.heading_std_rad, np.radians(1.0))
    init = InitialState(nav0, position_std_m=max(position_std_m, 1e-3), velocity_std_m_s=0.01,
                        attitude_std_rad=(tilt_std_rad, tilt_std_rad, hstd),
                        gyro_bias_std_rad_s=gyro_bias_std_rad_s, accel_bias_std_m_s2=accel_bias_std_m_s2)
    rec = ImuRecord(t_s=t[sel], gyro=np.asarray(imu.gyro)[sel], accel=np.asarray(imu.accel)[sel],
                    kind=imu.kind, source=getattr(imu, "source", ""))
    nav = IntegratedNavigator(config, init)
    sol = nav.run(rec, zero, gnss_velocity=True)
    P = nav.covariance
    return FineAlignment(sol.q_bn[-1].copy(), sol.euler_rad[-1].copy(), sol.std[-1, 6:9].copy(),
                         sol.sensors[-1].copy(), np.sqrt(np.diag(P)[9:15]), sol)


@dataclass
class InMotionAlignment:
    """Result of :func:`align_in_motion`.

    Attributes
    ----------
    t_s : time of the result (the record's last sample)
    q_bn, euler_rad : attitude at ``t_s`` (heading, pitch, roll; rad)
    attitude_std_rad : 1-sigma (east, north, up) of the attitude error, rad. After
        forward-backward passes the filter has used each datum 1 + 2 passes times, so this
        sigma is optimistic (docs/alignment.md): judge convergence on the pass history.
    covariance : the filter's error covariance at ``t_s``
    sensors : sensor-error estimates (``SENSOR_NAMES`` order)
    passes : structured array, one row per pass (direction +1/-1, t_s, q_bn, v_n_m_s,
        std9, sensors, n_updates, n_rejected)
    pass_euler_rad : (heading, pitch, roll) at the end of each pass
    innovations : the innovation log of all passes (``MEAS_TYPES``, ``UPDATE_STATUS``)
    navigator : the filter, forward at ``t_s``: ``navigator.run(rest_of_record, ...)``
        navigates on to the present
    rows : with ``keep_rows=True``, the solution of each pass (IntegratedSolution; rows
        of backward passes are in recorded order), else None
    converged : the alignment's own verdict: the heading sigma after the first forward
        pass (each datum used once) is below ``convergence_tol_rad`` and, with passes, the
        heading moved less than ``max(3 sigma, convergence_tol_rad)`` over the last
        forward-backward pass
    heading_change_rad : heading change between the last two forward passes (NaN with
        passes=0)
    notes : what was found (rejected speed updates, low speed, not converged)
    """
    t_s: float
    q_bn: np.ndarray
    euler_rad: np.ndarray
    attitude_std_rad: np.ndarray
    covariance: np.ndarray
    sensors: np.ndarray
    passes: np.ndarray
    pass_euler_rad: np.ndarray
    innovations: np.ndarray
    navigator: object
    rows: Optional[list]
    converged: bool
    heading_change_rad: float
    notes: list


def _time_slice(rec, lo: float, hi: float):
    """The rows of a measurement record with lo < t_s < hi (None stays None)."""
    if rec is None:
        return None
    t = np.asarray(rec.t_s, float)
    sel = (t > lo) & (t < hi)
    out = {}
    for k in ("t_s", "lat_rad", "lon_rad", "h_m", "pos_std_m", "vel_enu_m_s", "vel_std_m_s", "std_m",
              "speed_m_s", "std_m_s"):
        v = getattr(rec, k, None)
        if v is not None:
            out[k] = np.asarray(v)[sel]
    return SimpleNamespace(**out)


def align_in_motion(imu, speed, *, config, initial, depth=None, gnss=None, odometer=None,
                    passes: int = 0, keep_rows: bool = False, min_duration_s: float = 10.0,
                    max_rejected_fraction: float = 0.5, max_initial_heading_std_rad: float = np.radians(10.0),
                    convergence_tol_rad: float = np.radians(0.5), progress: bool = False) -> InMotionAlignment:
    """In-motion alignment with a speed sensor (seed 003): the integrated-navigation filter
    started from a coarse attitude (``initial``: its ``attitude_std_rad`` must cover the
    coarse heading error, its velocity the speed along that heading) and updated with the
    horizontal speed magnitude (``speed``: records with ``t_s``, ``speed_m_s``,
    ``std_m_s``; an ``OdometerRecord`` serves) and the depth (``depth``: a height record,
    ``BaroRecord`` with h_m = -depth), optionally GNSS/odometer; then ``passes``
    forward-backward passes over the same stored record (one C call for all of them, or
    one per pass with ``keep_rows=True``), ending forward at the record's last sample.

    Heading observability: the speed magnitude does not change when the velocity (and
    the INS with it) is rotated about the vertical, so the heading comes only from the
    Earth rate (gyrocompassing in motion: error -> east gyro bias / (Omega cos L), minutes
    of data with a navigation-grade gyro); the level errors come from the speed during
    turns and speed changes (a straight run at constant speed shows only the along-track
    tilt). See docs/alignment.md.

    Raises
    ------
    AlignmentError
        Latitude beyond 85 deg (no heading from the Earth rate), a record shorter than
        ``min_duration_s`` (too short for the requested passes), a filter start after the
        record's first sample, or a speed sensor that disagrees grossly with the INS (more
        than ``max_rejected_fraction`` of its updates gated out in the last pass), an
        initial heading sigma above ``max_initial_heading_std_rad`` (the EKF's small-angle
        error model: measured with 300 s and 5 passes, a 30 deg start left heading errors of
        10-30 deg in some runs that were not refused; docs/alignment.md).

    The result's ``converged`` flag and notes report an alignment that has not settled
    (e.g. seed 003's 30 s): check it before navigating on.
    """
    nav0 = initial.nav
    if not abs(nav0.lat_rad) < np.radians(85.0):
        raise AlignmentError(f"latitude {np.degrees(nav0.lat_rad):.4g} deg: beyond 85 deg the Earth rate is "
                             "nearly vertical and gives no heading; in-motion alignment from a speed "
                             "sensor needs it (use a heading reference: GNSS velocity, a compass)")
    if isinstance(passes, bool) or not isinstance(passes, (int, np.integer)) or passes < 0:
        raise AlignmentError(f"passes must be an integer >= 0 (forward-backward passes); got {passes!r}")
    att_std = np.broadcast_to(np.asarray(initial.attitude_std_rad, float), (3,))
    if not att_std[2] <= max_initial_heading_std_rad:
        raise AlignmentError(f"initial heading sigma {np.degrees(att_std[2]):.3g} deg is above "
                             f"{np.degrees(max_initial_heading_std_rad):.3g} deg: the filter's small-angle error "
                             "model needs a coarse heading (a compass, a previous alignment) within a few "
                             "degrees; the speed magnitude cannot find an unknown heading")
    if speed is None or len(np.asarray(speed.t_s)) == 0:
        raise AlignmentError("align_in_motion needs a speed record (tachometer/odometer speeds)")
    t = np.asarray(imu.t_s, float)
    if len(t) < 2:
        raise AlignmentError(f"the IMU record holds {len(t)} samples; an alignment needs a stored period")
    if not nav0.t_s < t[0] + (1e-9 if getattr(imu, "kind", "increments") == "rates" else 0.0):
        raise AlignmentError(f"the initial state (t = {float(nav0.t_s)!r} s) must be at the start of the record's "
                             f"first interval, before its first sample ({float(t[0])!r} s)")
    span = float(t[-1] - nav0.t_s)
    if span < min_duration_s:
        raise AlignmentError(f"the alignment record spans {span:.3g} s, shorter than min_duration_s = "
                             f"{min_duration_s} s: too short for {passes} forward-backward pass(es) to "
                             "converge (seed 003: 30 s do not, 200-300 s do); store a longer period")
    ts = np.asarray(speed.t_s, float)
    if not np.any((ts > nav0.t_s) & (ts <= t[-1])):
        raise AlignmentError(f"no speed measurement inside the record ({nav0.t_s}, {t[-1]}] s: check the time "
                             "scales")
    nav = IntegratedNavigator(config, initial)
    notes = []
    rows = None
    t0, t1 = float(nav0.t_s), float(t[-1])
    recs = dict(gnss=gnss, baro=depth, odometer=odometer, speed=speed)
    if not keep_rows:
        if progress:
            print(f"align_in_motion: {1 + 2 * passes} passes over {span:.1f} s of data (one C call)")
        table, inn = nav.forward_backward(imu, passes, gnss, depth, odometer, speed=speed)
    else:
        rows, logs = [], []
        table = np.zeros(1 + 2 * passes, PASS_DTYPE)
        inside = {k: _time_slice(v, t0 - 1.0, t1 + 1e-9) for k, v in recs.items()}
        after_start = {k: _time_slice(v, t0 + 1e-9, t1 + 1e-9) for k, v in recs.items()}
        before_end = {k: _time_slice(v, t0 - 1e-9, t1 - 1e-9) for k, v in recs.items()}
        bar = None
        if progress:
            from tqdm import tqdm   # lazy: only with a progress bar
            bar = tqdm(total=1 + 2 * passes, unit="pass", desc="alignment passes")
        try:
            for p in range(1 + 2 * passes):
                c0 = nav.counts
                if p % 2 == 1:
                    nav.reverse()
                    sol = nav.run_backward(imu, t0, before_end["gnss"], before_end["baro"],
                                           before_end["odometer"], speed=before_end["speed"])
                else:
                    if p > 0:
                        nav.reverse()
                    m = inside if p == 0 else after_start
                    sol = nav.run(imu, m["gnss"], m["baro"], m["odometer"], speed=m["speed"])
                rows.append(sol)
                logs.append(sol.innovations)
                k = int(np.argmin(sol.t_s)) if p % 2 == 1 else len(sol) - 1
                c1 = nav.counts
                table[p] = (1 if p % 2 == 0 else -1, nav.t_s, sol.q_bn[k], sol.v_n_m_s[k], sol.std[k],
                            sol.sensors[k], c1["updates"] - c0["updates"], c1["rejected"] - c0["rejected"])
                if bar:
                    bar.update(1)
        finally:
            if bar:
                bar.close()
        inn = np.concatenate(logs)
    # the speed sensor against the INS in the last pass
    last = int(table["n_updates"][-1] + table["n_rejected"][-1])
    tail = inn[len(inn) - last:] if last else inn[:0]
    code = {v: k for k, v in MEAS_TYPES.items()}["speed"]
    sp = tail[tail["type"] == code]
    if len(sp):
        gated = np.count_nonzero(sp["status"] == lib.GF_INS_REJECTED_GATE)
        low = np.count_nonzero(sp["status"] == lib.GF_INS_REJECTED_LOW_SPEED)
        if gated > max_rejected_fraction * len(sp):
            raise AlignmentError(f"the speed sensor disagrees with the INS: {gated} of {len(sp)} speed updates of "
                                 f"the last pass were rejected by the innovation gate (median |innovation| "
                                 f"{np.nanmedian(np.abs(sp['r'][:, 0])):.3g} m/s); check the speed record's "
                                 "units, scale (FilterConfig(odometer_scale=True) estimates a scale error) and "
                                 "std, and the initial velocity and heading")
        if gated:
            notes.append(f"{gated} of {len(sp)} speed updates of the last pass rejected by the gate")
        if low:
            notes.append(f"{low} of {len(sp)} speed updates of the last pass refused below "
                         f"{config.speed_min_m_s} m/s")
    q = table["q_bn"][-1].copy()
    pe = quat_to_euler(table["q_bn"])
    # the first forward pass is the honest one (each datum used once): its heading sigma
    # judges whether the data hold the heading at all; passes over too short a record
    # settle on a wrong fixed point with a small sigma (seed 003's 30 s, measured)
    hstd1, hstd = float(table["std9"][0, 8]), float(table["std9"][-1, 8])
    converged = hstd1 <= convergence_tol_rad
    dpsi = float("nan")
    if passes > 0:
        dpsi = float((pe[-1, 0] - pe[-3, 0] + np.pi) % (2 * np.pi) - np.pi)
        converged &= abs(dpsi) <= max(3 * hstd, convergence_tol_rad)
    if not converged:
        notes.append(f"NOT CONVERGED: heading sigma after the first forward pass {np.degrees(hstd1):.3g} deg "
                     f"(limit {np.degrees(convergence_tol_rad):.3g} deg)" +
                     (f", heading moved {np.degrees(dpsi):.3g} deg over the last forward-backward pass"
                      if passes > 0 else "") + "; store a longer period with turns (passes reuse the same data "
                     "and cannot make up for it)")
    return InMotionAlignment(t_s=float(table["t_s"][-1]), q_bn=q, euler_rad=quat_to_euler(q),
                             attitude_std_rad=table["std9"][-1, 6:9].copy(), covariance=nav.covariance,
                             sensors=table["sensors"][-1].copy(), passes=table, pass_euler_rad=pe,
                             innovations=inn, navigator=nav, rows=rows, converged=bool(converged),
                             heading_change_rad=dpsi, notes=notes)
