"""Initialisation of the integrated-navigation filter (issue 11, item 5): coarse alignment
at standstill — levelling from the accelerometers, heading by gyrocompassing when the
gyros can see the Earth's rotation — or the heading from GNSS velocity once moving.

Which applies when (see docs/estimation.md):

* levelling needs ~1 s at rest with any IMU: tilt error ~ accelerometer bias / g
  (100 ug -> 0.006 deg);
* gyrocompassing needs gyro bias << Earth rate x cos(latitude) (15 deg/h at the equator):
  heading error ~ gyro bias / (Omega cos L), e.g. 0.01 deg/h -> 0.06 deg at 30 deg, 1 deg/h ->
  4.4 deg; consumer MEMS gyros (tens to thousands of deg/h) cannot, and the heading comes
  from GNSS velocity (the direction of travel of a vehicle, or of a walker holding the
  device pointing forward) once the speed is well above the velocity noise;
* near the poles (|lat| > 85 deg) the Earth rate is vertical and gives no heading;
* in motion, with a speed sensor (seed 003's tachometer, :func:`align_in_motion`): levels
  from the speed during manoeuvres, heading only by gyrocompassing in motion (the speed
  magnitude is blind to a rotation of the velocity about the vertical), so it needs the
  same gyro quality and minutes of data; forward-backward passes over the stored period
  reuse the data (docs/alignment.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from gfins_fmi.nav.earth import WGS84
from gfins_fmi.nav.plausibility import latitude_problem, report
from gfins_fmi.nav.strapdown import NavState, SinsConfig, Strapdown, euler_to_quat, quat_to_euler

__all__ = ["CoarseAlignment", "coarse_align", "coarse_align_inertial", "attitude_from_gravity_and_earth_rate",
           "heading_from_gnss", "AlignmentError", "StartingPoint", "align_static_then_gnss"]

_OMEGA = WGS84.omega_ie


class AlignmentError(ValueError):
    """The data cannot give the requested alignment (motion at 'standstill', too short,
    near the poles); the message says why and what to do."""


@dataclass
class CoarseAlignment:
    """Result of :func:`coarse_align`.

    Attributes
    ----------
    euler_rad : (heading, pitch, roll), rad; heading NaN when not determined
    tilt_std_rad : 1-sigma of pitch and roll from the accelerometer bias
    heading_std_rad : 1-sigma of the heading (NaN when not determined)
    heading_method : "gyrocompass" or "none"
    t_s : (start, end) of the window used
    f_mean_m_s2, w_mean_rad_s : mean specific force and rate over the window (body)
    notes : what was found (motion, gyro too poor, ...)
    """
    euler_rad: np.ndarray
    tilt_std_rad: float
    heading_std_rad: float
    heading_method: str
    t_s: tuple
    f_mean_m_s2: np.ndarray
    w_mean_rad_s: np.ndarray
    notes: list = field(default_factory=list)

    def quaternion(self, heading_rad: Optional[float] = None) -> np.ndarray:
        """q_b^n of the alignment (heading replaced by ``heading_rad`` if given)."""
        e = self.euler_rad.copy()
        if heading_rad is not None:
            e[0] = heading_rad
        if not np.isfinite(e[0]):
            raise AlignmentError("the heading is not determined: give heading_rad (e.g. from "
                                 "heading_from_gnss) or use an IMU that can gyrocompass")
        return euler_to_quat(e)


def _window_means(imu, t0, t1):
    t = np.asarray(imu.t_s)
    sel = (t > t0) & (t <= t1)
    if np.count_nonzero(sel) < 10:
        raise AlignmentError(f"the window ({float(t0):.10g}, {float(t1):.10g}] s holds {np.count_nonzero(sel)} IMU samples; "
                             "an alignment needs at least 10 (and ~1 s or more)")
    g, a = np.asarray(imu.gyro)[sel], np.asarray(imu.accel)[sel]
    if imu.kind == "increments":
        i0 = int(np.flatnonzero(sel)[0])
        if i0 > 0:
            prev = t[i0 - 1]
        else:
            # the record's first increment: its interval starts at the window's start only
            # if that is about one interval before it; otherwise (a window opened just
            # before the first sample, `gfins align static` without --window) the typical
            # interval. Before: dt = 1e-9 s there, |f| = 1e6 m/s^2, and the window was
            # refused as "motion during the static alignment window" (issue 21)
            typical = float(np.median(np.diff(t[sel])))
            prev = t0 if abs(t[i0] - t0 - typical) <= 0.5 * typical else t[i0] - typical
        dt = np.diff(np.r_[prev, t[sel]])
        w, f = g / dt[:, None], a / dt[:, None]
    else:
        w, f = g, a
    return w, f


def coarse_align(imu, t0_s: float, t1_s: float, lat_rad: float, *, gyro_bias_std_rad_s: float = 0.0,
                 accel_bias_std_m_s2: float = 1e-3, max_accel_std_m_s2: float = 0.2,
                 max_rate_rad_s: float = 0.05, max_heading_std_rad: float = np.radians(10.0),
                 checks: str = "raise") -> CoarseAlignment:
    """Analytic coarse alignment over the window (t0_s, t1_s] of an IMU record at rest.

    Levelling: the mean specific force f is the up axis in body coordinates, so pitch =
    asin(f_y / |f|), roll = atan2(-f_x, f_z) (C_b^n = Rz(-heading) Rx(pitch) Ry(roll)).
    Gyrocompassing: the mean rate rotated to the level frame is the Earth rate, [-W cos L
    sin(heading), W cos L cos(heading), W sin L], so heading = atan2(-w_x, w_y); its error
    is ~ gyro bias / (W cos L), and the heading is kept only below ``max_heading_std_rad``.

    Motion in the window (std of |f| above ``max_accel_std_m_s2`` or mean |w| above
    ``max_rate_rad_s``) raises :class:`AlignmentError`.

    ``checks``: with ``gyro_bias_std_rad_s`` > 0 (gyros good enough to gyrocompass), a
    ``lat_rad`` that the Earth rate measured in the window contradicts (more than 5 sigma
    and 2 deg away: :func:`gfins_fmi.nav.plausibility.latitude_problem`) raises
    :class:`AlignmentError` (``"raise"``), warns (``"warn"``) or passes (``"off"``).
    """
    if not abs(lat_rad) < np.pi / 2:
        raise AlignmentError("lat_rad must be inside (-90, 90) deg")
    w, f = _window_means(imu, t0_s, t1_s)
    fn = np.linalg.norm(f, axis=1)
    notes = []
    if fn.std() > max_accel_std_m_s2 or np.linalg.norm(w, axis=1).mean() > max_rate_rad_s:
        raise AlignmentError(f"motion during the static alignment window ({float(t0_s):.10g}, {float(t1_s):.10g}] s: std of |f| "
                             f"{fn.std():.3g} m/s^2 (limit {max_accel_std_m_s2}), mean |w| "
                             f"{np.linalg.norm(w, axis=1).mean():.3g} rad/s (limit {max_rate_rad_s}); "
                             "choose a window at rest")
    fm, wm = f.mean(axis=0), w.mean(axis=0)
    u = fm / np.linalg.norm(fm)
    pitch = float(np.arcsin(np.clip(u[1], -1.0, 1.0)))
    roll = float(np.arctan2(-u[0], u[2]))
    # body -> level frame (heading 0): C_tilt = Rx(pitch) Ry(roll)
    cp, sp, cr, sr = np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    Rx = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
    Ry = np.array([[cr, 0, sr], [0, 1, 0], [-sr, 0, cr]])
    wl = Rx @ Ry @ wm
    horiz = _OMEGA * np.cos(lat_rad)
    heading, hstd, method = np.nan, np.nan, "none"
    if abs(lat_rad) > np.radians(85.0):
        notes.append("latitude beyond 85 deg: the Earth rate is nearly vertical, no gyrocompass heading")
    else:
        noise = np.linalg.norm(w - wm, axis=1).std() / np.sqrt(len(w))
        sd = np.hypot(gyro_bias_std_rad_s, noise) / horiz
        if gyro_bias_std_rad_s > 0:   # the latitude given against the one the gyros measure
            report([latitude_problem(lat_rad, wm, fm, float(np.hypot(gyro_bias_std_rad_s, noise)),
                                     f"the window ({float(t0_s):.10g}, {float(t1_s):.10g}] s at rest")],
                   checks, error=AlignmentError, stacklevel=3)
        if sd <= max_heading_std_rad:
            heading = float(np.arctan2(-wl[0], wl[1]) % (2 * np.pi))
            hstd, method = float(sd), "gyrocompass"
        else:
            notes.append(f"gyrocompassing would give a heading sigma of {np.degrees(sd):.3g} deg (gyro bias "
                         f"{np.degrees(gyro_bias_std_rad_s) * 3600:.3g} deg/h against an Earth rate of "
                         f"{np.degrees(horiz) * 3600:.3g} deg/h here): heading left undetermined")
    tilt_std = float(accel_bias_std_m_s2 / np.linalg.norm(fm))
    return CoarseAlignment(np.array([heading, pitch, roll]), tilt_std, hstd, method, (t0_s, t1_s), fm, wm,
                           notes)


def coarse_align_inertial(imu, t0_s: float, t1_s: float, lat_rad: float, *,
                          gyro_bias_std_rad_s: float = 0.0, accel_bias_std_m_s2: float = 1e-3,
                          n_vectors: int = 20, min_duration_s: float = 30.0, max_misfit_rad: float = 5e-3,
                          max_heading_std_rad: float = np.radians(10.0)) -> CoarseAlignment:
    """Coarse alignment on a disturbed base (a moored ship, a vehicle with its engine
    running, people walking on a platform): the inertial-frame method.

    At rest on a swaying base the mean rate is dominated by the sway, not the Earth rate,
    and gyrocompassing fails. Here the gyros integrate the body's attitude relative to the
    inertial frame it had at ``t0_s`` (ib0), and the specific force is integrated in that
    frame: V^ib0(t) = int C_b^ib0 f^b dt (the strapdown mechanization, fixed frame, no
    gravity: one C call). In the frame i0 = the navigation frame at t0, frozen in inertial
    space, the same integral of gravity's reaction is a closed form — the up axis turns
    about the Earth's axis u = [0, cos L, sin L] at the Earth rate W:

        V^i0(t) = g [ p sin(W t) / W + (u x p)(1 - cos(W t)) / W + (u . e_U) u t ],
        p = e_U - (u . e_U) u

    while the sway's accelerations integrate to its bounded velocity. The rotation
    C_ib0^i0 that best maps the directions of the V^ib0 onto those of the V^i0 at
    ``n_vectors`` times of the second half of the window (Wahba's problem,
    ``scipy.spatial.transform.Rotation.align_vectors``; directions only, so g drops out)
    gives the attitude at the window's end, C_b^n(t1) = C_i0^n(t1) C_ib0^i0 C_b^ib0(t1),
    C_i0^n(t1) = R(u, W t1)^T.

    Errors: the heading comes from the turn of the up axis (W T cos L rad over the window),
    so the window must be long enough for the sway's velocity to be small against it:
    heading ~ v_sway / (g T) / (W T cos L) (e.g. 0.15 m/s of sway over 300 s at 30 deg: a
    few mrad); the gyro bias gives ~ bias / (W cos L) as in gyrocompassing, the tilt
    ~ accelerometer bias / g.

    Returns a :class:`CoarseAlignment` whose attitude is that at ``t1_s`` (the base moves:
    the start of navigation), ``heading_method`` "inertial frame" — or "none" with the
    heading NaN when its 1-sigma (from the gyro bias and the fit's misfit) exceeds
    ``max_heading_std_rad``.

    Raises
    ------
    AlignmentError
        A window shorter than ``min_duration_s`` or holding too few samples, a latitude
        beyond 85 deg (the Earth rate turns the up axis about itself: no heading), or a
        window in which the base is not at rest on average (the directions of the
        integrated specific force miss gravity's closed form by more than
        ``max_misfit_rad``: measured 6e-5-3e-4 rad on a moored ship, 0.02 rad on a car
        driving a 100 m circle).
    """
    from scipy.spatial.transform import Rotation   # lazy: scipy's import costs start-up time
    if not abs(lat_rad) <= np.radians(85.0):
        raise AlignmentError(f"latitude {np.degrees(lat_rad):.3g} deg: beyond 85 deg the Earth rate is "
                             "nearly vertical and gives no heading")
    if not (t1_s - t0_s >= min_duration_s):
        raise AlignmentError(f"the window ({t0_s}, {t1_s}] s is shorter than {min_duration_s} s: the "
                             "inertial-frame alignment needs the Earth to turn the up axis (use 60-300 s)")
    if not (isinstance(n_vectors, (int, np.integer)) and n_vectors >= 2):
        raise ValueError(f"n_vectors must be an integer >= 2, got {n_vectors!r}")
    t = np.asarray(imu.t_s)
    idx = np.flatnonzero((t > t0_s) & (t <= t1_s))
    if idx.size < 10 * n_vectors:
        raise AlignmentError(f"the window ({t0_s}, {t1_s}] s holds {idx.size} IMU samples; the "
                             f"inertial-frame alignment needs at least {10 * n_vectors}")
    w, f = _window_means(imu, t0_s, t1_s)
    t_start = float(t[idx[0] - 1]) if idx[0] > 0 else float(t0_s)
    x0 = NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), 0.0, 0.0, 0.0, t_start, np.zeros(3))
    sol = Strapdown(x0, SinsConfig(input=imu.kind, earth="flat", flat_gravity_m_s2=0.0)).run(
        np.asarray(imu.gyro)[idx], np.asarray(imu.accel)[idx], t_s=t[idx])
    tau = sol.t_s - t_start
    T = float(tau[-1])
    pick = np.unique(np.searchsorted(tau, np.linspace(0.5 * T, T, n_vectors)).clip(0, len(tau) - 1))
    u = np.array([0.0, np.cos(lat_rad), np.sin(lat_rad)])
    up = np.array([0.0, 0.0, 1.0])
    p = up - u[2] * u
    wt = _OMEGA * tau[pick][:, None]
    V_i = (np.sin(wt) / _OMEGA * p + (1.0 - np.cos(wt)) / _OMEGA * np.cross(u, p) + u[2] * u * tau[pick][:, None])
    V_b = sol.v_n_m_s[pick]
    # directions only: g (and an accelerometer scale error) drops out, and the mean |f| of
    # a swaying body is not g (the sway turns f in body axes: 0.25 % for 5 deg of roll)
    V_i /= np.linalg.norm(V_i, axis=1)[:, None]
    V_b = V_b / np.linalg.norm(V_b, axis=1)[:, None]
    R, rssd = Rotation.align_vectors(V_i, V_b)            # V_i ~ C_ib0^i0 V_b
    resid = float(rssd) / np.sqrt(len(pick))              # rms angle between fitted directions, rad
    if not resid < max_misfit_rad:
        raise AlignmentError(f"the specific force integrated over ({t0_s}, {t1_s}] s does not follow "
                             f"gravity's (rms misfit {resid:.3g} rad): the base is moving, not "
                             "swaying about a fixed point; use an in-motion alignment (align_in_motion)")
    q_b_ib0 = sol.q_bn[-1]
    C_b_ib0 = Rotation.from_quat([q_b_ib0[1], q_b_ib0[2], q_b_ib0[3], q_b_ib0[0]])
    C_i0_n = Rotation.from_rotvec(u * _OMEGA * T).inv()
    qx = (C_i0_n * R * C_b_ib0).as_quat()
    euler = quat_to_euler(np.array([qx[3], qx[0], qx[1], qx[2]]))
    g = float(np.linalg.norm(f.mean(axis=0)))
    horiz = _OMEGA * np.cos(lat_rad)
    notes = [f"attitude at the end of the window, t = {float(sol.t_s[-1])} s (the base moves)",
             f"rms misfit of the fitted directions {resid:.2g} rad"]
    # 1-sigma estimates: the directions' misfit is the sway's share of the vectors; the
    # heading sees it divided by the turn of the up axis over the window's second half
    tilt_std = float(np.hypot(accel_bias_std_m_s2 / g, resid))
    heading_std = float(np.hypot(gyro_bias_std_rad_s / horiz, resid / (0.5 * _OMEGA * T * np.cos(lat_rad))))
    euler = np.asarray(euler, float)
    method = "inertial frame"
    if not heading_std <= max_heading_std_rad:
        notes.append(f"heading sigma {np.degrees(heading_std):.3g} deg above {np.degrees(max_heading_std_rad):.3g} "
                     "deg: heading left undetermined (a longer window, a quieter base or better gyros)")
        euler[0], heading_std, method = np.nan, np.nan, "none"
    return CoarseAlignment(euler, tilt_std, heading_std, method, (t0_s, t1_s), f.mean(axis=0), w.mean(axis=0),
                           notes)


def attitude_from_gravity_and_earth_rate(f_mean_m_s2, w_mean_rad_s) -> np.ndarray:
    """Coarse attitude q_b^n at rest for ANY orientation of the body (no Euler angles, so
    no singularity with an axis vertical: the positions of a calibration path): the mean
    specific force is Up and the mean rate x specific force is East in body axes (TRIAD
    on gravity and the Earth rate), C_n^b = [E, N = U x E, U]. Needs a gyro that sees the
    Earth rate (bias << W cos L) and |lat| < 85 deg.

    Raises
    ------
    AlignmentError
        The rate is (anti)parallel to the specific force (at a pole or without Earth rate).
    """
    f = np.asarray(f_mean_m_s2, float)
    w = np.asarray(w_mean_rad_s, float)
    u = f / np.linalg.norm(f)
    e = np.cross(w, f)
    if not np.linalg.norm(e) > 1e-3 * np.linalg.norm(w) * np.linalg.norm(f):
        raise AlignmentError("the mean rate is parallel to the specific force: no heading from "
                             "gyrocompassing (near a pole, or the gyros do not see the Earth rate)")
    e /= np.linalg.norm(e)
    nn = np.cross(u, e)
    C_bn = np.array([e, nn, u])                     # rows: E, N, U in body axes = C_b^n
    from scipy.spatial.transform import Rotation   # lazy: scipy's import costs start-up time
    q = Rotation.from_matrix(C_bn).as_quat()        # x, y, z, w
    return np.array([q[3], q[0], q[1], q[2]])


def heading_from_gnss(gnss, min_speed_m_s: float = 1.0, t_from_s: Optional[float] = None):
    """The direction of travel (heading of the horizontal velocity, clockwise from north,
    rad) at the first GNSS epoch (at or after ``t_from_s``) whose horizontal speed exceeds
    ``min_speed_m_s``, with its 1-sigma (velocity noise / speed) and the epoch's time.
    Returns (t_s, heading_rad, std_rad). Raises AlignmentError if the speed never
    exceeds the threshold or the record has no velocity."""
    v = getattr(gnss, "vel_enu_m_s", None)
    if v is None:
        raise AlignmentError("the GNSS record has no velocity: a heading from GNSS needs it")
    v = np.asarray(v)
    t = np.asarray(gnss.t_s)
    sp = np.hypot(v[:, 0], v[:, 1])
    ok = sp > min_speed_m_s
    if t_from_s is not None:
        ok &= t >= t_from_s
    if not np.any(ok):
        raise AlignmentError(f"the horizontal GNSS speed never exceeds {min_speed_m_s} m/s: no heading "
                             "from the direction of travel")
    k = int(np.flatnonzero(ok)[0])
    vs = getattr(gnss, "vel_std_m_s", None)
    sv = float(np.hypot(*np.asarray(vs)[k, :2]) / np.sqrt(2)) if vs is not None else 0.1
    return float(t[k]), float(np.arctan2(v[k, 0], v[k, 1]) % (2 * np.pi)), float(sv / sp[k])


@dataclass
class StartingPoint:
    """What a filter run needs at its start (see :func:`align_static_then_gnss`):
    ``nav`` (NavState at ``nav.t_s``), the attitude 1-sigma (east, north, up; rad),
    initial sensor estimates (``gfins_fmi.estimation.SENSOR_NAMES`` order) and notes."""
    nav: NavState
    attitude_std_rad: np.ndarray
    sensors: np.ndarray
    alignment: CoarseAlignment
    notes: list


def align_static_then_gnss(imu, gnss, static_window_s: tuple, *, min_speed_m_s: float = 1.0,
                           gyro_bias_std_rad_s: float = 0.0, accel_bias_std_m_s2: float = 1e-3,
                           travel_misalignment_rad: float = np.radians(10.0),
                           **coarse_kw) -> StartingPoint:
    """The start of a filter run from a record that begins at rest: levelling (and, if
    the gyros allow, gyrocompassing) over ``static_window_s``; otherwise the heading from
    the direction of travel at the first GNSS epoch faster than ``min_speed_m_s``, carried
    back to the start through the gyros (mechanized from the static window with the rate
    measured at rest removed as gyro bias). The body's forward axis (y) is taken to point
    along the travel, within ``travel_misalignment_rad`` (1 sigma).

    The state is placed at the end of the static window, at rest, at the GNSS position
    interpolated there (the GNSS antenna; give the lever arm to the filter).
    """
    t0, t1 = static_window_s
    tg = np.asarray(gnss.t_s)
    if not (tg[0] <= t1 <= tg[-1]):
        raise AlignmentError(f"the GNSS record ([{tg[0]}, {tg[-1]}] s) does not cover the end of the "
                             f"static window {t1} s: check the time scales")
    lat = float(np.interp(t1, tg, gnss.lat_rad))
    lon = float(np.interp(t1, tg, np.unwrap(gnss.lon_rad)))
    h = float(np.interp(t1, tg, gnss.h_m))
    al = coarse_align(imu, t0, t1, lat, gyro_bias_std_rad_s=gyro_bias_std_rad_s,
                      accel_bias_std_m_s2=accel_bias_std_m_s2, **coarse_kw)
    notes = list(al.notes)
    sensors = np.zeros(16)
    if al.heading_method == "gyrocompass":
        heading, hstd = al.euler_rad[0], al.heading_std_rad
        notes.append(f"heading by gyrocompassing: {np.degrees(heading):.2f} +- {np.degrees(hstd):.2f} deg")
    else:
        # the rate at rest is the gyro bias (the Earth rate, below the bias here, is left in)
        sensors[0:3] = al.w_mean_rad_s
        t_h, psi_gnss, s_gnss = heading_from_gnss(gnss, min_speed_m_s, t_from_s=t1)
        t = np.asarray(imu.t_s)
        sel = (t > t1) & (t <= t_h)
        if not np.any(sel):
            raise AlignmentError(f"no IMU sample between the static window's end ({t1} s) and the first "
                                 f"GNSS epoch above {min_speed_m_s} m/s ({t_h} s)")
        cfg = SinsConfig(input=imu.kind, vertical="hold", hold_height_m=h)
        start = NavState(euler_to_quat(np.array([0.0, al.euler_rad[1], al.euler_rad[2]])), np.zeros(3),
                         lat, lon, h, t1)
        g = np.asarray(imu.gyro)[sel] - (sensors[0:3] if imu.kind == "rates" else
                                        sensors[0:3] * np.diff(np.r_[t1, t[sel]])[:, None])
        nav = Strapdown(start, cfg).run(g, np.asarray(imu.accel)[sel], t_s=t[sel])
        psi_body = quat_to_euler(nav.q_bn[-1])[0]
        heading = float((psi_gnss - psi_body) % (2 * np.pi))
        drift = gyro_bias_std_rad_s * (t_h - t1)
        hstd = float(np.sqrt(s_gnss ** 2 + travel_misalignment_rad ** 2 + drift ** 2))
        notes.append(f"heading from GNSS velocity at {t_h:.2f} s ({np.degrees(psi_gnss):.1f} deg travel), "
                     f"carried back {t_h - t1:.1f} s by the gyros: {np.degrees(heading):.1f} +- "
                     f"{np.degrees(hstd):.1f} deg at the start")
    q = euler_to_quat(np.array([heading, al.euler_rad[1], al.euler_rad[2]]))
    nav0 = NavState(q, np.zeros(3), lat, lon, h, t1)
    return StartingPoint(nav0, np.array([al.tilt_std_rad, al.tilt_std_rad, hstd]), sensors, al, notes)
