"""System-level calibration of a rotating INS (seed 001, steps S3-S5, and the full inner
lever-arm model) on a raw multi-position record, with the filter of
:mod:`gfins_fmi.calibration.syscal_filter`.

:func:`calibrate` takes a raw record (any rate, increments or rates) of an IMU turned
through any sequence of rotations at a known site: it checks units and sampling, finds
the static intervals and the turns, picks the defaults of the IMU's grade (given, or read
from the first static interval), aligns coarsely on the first static interval, runs the
filter (``passes`` > 1 re-runs it from the previous estimates), checks the result against
the prior, the noise and the model (:mod:`gfins_fmi.calibration.diagnostics`; with
``widen_priors`` it widens the priors that the data fight and runs again), and reports
every parameter with its standard deviation in both conventions
(:mod:`gfins_fmi.calibration.report`).
:func:`simulate_record` is the forward model (gf_rotation's exact increments, the
gf_imu_error model with the exact angular acceleration, the exact accelerometer delay,
white noise) for tests and studies; :func:`covariance_study` tells what a path can
observe before anything is recorded.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from gfins_fmi._lib import as_array, as_scalar
from gfins_fmi.calibration.diagnostics import diagnose, missing_terms
from gfins_fmi.calibration.grades import (config_for_grade, detect_grade, grade as grade_by_name,
                                         measured_noise)
from gfins_fmi.calibration.report import CalibrationReport, plot_report
from gfins_fmi.calibration.segmentation import (check_record, lat_problem, record_increments,
                                                segment_record)
from gfins_fmi.calibration.syscal_filter import (N_C_PARAMS, CalibrationInputError, Prior,
                                                 SyscalConfig, SyscalFilter, c_params_to_imu_errors,
                                                 core_gravity_m_s2, param_index, param_names,
                                                 param_units, params_to_c, params_to_imu_errors,
                                                 prior_fields)
from gfins_fmi.estimation.alignment import attitude_from_gravity_and_earth_rate
from gfins_fmi.nav.earth import WGS84, quat_to_dcm
from gfins_fmi.nav.imu_errors import UG, ImuErrors, ImuNoise
from gfins_fmi.sim.rotation import simulate_static

__all__ = ["CalibrationReport", "calibrate", "random_params", "simulate_record",
           "covariance_study", "plot_report"]


def _level_with_heading(f_mean, heading_rad: float) -> np.ndarray:
    """q_b^n from the mean specific force (up) and the heading of the body y axis's
    horizontal projection (clockwise from north): for gyros that cannot see the Earth rate."""
    from scipy.spatial.transform import Rotation   # lazy: scipy's import costs start-up time
    u = np.asarray(f_mean, float) / np.linalg.norm(f_mean)
    y = np.array([0.0, 1.0, 0.0]) if abs(u[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    p = y - (y @ u) * u
    p /= np.linalg.norm(p)
    north = Rotation.from_rotvec(u * heading_rad).apply(p)   # turned left of y by the heading
    east = np.cross(north, u)
    q = Rotation.from_matrix(np.array([east, north, u])).as_quat()
    return np.array([q[3], q[0], q[1], q[2]])


def _run_passes(config, site, rec, first, mu_c, p_c, passes, heading_rad, bar):
    """``passes`` filter passes, each linearised about the previous estimates with the
    prior of ``config`` centred on ``mu_c`` (C param[]); returns (filter, P, p_c, epochs, q0)."""
    lat, h, lon = site
    t_end, dt, dth, dv = rec
    idx = param_index(config.model, config.estimate_delay)
    prior_var = config.params_std() ** 2
    t0 = float(t_end[0] - dt[0])
    pass_epochs = []
    for _ in range(passes):
        # coarse alignment on the first static interval, with the current compensation
        sl = slice(first.i0, first.i1)
        w_c, f_c = c_params_to_imu_errors(p_c).compensate_increments(dth[sl], dv[sl], dt[sl])
        q0 = attitude_from_gravity_and_earth_rate(f_c.sum(axis=0), w_c.sum(axis=0)) if heading_rad is None \
            else _level_with_heading(f_c.sum(axis=0), heading_rad)
        filt = SyscalFilter(config, lat, h, q0, lon_rad=lon, params0=p_c, t0_s=t0)
        filt.run(t_end, dth, dv)
        P = filt.covariance()
        # the filter's prior was N(p, P0); the prior is N(mu, P0): the parameters are
        # constant states, so moving the prior's mean by d moves the posterior mean by
        # P_pp P0^-1 d (the covariance does not change)
        d = mu_c[idx] - p_c[idx]
        p_c = filt.c_params
        p_c[idx] += P[9:, 9:] @ (d / prior_var)
        pass_epochs.append(filt.epochs())
        if bar is not None:
            bar.update(1)
    return filt, P, p_c, pass_epochs, q0


def _prior_mean(config, params0) -> np.ndarray:
    """The prior's mean as a C param[] (34) from params0 (model order, model order without
    the delay, or a C param[]; None: 0, the nominal IMU)."""
    if params0 is None:
        return np.zeros(N_C_PARAMS)
    v = as_array("params0", params0, (None,), "SI")
    n = len(config.names)
    if v.size == N_C_PARAMS:
        return v.copy()
    if v.size == n:
        return params_to_c(v, config.model, config.estimate_delay)
    if config.estimate_delay and v.size == n - 1:
        return params_to_c(np.r_[v, 0.0], config.model, True)
    raise ValueError(f"params0 must hold {n} values (the {config.model} model's parameters, SI) or "
                     f"{N_C_PARAMS} (the C param[]); got {v.size}")


def _flagged_fields(diag, config) -> dict:
    """The prior fields to widen and by how much: every block with a parameter that fights
    its prior or a block test beyond its bound, by max(10, 3 x its largest |shift|)."""
    fields = prior_fields(config.model, config.estimate_delay)
    names = config.names
    flagged = set(diag.fights) | {n for b in diag.blocks if not b["ok"] for n in b["names"]}
    out = {}
    for n in flagged:
        f = fields[names.index(n)]
        sel = [k for k, g in enumerate(fields) if g == f]
        out[f] = max(out.get(f, 10.0), 10.0, 3.0 * float(np.max(np.abs(diag.shift[sel]))))
    return out


def calibrate(record, lat_rad: float, h_m: float, *, lon_rad: float = 0.0,
              config: SyscalConfig | None = None, grade: str | None = None, passes: int = 2,
              params0=None, gravity_m_s2: float | None = None, widen_priors: bool = False,
              max_rounds: int = 4, check_model: bool = True, rate_threshold_deg_s: float = 0.5,
              min_static_s: float = 5.0, min_align_s: float = 30.0,
              max_angle_per_sample_deg: float = 3.0, heading_rad: float | None = None,
              progress: bool = False, checks: str = "raise") -> CalibrationReport:
    """System-level calibration of a raw multi-position record (seed 001 S4-S5).

    Parameters
    ----------
    record : gfins_fmi.io.ImuRecord
        Raw IMU samples (increments or rates, any rate) in the IMU frame m, at rest on a
        turntable or the rotating INS's own mechanism, starting at rest.
    lat_rad, h_m, lon_rad : the site (known; seed 001 S501), |lat| < 89 deg.
    config : SyscalConfig (model, noise densities, prior); default: the grade's.
    grade : "navigation", "tactical" or "mems" (:mod:`gfins_fmi.calibration.grades`): its
        defaults, when ``config`` is not given; None: read from the first static interval
        (the finest grade it fits, with the white noise it shows).
    passes : runs of the filter; each pass is linearised about the previous pass's
        estimates (iterated linearisation), with the prior centred on ``params0``: a pass
        that starts from estimates x_lin has its prior centred there instead, and its
        result is re-centred exactly (linear-Gaussian posterior: x += P_pp P0^-1
        (params0 - x_lin)), so the data are not counted twice.
    params0 : prior mean of the parameters, SI (model order, or the C param[]; default 0).
    gravity_m_s2 : the site's gravity (e.g. surveyed); default WGS-84 normal gravity at
        (lat, h). The filter removes the difference (gf_syscal.h).
    widen_priors : when estimates fight their prior (diagnostics), widen those blocks'
        priors by max(10, 3 x the largest shift) and run again, up to ``max_rounds`` runs
        (the multi-round feedback of laboratory tools); the rounds are in ``rounds``.
    check_model : when the model lacks terms (seed model, or no delay), one more pass
        with the full model and the delay tests them (diagnostics.missing_terms).
    rate_threshold_deg_s, min_static_s : segmentation (:func:`segment_record`).
    min_align_s : shortest first static interval (the coarse alignment).
    max_angle_per_sample_deg : turning faster than this per sample is refused.
    heading_rad : the heading of the IMU's y axis at the start, for gyros that cannot
        see the Earth rate (MEMS): the coarse alignment then levels only.
    progress : a progress bar over the filter passes (tqdm).
    checks : {"raise", "warn", "off"}
        A site latitude the Earth rate measured in the static intervals contradicts
        (more than 5 sigma of the prior's gyro bias and 2 deg away: the record was made
        elsewhere) raises :class:`CalibrationInputError`, warns or passes (not checked
        with ``heading_rad``: gyros that cannot see the Earth rate).

    Returns
    -------
    CalibrationReport

    Raises
    ------
    CalibrationInputError
        Units, sampling, no rest, motion too fast, site (the message says what to change).
    GfinsError
        The filter diverged (the message names the sample).
    """
    lat = float(lat_rad)
    if not (np.isfinite(lat) and abs(lat) < np.radians(89.0)):
        raise CalibrationInputError(f"lat_rad = {float(lat_rad)!r}: the site's latitude must be within +-89 deg "
                                    "(in radians: np.radians)")
    h = as_scalar("h_m", h_m, "m", at_least=-1000.0, at_most=1e5)
    if not (isinstance(passes, int) and 1 <= passes <= 10):
        raise ValueError(f"passes must be an integer in 1..10; got {passes!r}")
    if not (isinstance(max_rounds, int) and 1 <= max_rounds <= 10):
        raise ValueError(f"max_rounds must be an integer in 1..10; got {max_rounds!r}")
    if config is not None and grade is not None:
        raise ValueError("give config or grade, not both (config_for_grade(grade, ...) combines them)")
    g_normal = core_gravity_m_s2(lat, h)
    g_site = g_normal if gravity_m_s2 is None else as_scalar("gravity_m_s2", gravity_m_s2, "m/s^2",
                                                               above=9.7, below=9.9)
    t_end, dt, dth, dv = record_increments(record)
    segs = segment_record(t_end, dth, rate_threshold_deg_s, min_static_s=min_static_s)
    check_record(t_end, dt, dth, dv, segs, lat, h, min_align_s, np.radians(max_angle_per_sample_deg),
                 gravity_m_s2=g_site, earth_rate=heading_rad is None)
    first = next(s for s in segs if s.kind == "static")
    sl = slice(first.i0, first.i1)
    grade_name, figures = None, {}
    if config is None:
        if grade is None:   # the grade and the white noise of the first static interval
            gr, figures = detect_grade(dth[sl], dv[sl], dt[sl], lat, h, g_site)
            config = config_for_grade(gr, **measured_noise(gr, figures))
        else:
            gr = grade_by_name(grade)
            config = config_for_grade(gr)
        grade_name = gr.name
    config = dataclasses.replace(config, gravity_anomaly_m_s2=g_site - g_normal)
    if heading_rad is None:     # the site's latitude against the Earth rate (issue 21)
        lat_problem(t_end, dt, dth, dv, [s for s in segs if s.kind == "static"], lat,
                    np.radians(config.prior.gyro_bias_deg_h) / 3600.0, checks)
    mu_c = _prior_mean(config, params0)
    site, rec = (lat, h, lon_rad), (t_end, dt, dth, dv)
    diagnostic = check_model and (config.model == "seed" or not config.estimate_delay)
    bar = None
    if progress:
        from tqdm import tqdm   # lazy: only with a progress bar
        bar = tqdm(total=passes * (max_rounds if widen_priors else 1) + int(diagnostic),
                   desc="calibration passes", unit="pass")
    notes, rounds = [], []
    for r in range(max_rounds if widen_priors else 1):
        filt, P, p_c, pass_epochs, q0 = _run_passes(config, site, rec, first, mu_c, mu_c.copy(),
                                                    passes, heading_rad, bar)
        rep = _report(config, filt, P, p_c, mu_c, pass_epochs, segs, q0, passes, grade_name,
                      figures, g_site)
        diag = diagnose(rep, segs, None, config)
        widen = _flagged_fields(diag, config) if widen_priors else {}
        if not widen or r + 1 == max_rounds:
            break
        notes.append(f"round {r + 1}: estimates fought their prior ({', '.join(diag.fights) or 'block tests'}); "
                     "widened " + ", ".join(f"{f} x{k:.3g}" for f, k in widen.items()))
        config = dataclasses.replace(config, prior=dataclasses.replace(
            config.prior, **{f: getattr(config.prior, f) * k for f, k in widen.items()}))
        rounds.append({f: getattr(config.prior, f) for f in widen})
    missing = None
    if diagnostic:
        full = dataclasses.replace(config, model="full", estimate_delay=True)
        ff, Pf, pf, _, _ = _run_passes(full, site, rec, first, p_c, p_c.copy(), 1, heading_rad, bar)
        idx = param_index("full", True)
        missing = missing_terms(config.model, config.estimate_delay, param_names("full", True),
                                pf[idx], Pf[9:, 9:], param_units("full", True))
    if bar is not None:
        bar.close()
    rep.diagnostics = diagnose(rep, segs, missing, config)
    rep.notes = notes
    rep.rounds = rounds
    return rep


def _report(config, filt, P, p_c, mu_c, pass_epochs, segs, q0, passes, grade_name, figures, g_site):
    idx = param_index(config.model, config.estimate_delay)
    est = p_c[idx].copy()
    ep = pass_epochs[-1]
    positions = []
    for s in segs:
        if s.kind != "static":
            continue
        m = (ep["t_s"] > s.t0_s) & (ep["t_s"] <= s.t1_s)
        rms = float(np.sqrt(np.mean(ep["residual_m_s"][m] ** 2))) if m.any() else float("nan")
        positions.append({"t0_s": s.t0_s, "t1_s": s.t1_s, "rms_residual_m_s": rms})
    try:
        errors = c_params_to_imu_errors(p_c)
    except ValueError as exc:
        raise CalibrationInputError(
            f"the estimates left the IMU error model's range ({exc}): the record holds errors the "
            f"{config.model} model cannot represent, or the prior is far off (try the full model, "
            "the grade of the IMU, --widen-priors); the units of the record?") from exc
    return CalibrationReport(est, np.sqrt(np.diag(P))[9:], config.params_std(), config.names,
                             errors,
                             float(p_c[-1]) if config.estimate_delay else 0.0, ep, segs, positions,
                             passes, q0, P, pass_epochs, [], mu_c[idx].copy(), config.units,
                             config.model, None, grade_name, figures, [], g_site)


# ---- forward model and studies ---------------------------------------------------------------

def random_params(rng: np.random.Generator, prior: Prior | None = None, n_params: int = 27,
                  model: str = "seed") -> np.ndarray:
    """A random error set drawn from the prior (zero mean, the prior's 1-sigma), SI, model
    order: ``n_params`` of the seed model's 28 (27: no delay), or the full model's 31."""
    prior = prior or Prior()
    std = prior.params_std(model, True)
    return rng.normal(0.0, std[:n_params])


def _rates_at(schedule, t_s, q_base, lat_rad: float) -> np.ndarray:
    """w_im^m (n, 3) of the IMU on the static base (q_b^n = q_base) at the times t_s."""
    wie_n = WGS84.omega_ie * np.array([0.0, np.cos(lat_rad), np.sin(lat_rad)])
    pose = schedule.poses(t_s)
    C_mb = quat_to_dcm(pose["q_mb"])                       # (n, 3, 3) C_m^b
    return np.einsum("kji,j->ki", C_mb, quat_to_dcm(q_base).T @ wie_n) + pose["w_bm_m_rad_s"]


def simulate_record(schedule, params_si, lat_rad: float, h_m: float, dt_s: float = 0.01, *,
                    duration_s: float | None = None, heading_rad: float = 0.0,
                    noise: ImuNoise | None = None, seed: int = 0, accel_delay_s: float = 0.0):
    """A raw record of an IMU with the errors ``params_si`` turned by ``schedule``
    (:class:`gfins_fmi.sim.rotation.RotationSchedule`) on a static level base: exact
    increments (gf_rotation, with the accelerometer delay sampled exactly), the error model
    (gf_imu_error; lever arms across the axes with the exact mean angular acceleration
    over each sample, from the mechanism's rates at the sample ends), white noise
    (``noise``: its angle random walk and accelerometer white noise), seeded.
    ``params_si``: an :class:`gfins_fmi.ImuErrors` (its delay is the record's), or SI
    parameters in model order (27 / 28 seed, 30 / 31 full; the last of 28 / 31 is the
    accelerometer delay, overriding ``accel_delay_s``). Returns an ImuRecord of increments
    and the RotatingImuRecord of the truth."""
    if isinstance(params_si, ImuErrors):
        errs = params_si
        accel_delay_s = float(errs._c.a_delay_s)
    else:
        p = as_array("params_si", params_si, (None,), "SI")
        errs = params_to_imu_errors(p)
        if p.size in (28, 31):
            accel_delay_s = float(p[-1])
    errs = dataclasses.replace(errs, accel_delay_ms=0.0)     # the delay: sampled exactly
    dur = schedule.duration_s if duration_s is None else duration_s
    truth = simulate_static(schedule, dur, dt_s, lat_rad, h_m, heading_rad=heading_rad,
                            accel_delay_s=accel_delay_s)
    wd = None
    if errs.has_transverse_lever_arms:
        w = _rates_at(schedule, np.r_[truth.t_s[0] - dt_s, truth.t_s], truth.q_bn_base, lat_rad)
        wd = np.diff(w, axis=0) / dt_s
    th, dv = errs.apply_increments(truth.dtheta_rad, truth.dv_m_s, dt_s, omega_dot_rad_s2=wd)
    if noise is not None:
        rng = np.random.default_rng(seed)
        n = th.shape[0]
        arw = noise.gyro_arw_deg_sqrt_h * np.pi / 180.0 / 60.0
        asd = noise.accel_vrw_ug_sqrt_hz * UG
        th = th + rng.normal(0.0, arw * np.sqrt(dt_s), (n, 3))
        dv = dv + rng.normal(0.0, asd * np.sqrt(dt_s / 2.0), (n, 3))
    return truth.imu_record(th, dv, source="gfins_fmi.calibration.system.simulate_record"), truth


def covariance_study(schedule, lat_rad: float, h_m: float, config: SyscalConfig | None = None,
                     dt_s: float = 0.05) -> dict:
    """What a path can observe, before anything is recorded: the filter run on the exact
    increments of ``schedule`` (no errors, no noise; the covariance of a linear filter
    does not depend on the data) gives the final 1-sigma of each parameter. Returns
    ``{"names", "std", "prior_std", "ratio"}`` (SI, model order)."""
    config = config or SyscalConfig()
    truth = simulate_static(schedule, schedule.duration_s, dt_s, lat_rad, h_m)
    f = SyscalFilter(config, lat_rad, h_m, truth.q_mn[0], t0_s=0.0)
    f.run(truth.t_s, truth.dtheta_rad, truth.dv_m_s)
    std = f.std()[9:]
    prior = config.params_std()
    return {"names": config.names, "std": std, "prior_std": prior, "ratio": std / prior}
