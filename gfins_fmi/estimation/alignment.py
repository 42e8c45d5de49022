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

from gfins_fmi.sins import NavState, euler_to_quat, quat_to_euler

__all__ = ["CoarseAlignment", "coarse_align", "coarse_align_inertial", "attitude_from_gravity_and_earth_rate", "heading_from_gnss",
           "AlignmentError", "StartingPoint", "align_static_then_gnss", "FineAlignment", "fine_align",
           "InMotionAlignment", "align_in_motion"]

_OMEGA = 7.292115e-5


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
        raise AlignmentError(f"the window ({t0}, {t1}] s holds {np.count_nonzero(sel)} IMU samples; "
                             "an alignment needs at least 10 (and ~1 s or more)")
    g, a = np.asarray(imu.gyro)[sel], np.asarray(imu.accel)[sel]
    if imu.kind == "increments":
        dt = np.diff(np.r_[t[np.flatnonzero(sel)[0] - 1] if np.flatnonzero(sel)[0] > 0 else t0, t[sel]])
        w, f = g / dt[:, None], a / dt[:, None]
    else:
        w, f = g, a
    return w, f


def coarse_align(imu, t0_s: float, t1_s: float, lat_rad: float, *, gyro_bias_std_rad_s: float = 0.0,
                 accel_bias_std_m_s2: float = 1e-3, max_accel_std_m_s2: float = 0.2,
                 max_rate_rad_s: float = 0.05, max_heading_std_rad: float = np.radians(10.0)) -> CoarseAlignment:
    """Analytic coarse alignment over the window (t0_s, t1_s] of an IMU record at rest.

    Levelling: the mean specific force f is the up axis in body coordinates, so pitch =
    asin(f_y / |f|), roll = atan2(-f_x, f_z) (C_b^n = Rz(-heading) Rx(pitch) Ry(roll)).
    Gyrocompassing: the mean rate rotated to the level frame is the Earth rate, [-W cos L
    sin(heading), W cos L cos(heading), W sin L], so heading = atan2(-w_x, w_y); its error
    is ~ gyro bias / (W cos L), and the heading is kept only below ``max_heading_std_rad``.

    Motion in the window (std of |f| above ``max_accel_std_m_s2`` or mean |w| above
    ``max_rate_rad_s``) raises :class:`AlignmentError`.
    """
    if not abs(lat_rad) < np.pi / 2:
        raise AlignmentError("lat_rad must be inside (-90, 90) deg")
    w, f = _window_means(imu, t0_s, t1_s)
    fn = np.linalg.norm(f, axis=1)
    notes = []
    if fn.std() > max_accel_std_m_s2 or np.linalg.norm(w, axis=1).mean() > max_rate_rad_s:
        raise AlignmentError(f"motion during the static alignment window ({t0_s}, {t1_s}] s: std of |f| "
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
    from scipy.spatial.transform import Rotation

    from gfins_fmi.sins import SinsConfig, Strapdown
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
    from scipy.spatial.transform import Rotation
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
    from gfins_fmi.sins import SinsConfig, Strapdown, quat_to_euler
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
    from gfins_fmi.estimation.ins_gnss import InitialState, IntegratedNavigator
    from gfins_fmi.io.records import GnssRecord, ImuRecord
    t = np.asarray(imu.t_s)
    t0 = coarse.t_s[1] if t0_s is None else float(t0_s)
    t1 = t[-1] if t1_s is None else float(t1_s)
    sel = (t > t0) & (t <= t1)
    if np.count_nonzero(sel) < 2:
        raise AlignmentError(f"no IMU samples in the fine-alignment window ({t0}, {t1}] s")
    if not np.isfinite(coarse.euler_rad[0]) and heading_std_rad is None:
        raise AlignmentError("the coarse alignment has no heading: give heading_std_rad (and a "
                             "heading through coarse.euler_rad) or gyrocompass first")
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
    from types import SimpleNamespace
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
    from gfins_fmi.estimation.ins_gnss import IntegratedNavigator, MEAS_TYPES
    from gfins_fmi._lib import lib
    from gfins_fmi.sins import quat_to_euler
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
        raise AlignmentError(f"the initial state (t = {nav0.t_s!r} s) must be at the start of the record's "
                             f"first interval, before its first sample ({t[0]!r} s)")
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
        from gfins_fmi.estimation.ins_gnss import _PASS_DTYPE
        rows, logs = [], []
        table = np.zeros(1 + 2 * passes, _PASS_DTYPE)
        inside = {k: _time_slice(v, t0 - 1.0, t1 + 1e-9) for k, v in recs.items()}
        after_start = {k: _time_slice(v, t0 + 1e-9, t1 + 1e-9) for k, v in recs.items()}
        before_end = {k: _time_slice(v, t0 - 1e-9, t1 - 1e-9) for k, v in recs.items()}
        bar = None
        if progress:
            from tqdm import tqdm
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
