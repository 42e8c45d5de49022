"""Evaluation of integrated-navigation solutions: errors against a reference trajectory
(with time alignment), filter consistency (NEES, NIS with chi-square bands), the GNSS
outage protocol, the covariance (python-control) prediction of the drift during an
outage, and the figures.

Conventions: position errors in metres east, north, up; velocity errors ENU in m/s;
attitude error as the rotation vector a (ENU, rad) with C_b^n(estimate) =
exp([a x]) C_b^n(reference) — the filter's own attitude state is phi = -a
(csrc/est/gf_ins_gnss.h).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from gfins_fmi.estimation.error_model import ins_error_model
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.nav.earth import WGS84, attitude_error_rad, quat_to_dcm
from gfins_fmi.nav.earth import euler_to_quat as earth_euler_to_quat
from gfins_fmi.nav.strapdown import euler_to_quat, quat_to_euler

__all__ = ["NavErrors", "navigation_errors", "state_errors", "nees", "chi2_band",
           "outage_windows", "kfgins_outage_windows", "without_outages", "OutageResult", "outage_protocol",
           "outage_drift", "antenna_positions", "GnssResiduals", "gnss_residuals", "gnss_outage_drift",
           "predict_outage_std", "plot_errors", "plot_consistency", "plot_outages"]

def _radii(lat):
    # gfins_fmi.nav.earth.radii's R_M, R_N with e2 sin^2 rounded in another order: kept,
    # so that the errors this module reports stay bit for bit what they were
    q = 1.0 - WGS84.e2 * np.sin(lat) ** 2
    return WGS84.a * (1.0 - WGS84.e2) / q ** 1.5, WGS84.a / np.sqrt(q)


def _get(obj, *names):
    for n in names:
        v = getattr(obj, n, None)
        if v is not None:
            return np.asarray(v)
    return None


def _quat_of(obj):
    q = _get(obj, "q_bn")
    if q is not None:
        return q
    e = _get(obj, "euler_rad")
    if e is None:
        return None
    if e.ndim == 1:
        return euler_to_quat(e)
    # a record's angles, (n, 3): the same convention as the C core's gf_euler_to_quat
    # (before: handed whole to the one-attitude function, so every --truth TruthRecord
    # refused in the scoring, "euler_rad must have shape (3,)")
    return np.asarray(earth_euler_to_quat(e[:, 0], e[:, 1], e[:, 2]))


def _interp_quat(t_ref, q_ref, t):
    from scipy.spatial.transform import Rotation, Slerp   # lazy: scipy's import costs start-up time
    # q_b^n scalar first -> scipy's scalar-last; the same active rotation C_b^n
    rot = Rotation.from_quat(np.c_[q_ref[:, 1:], q_ref[:, :1]])
    out = Slerp(t_ref, rot)(t).as_quat()
    return np.c_[out[:, 3:], out[:, :3]]


def reference_at(reference, t_s) -> dict:
    """The reference (a TruthRecord, Trajectory/VehicleRecord, IntegratedSolution or a
    GnssRecord: anything with t_s, lat_rad, lon_rad, h_m and optionally velocity and
    attitude) interpolated to times t_s (linear; attitude by slerp). Times outside the
    reference are NaN."""
    tr = np.asarray(reference.t_s, float)
    t = np.asarray(t_s, float)
    inside = (t >= tr[0]) & (t <= tr[-1])
    if not np.any(inside):
        raise ValueError(f"the reference covers [{tr[0]}, {tr[-1]}] s, no time of the solution "
                         f"([{t[0]}, {t[-1]}] s): check the time scales (offset?)")
    out = {"inside": inside}
    for key, names in (("lat", ("lat_rad",)), ("lon", ("lon_rad",)), ("h", ("h_m",))):
        v = _get(reference, *names)
        if key == "lon":
            v = np.unwrap(v)
        out[key] = np.where(inside, np.interp(t, tr, v), np.nan)
    v = _get(reference, "v_n_m_s", "v_enu_m_s", "vel_enu_m_s")
    out["v"] = None if v is None else np.where(
        inside[:, None], np.column_stack([np.interp(t, tr, v[:, i]) for i in range(3)]), np.nan)
    q = _quat_of(reference)
    if q is None:
        out["q"] = None
    else:
        qq = np.full((len(t), 4), np.nan)
        qq[inside] = _interp_quat(tr, q, t[inside])
        out["q"] = qq
    return out


def attitude_difference_rad(q_est, q_ref) -> np.ndarray:
    """Rotation vector a (n, 3, ENU) with C(q_est) = exp([a x]) C(q_ref)."""
    return attitude_error_rad(q_est, q_ref)


@dataclass
class NavErrors:
    """Errors of a solution against a reference at the solution's times: ``pos_enu_m``
    (n, 3), ``vel_enu_m_s`` (n, 3) or None, ``att_rad`` (n, 3) or None (see the module),
    ``heading_rad`` (n,) or None (estimate - reference, wrapped), NaN outside the
    reference."""
    t_s: np.ndarray
    pos_enu_m: np.ndarray
    vel_enu_m_s: Optional[np.ndarray]
    att_rad: Optional[np.ndarray]
    heading_rad: Optional[np.ndarray]

    @property
    def horizontal_m(self) -> np.ndarray:
        return np.hypot(self.pos_enu_m[:, 0], self.pos_enu_m[:, 1])

    def rms(self) -> dict:
        """RMS of each component over the finite rows."""
        def r(a):
            return None if a is None else np.sqrt(np.nanmean(a ** 2, axis=0))
        return {"pos_enu_m": r(self.pos_enu_m), "horizontal_m": float(r(self.horizontal_m)),
                "vel_enu_m_s": r(self.vel_enu_m_s), "att_rad": r(self.att_rad),
                "heading_rad": None if self.heading_rad is None else float(r(self.heading_rad))}


def navigation_errors(solution, reference, time_offset_s: float = 0.0) -> NavErrors:
    """Errors of ``solution`` (IntegratedSolution, NavSolution or any record with t_s,
    lat_rad, lon_rad, h_m [, v_n_m_s, q_bn]) against ``reference`` interpolated to the
    solution's times + ``time_offset_s`` (the reference's clock minus the solution's)."""
    t = np.asarray(solution.t_s, float)
    ref = reference_at(reference, t + time_offset_s)
    RM, RN = _radii(ref["lat"])
    lat, lon, h = (np.asarray(solution.lat_rad), np.asarray(solution.lon_rad), np.asarray(solution.h_m))
    dlon = (lon - ref["lon"] + np.pi) % (2 * np.pi) - np.pi
    pos = np.c_[dlon * (RN + ref["h"]) * np.cos(ref["lat"]), (lat - ref["lat"]) * (RM + ref["h"]), h - ref["h"]]
    v = _get(solution, "v_n_m_s", "v_enu_m_s")
    vel = None if v is None or ref["v"] is None else v - ref["v"]
    q = _quat_of(solution)
    att = heading = None
    if q is not None and ref["q"] is not None:
        att = np.full((len(t), 3), np.nan)
        ok = ref["inside"]
        att[ok] = attitude_difference_rad(q[ok], ref["q"][ok])
        heading = np.full(len(t), np.nan)
        he = quat_to_euler(q[ok])[:, 0] - quat_to_euler(ref["q"][ok])[:, 0]
        heading[ok] = (he + np.pi) % (2 * np.pi) - np.pi
    return NavErrors(t, pos, vel, att, heading)


def state_errors(epochs: dict, truth, gyro_bias_rad_s=None, accel_bias_m_s2=None,
                 truth_t_s=None) -> np.ndarray:
    """The true error state (E, n) of each smoother epoch's posterior nominal, in the
    filter's convention (computed - true for navigation; true - estimated for the sensor
    states): what NEES needs. ``gyro_bias_rad_s``/``accel_bias_m_s2`` (m, 3) are the
    true biases at times ``truth_t_s`` (default: the truth's t_s[1:], the IMU samples of
    a SimulatedDrive). Only the 15 base states are filled (others 0)."""
    t = np.asarray(epochs["t_s"])
    nav = np.asarray(epochs["nav"])
    n = int(epochs["n_states"])
    ref = reference_at(truth, t)
    e = np.zeros((len(t), n))
    e[:, 0:3] = nav[:, 4:7] - ref["v"]
    e[:, 3] = nav[:, 7] - ref["lat"]
    e[:, 4] = (nav[:, 8] - ref["lon"] + np.pi) % (2 * np.pi) - np.pi
    e[:, 5] = nav[:, 9] - ref["h"]
    e[:, 6:9] = -attitude_difference_rad(nav[:, 0:4], ref["q"])
    tt = np.asarray(truth.t_s)[1:] if truth_t_s is None else np.asarray(truth_t_s)
    sens = np.asarray(epochs["sensors"])
    if gyro_bias_rad_s is not None:
        gb = np.column_stack([np.interp(t, tt, gyro_bias_rad_s[:, i]) for i in range(3)])
        e[:, 9:12] = gb - sens[:, 0:3]
    if accel_bias_m_s2 is not None:
        ab = np.column_stack([np.interp(t, tt, accel_bias_m_s2[:, i]) for i in range(3)])
        e[:, 12:15] = ab - sens[:, 3:6]
    return e


def _unpack(tri, n):
    P = np.zeros((len(tri), n, n))
    iu = np.triu_indices(n)
    P[:, iu[0], iu[1]] = tri
    P[:, iu[1], iu[0]] = tri
    return P


def nees(epochs: dict, errors: np.ndarray, states: Optional[Sequence[int]] = None,
         which: str = "P_post") -> np.ndarray:
    """Normalised estimation error squared e^T P^-1 e at each epoch, over the ``states``
    (default all), with the epochs' posterior covariance (or ``which="P_prior"``; a
    smoothed covariance array of the same layout may be passed in ``epochs[which]``)."""
    n = int(epochs["n_states"])
    P = _unpack(np.asarray(epochs[which]), n)
    idx = np.arange(n) if states is None else np.asarray(states)
    Ps = P[:, idx[:, None], idx[None, :]]
    e = np.asarray(errors)[:, idx]
    return np.einsum("ki,ki->k", e, np.linalg.solve(Ps, e[..., None])[..., 0])


def chi2_band(dof: int, runs: int, prob: float = 0.95) -> tuple:
    """The two-sided ``prob`` band of the mean of ``runs`` independent chi-square
    variables of ``dof`` degrees of freedom (the band for an average NEES or NIS)."""
    from scipy.stats import chi2   # lazy: scipy's import costs start-up time
    lo = chi2.ppf((1 - prob) / 2, dof * runs) / runs
    hi = chi2.ppf(1 - (1 - prob) / 2, dof * runs) / runs
    return float(lo), float(hi)


def outage_windows(t_start_s: float, t_end_s: float, outage_s: float, period_s: float,
                   first_s: float) -> np.ndarray:
    """The older, stricter variant (``protocol="inside"``; not KF-GINS's): (k, 2) outages
    [t0, t1] of ``outage_s`` every ``period_s`` from ``first_s`` after ``t_start_s``, only
    those ending before ``t_end_s``, both boundary fixes removed. Its figures are not
    comparable with KF-GINS's or pyins's: use :func:`kfgins_outage_windows`."""
    if not (outage_s > 0 and period_s >= outage_s and first_s >= 0):
        raise ValueError("need outage_s > 0, period_s >= outage_s and first_s >= 0")
    t0 = np.arange(t_start_s + first_s, t_end_s - outage_s, period_s)
    return np.c_[t0, t0 + outage_s]


def kfgins_outage_windows(t_start_s: float, t_end_s: float, outage_s: float, period_s: float,
                          first_s: float) -> np.ndarray:
    """The outage protocol of KF-GINS and pyins users: (k, 2) open windows (t_s, t_s + L)
    with t_s = ``t_start_s`` + ``first_s`` + k ``period_s``, every one that starts inside
    the record (t_s < ``t_end_s``, even when it ends after it). The fixes with
    t_s < t < t_s + L are removed (:func:`without_outages`; the boundary fixes kept) and
    the drift of an outage is the maximum horizontal error inside it."""
    if not (outage_s > 0 and period_s >= outage_s and first_s >= 0):
        raise ValueError("need outage_s > 0, period_s >= outage_s and first_s >= 0")
    t0 = np.arange(t_start_s + first_s, t_end_s, period_s)
    return np.c_[t0, t0 + outage_s]


def without_outages(gnss, windows: np.ndarray):
    """``gnss`` without its fixes strictly inside any window (t0 < t < t1): the boundary
    fixes stay, as in KF-GINS's and pyins's protocol."""
    inner = [(np.nextafter(a, np.inf), np.nextafter(b, -np.inf)) for a, b in np.asarray(windows, float)]
    t = np.asarray(gnss.t_s)
    inner = [(a, b) for a, b in inner if np.any((t >= a) & (t <= b))]
    return gnss.with_outages(inner) if inner else gnss


def _inside(t, a, b, protocol):
    return (t > a) & (t < b) if protocol == "kfgins" else (t >= a) & (t < b)


def outage_drift(solution, reference, windows: np.ndarray, protocol: str = "kfgins") -> dict:
    """For each outage window: the maximum horizontal error during it and the error at
    its end (m), from the solution's rows inside the window (t0 < t < t1; ``protocol=
    "inside"``: t0 <= t < t1). A window that runs past the solution is scored over the
    rows it has."""
    err = navigation_errors(solution, reference)
    hz = err.horizontal_m
    t = err.t_s
    mx, end = np.empty(len(windows)), np.empty(len(windows))
    for i, (a, b) in enumerate(windows):
        sel = _inside(t, a, b, protocol) & np.isfinite(hz)
        if not np.any(sel):
            raise ValueError(f"the solution has no row in the outage ({a}, {b}) s")
        mx[i] = np.max(hz[sel])
        end[i] = hz[np.flatnonzero(sel)[-1]]
    return {"max_m": mx, "end_m": end}


def antenna_positions(solution, lever_arm_m) -> tuple:
    """The GNSS antenna's latitude, longitude (rad) and height (m) at every row of
    ``solution``: its position + C_b^n ``lever_arm_m`` (body right, front, up, m; the
    ENU offset turned into latitude and longitude with the radii at the row)."""
    lat, lon, h = (np.asarray(solution.lat_rad, float), np.asarray(solution.lon_rad, float),
                   np.asarray(solution.h_m, float))
    arm = np.asarray(lever_arm_m, float)
    if not np.any(arm):
        return lat, lon, h
    d = np.einsum("kij,j->ki", quat_to_dcm(np.asarray(_quat_of(solution), float)), arm)
    RM, RN = _radii(lat)
    return (lat + d[:, 1] / (RM + h), lon + d[:, 0] / ((RN + h) * np.cos(lat)), h + d[:, 2])


@dataclass
class GnssResiduals:
    """The solution's antenna position minus the GNSS fixes, at the fixes' own times
    (``t_s``, (m,)), east, north, up in m (``enu_m``, (m, 3)): residuals, not errors —
    the fixes carry their own noise. Fixes outside the solution's span are left out."""
    t_s: np.ndarray
    enu_m: np.ndarray

    @property
    def horizontal_m(self) -> np.ndarray:
        return np.hypot(self.enu_m[:, 0], self.enu_m[:, 1])

    def rms(self) -> dict:
        """RMS of the horizontal and vertical residuals (m); NaN without a fix."""
        if len(self.t_s) == 0:
            return {"horizontal_m": float("nan"), "up_m": float("nan")}
        return {"horizontal_m": float(np.sqrt(np.mean(self.horizontal_m ** 2))),
                "up_m": float(np.sqrt(np.mean(self.enu_m[:, 2] ** 2)))}


def gnss_residuals(solution, gnss, lever_arm_m=(0.0, 0.0, 0.0)) -> GnssResiduals:
    """The residuals of ``solution`` to ``gnss`` at the antenna (lever arm applied), only
    where a fix exists: the antenna position of the solution's rows interpolated to each
    fix's time between the two rows around it (never the fixes interpolated across a
    gap)."""
    lat, lon, h = antenna_positions(solution, lever_arm_m)
    t = np.asarray(solution.t_s, float)
    tg = np.asarray(gnss.t_s, float)
    sel = (tg >= t[0]) & (tg <= t[-1]) if len(t) else np.zeros(len(tg), bool)
    tg = tg[sel]
    lon = np.unwrap(lon)
    a_lat, a_lon, a_h = (np.interp(tg, t, x) for x in (lat, lon, h))
    g_lat, g_lon, g_h = (np.asarray(gnss.lat_rad)[sel], np.asarray(gnss.lon_rad)[sel],
                         np.asarray(gnss.h_m)[sel])
    RM, RN = _radii(g_lat)
    dlon = (a_lon - g_lon + np.pi) % (2 * np.pi) - np.pi
    enu = np.c_[dlon * (RN + g_h) * np.cos(g_lat), (a_lat - g_lat) * (RM + g_h), a_h - g_h]
    return GnssResiduals(tg, enu)


def gnss_outage_drift(solution, gnss, windows: np.ndarray, lever_arm_m=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Without a truth: the maximum horizontal residual of ``solution`` to the fixes the
    outage protocol removed (those strictly inside each window), per window (m; NaN for
    a window without a fix)."""
    r = gnss_residuals(solution, gnss, lever_arm_m)
    hz = r.horizontal_m
    out = np.full(len(windows), np.nan)
    for i, (a, b) in enumerate(windows):
        sel = (r.t_s > a) & (r.t_s < b)
        if np.any(sel):
            out[i] = hz[sel].max()
    return out


@dataclass
class OutageResult:
    """The GNSS outage protocol: ``windows`` (k, 2); the filter's and the smoother's
    maximum horizontal drift per outage (m) and their RMS (the score); the solutions."""
    windows: np.ndarray
    filter_max_m: np.ndarray
    smoother_max_m: Optional[np.ndarray]
    filter_score_m: float
    smoother_score_m: Optional[float]
    solution: object
    smoothed: object


def outage_protocol(imu, gnss, reference, *, config, initial, outage_s: float = 60.0,
                    period_s: float = 180.0, first_s: float = 300.0, smooth: bool = True,
                    baro=None, odometer=None, progress: bool = False,
                    protocol: str = "kfgins") -> OutageResult:
    """Run the filter with GNSS removed during an outage of ``outage_s`` every
    ``period_s`` (from ``first_s`` after the first GNSS epoch, once converged) and score
    it: RMS over the outages of the maximum horizontal drift during each, for the filter
    and, with ``smooth``, the RTS smoother. ``protocol="kfgins"`` (KF-GINS's and pyins's:
    :func:`kfgins_outage_windows`) or ``"inside"`` (the older variant,
    :func:`outage_windows`)."""
    if protocol not in ("kfgins", "inside"):
        raise ValueError(f"protocol must be 'kfgins' or 'inside'; got {protocol!r}")
    t_g = np.asarray(gnss.t_s)
    t_end = min(t_g[-1], np.asarray(imu.t_s)[-1])
    if protocol == "kfgins":
        win = kfgins_outage_windows(t_g[0], t_end, outage_s, period_s, first_s)
    else:
        win = outage_windows(t_g[0], t_end, outage_s, period_s, first_s)
    if len(win) == 0:
        raise ValueError("the record is too short for one outage after first_s")
    if protocol == "kfgins":
        g = without_outages(gnss, win)
    else:
        g = gnss.with_outages([tuple(w) for w in win]) if hasattr(gnss, "with_outages") else gnss
    nav = IntegratedNavigator(config, initial)
    sol = nav.run(imu, g, baro, odometer, smoother=smooth, progress=progress)
    f = outage_drift(sol, reference, win, protocol)
    sm = None
    s_max = s_score = None
    if smooth:
        sm = sol.smooth()
        s_max = outage_drift(sm, reference, win, protocol)["max_m"]
        s_score = float(np.sqrt(np.mean(s_max ** 2)))
    return OutageResult(win, f["max_m"], s_max, float(np.sqrt(np.mean(f["max_m"] ** 2))), s_score,
                        sol, sm)


def predict_outage_std(P0: np.ndarray, t_s, lat_rad, h_m, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s,
                       config, step_s: float = 1.0) -> dict:
    """Covariance prediction of the drift during an outage with the python-control error
    model (``estimation.error_model.ins_error_model`` along the nominal trajectory, Van Loan
    discretisation over ``step_s``), from the filter's covariance ``P0`` at the outage
    start and its process noise (``config.noise_si()``).

    The trajectory arrays give the nominal at times ``t_s`` (the outage's samples); the
    model is evaluated at each step's midpoint. Returns ``t_s`` and the 1-sigma of the
    east, north and horizontal position errors (m) at those times.
    """
    from scipy.linalg import expm   # lazy: scipy's import costs start-up time
    t = np.asarray(t_s, float)
    noise = config.noise_si()
    n = P0.shape[0]
    q = np.r_[[noise["accel_vrw_m_s_sqrt_s"] ** 2] * 3, [noise["gyro_arw_rad_sqrt_s"] ** 2] * 3,
              [2 * noise["gyro_bias_std_rad_s"] ** 2 / noise["gyro_bias_tau_s"]
               if noise["gyro_bias_tau_s"] > 0 else 0.0] * 3,
              [2 * noise["accel_bias_std_m_s2"] ** 2 / noise["accel_bias_tau_s"]
               if noise["accel_bias_tau_s"] > 0 else 0.0] * 3]
    if n != 15:
        raise ValueError("predict_outage_std models the 15 base states")
    tau = {"bg": noise["gyro_bias_tau_s"], "ba": noise["accel_bias_tau_s"]}
    grid = np.arange(t[0], t[-1] + 1e-9, step_s)
    P = np.array(P0, float)
    out_t, sE, sN = [grid[0]], [], []

    def pos_std(P, k):
        RM, RN = _radii(lat_rad[k])
        return (np.sqrt(P[4, 4]) * (RN + h_m[k]) * np.cos(lat_rad[k]), np.sqrt(P[3, 3]) * (RM + h_m[k]))

    k0 = 0
    e, nn = pos_std(P, k0)
    sE.append(e)
    sN.append(nn)
    for a, b in zip(grid[:-1], grid[1:]):
        k = int(np.clip(np.searchsorted(t, 0.5 * (a + b)), 0, len(t) - 1))
        sys = ins_error_model(lat_rad[k], h_m[k], v_enu_m_s[k], q_bn[k], f_b_m_s2[k], w_ib_b_rad_s[k],
                              tau_s=tau)
        A, G = np.asarray(sys.A), np.asarray(sys.B)
        dt = b - a
        M = np.zeros((2 * n, 2 * n))
        M[:n, :n] = -A
        M[:n, n:] = G @ np.diag(q) @ G.T
        M[n:, n:] = A.T
        E = expm(M * dt)
        Phi = E[n:, n:].T
        Qd = Phi @ E[:n, n:]
        P = Phi @ P @ Phi.T + 0.5 * (Qd + Qd.T)
        out_t.append(b)
        e, nn = pos_std(P, k)
        sE.append(e)
        sN.append(nn)
    sE, sN = np.array(sE), np.array(sN)
    return {"t_s": np.array(out_t), "east_m": sE, "north_m": sN, "horizontal_m": np.hypot(sE, sN)}


# ---- figures ----------------------------------------------------------------------------------

def _axes(nrows, ncols=1, figsize=(9, 7)):
    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(nrows, ncols, figsize=figsize, sharex=True, squeeze=False)
    return fig, ax


def plot_errors(errors: NavErrors, path, std: Optional[np.ndarray] = None, title: str = "",
                windows: Optional[np.ndarray] = None):
    """Position, velocity and attitude errors with the filter's ±3 sigma (``std`` (n, 9)
    as IntegratedSolution.std) and the outage windows shaded."""
    fig, ax = _axes(3)
    t = errors.t_s - errors.t_s[0]
    t0 = errors.t_s[0]
    labels = ("east", "north", "up")
    blocks = [(errors.pos_enu_m, "position error (m)", 3, 1.0),
              (errors.vel_enu_m_s, "velocity error (m/s)", 0, 1.0),
              (errors.att_rad, "attitude error (deg)", 6, 180 / np.pi)]
    for a, (val, lab, si, k) in zip(ax[:, 0], blocks):
        if val is None:
            continue
        for i in range(3):
            line, = a.plot(t, val[:, i] * k, lw=0.8, label=labels[i])
            if std is not None:
                a.plot(t, 3 * std[:, si + i] * k, lw=0.5, ls="--", color=line.get_color())
                a.plot(t, -3 * std[:, si + i] * k, lw=0.5, ls="--", color=line.get_color())
        if windows is not None:
            for w0, w1 in windows:
                a.axvspan(w0 - t0, w1 - t0, color="0.9", zorder=0)
        a.set_ylabel(lab)
        a.grid(True, lw=0.3)
    ax[0, 0].legend(loc="upper right", fontsize=8)
    ax[-1, 0].set_xlabel("time (s)" + ("  (dashed: ±3σ of the filter; grey: GNSS outages)"
                                        if std is not None else ""))
    if title:
        ax[0, 0].set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def plot_consistency(path, t_nees, mean_nees, nees_band, t_nis=None, mean_nis=None, nis_band=None,
                     title: str = ""):
    """Average NEES (and NIS) over Monte-Carlo runs with their chi-square bands."""
    fig, ax = _axes(2 if t_nis is not None else 1, figsize=(9, 6))
    a = ax[0, 0]
    a.plot(t_nees - t_nees[0], mean_nees, lw=0.7)
    a.axhline(nees_band[0], color="k", ls="--", lw=0.6)
    a.axhline(nees_band[1], color="k", ls="--", lw=0.6)
    a.set_ylabel("average NEES")
    a.grid(True, lw=0.3)
    if title:
        a.set_title(title)
    if t_nis is not None:
        b = ax[1, 0]
        b.plot(t_nis - t_nees[0], mean_nis, ".", ms=2)
        b.axhline(nis_band[0], color="k", ls="--", lw=0.6)
        b.axhline(nis_band[1], color="k", ls="--", lw=0.6)
        b.set_ylabel("average NIS")
        b.grid(True, lw=0.3)
    ax[-1, 0].set_xlabel("time (s)  (dashed: 95% chi-square band of the average)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def plot_outages(path, result: OutageResult, reference, title: str = ""):
    """Horizontal error over time (filter and smoother) with the outages shaded, and the
    maximum drift per outage."""
    fig, ax = _axes(2, figsize=(9, 6))
    e = navigation_errors(result.solution, reference)
    t0 = e.t_s[0]
    a = ax[0, 0]
    a.plot(e.t_s - t0, e.horizontal_m, lw=0.7, label=f"filter (score {result.filter_score_m:.3g} m)")
    if result.smoothed is not None:
        es = navigation_errors(result.smoothed, reference)
        a.plot(es.t_s - t0, es.horizontal_m, lw=0.7, label=f"smoother (score {result.smoother_score_m:.3g} m)")
    for w0, w1 in result.windows:
        a.axvspan(w0 - t0, w1 - t0, color="0.9", zorder=0)
    a.set_ylabel("horizontal error (m)")
    a.legend(fontsize=8)
    a.grid(True, lw=0.3)
    b = ax[1, 0]
    mid = result.windows.mean(axis=1) - t0
    width = 0.35 * (result.windows[0, 1] - result.windows[0, 0])
    b.bar(mid - width / 2, result.filter_max_m, width, label="filter")
    if result.smoother_max_m is not None:
        b.bar(mid + width / 2, result.smoother_max_m, width, label="smoother")
    b.set_ylabel("max drift per outage (m)")
    b.set_xlabel("time (s)")
    b.legend(fontsize=8)
    b.grid(True, lw=0.3)
    if title:
        a.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path
