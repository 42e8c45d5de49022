"""System-level calibration of a rotating INS (seed 001, steps S3-S5) on a raw
multi-position record, with the filter of :mod:`gfins_fmi.calibration.syscal_filter`.

:func:`calibrate` takes a raw record (any rate, increments or rates) of an IMU turned
through any sequence of rotations at a known site: it checks units and sampling, finds
the static intervals and the turns, aligns coarsely on the first static interval, runs
the filter (``passes`` > 1 re-runs it from the previous estimates), and reports every
parameter with its standard deviation and the ones the path cannot observe.
:func:`simulate_record` is the forward model (gf_rotation's exact increments, the
gf_imu_error model with seed 001's angles, white noise) for tests and studies;
:func:`covariance_study` tells what a path can observe before anything is recorded.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import as_array, as_scalar
from gfins_fmi.calibration.segmentation import check_record, record_increments, segment_record
from gfins_fmi.calibration.syscal_filter import (N_PARAMS, PARAM_NAMES, PARAM_UNITS,
                                                 CalibrationInputError, Prior, SyscalConfig,
                                                 SyscalFilter, params_to_imu_errors)
from gfins_fmi.estimation.alignment import attitude_from_gravity_and_earth_rate
from gfins_fmi.nav.imu_errors import UG, ImuErrors, ImuNoise
from gfins_fmi.sim.rotation import simulate_static

__all__ = ["CalibrationReport", "calibrate", "random_params", "simulate_record",
           "covariance_study", "plot_report"]

@dataclass
class CalibrationReport:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    estimate, std, prior_std : (n_params,) SI, PARAM_NAMES order (27 or 28)
    ratio : std / prior_std (1: the record says nothing about the parameter)
    unobservable, weak : names with ratio > 0.9 and 0.3 < ratio <= 0.9
    errors : ImuErrors of the estimates (use it to compensate: ImuErrors.compensate)
    accel_delay_s : estimated delay (0 unless estimated)
    epochs : the updates of the last pass (SyscalFilter.epochs)
    pass_epochs : the updates of every pass (the first shows the convergence from the prior)
    segments : the static intervals and turns found
    positions : per static interval, the RMS velocity residual (m/s) of the last pass
    passes, q_mn0, notes
    """
    estimate: np.ndarray
    std: np.ndarray
    prior_std: np.ndarray
    names: tuple
    errors: ImuErrors
    accel_delay_s: float
    epochs: dict
    segments: list
    positions: list
    passes: int
    q_mn0: np.ndarray
    covariance: np.ndarray
    pass_epochs: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def ratio(self) -> np.ndarray:
        return self.std / self.prior_std

    @property
    def unobservable(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if r > 0.9]

    @property
    def weak(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if 0.3 < r <= 0.9]

    def in_units(self, values_si) -> np.ndarray:
        """Values in the datasheet units of PARAM_UNITS."""
        return np.asarray(values_si) / np.array([u[1] for u in PARAM_UNITS[:len(self.names)]])

    def table(self) -> str:
        """Markdown: parameter, estimate, 1-sigma, prior 1-sigma, std/prior, note."""
        lines = ["| parameter | unit | estimate | 1-sigma | prior 1-sigma | std/prior |",
                 "|---|---|---|---|---|---|"]
        est, sd, pr = self.in_units(self.estimate), self.in_units(self.std), self.in_units(self.prior_std)
        for k, name in enumerate(self.names):
            note = " (not observed)" if self.ratio[k] > 0.9 else " (weak)" if self.ratio[k] > 0.3 else ""
            lines.append(f"| {name} | {PARAM_UNITS[k][0]} | {est[k]:.5g} | {sd[k]:.3g} | {pr[k]:.3g} | "
                         f"{self.ratio[k]:.3g}{note} |")
        return "\n".join(lines)


def calibrate(record, lat_rad: float, h_m: float, *, lon_rad: float = 0.0,
              config: SyscalConfig | None = None, passes: int = 2, params0=None,
              rate_threshold_deg_s: float = 0.5, min_static_s: float = 5.0,
              min_align_s: float = 30.0, max_angle_per_sample_deg: float = 3.0,
              heading_rad: float | None = None, checks: str = "raise") -> CalibrationReport:
    """System-level calibration of a raw multi-position record (seed 001 S4-S5).

    Parameters
    ----------
    record : gfins_fmi.io.ImuRecord
        Raw IMU samples (increments or rates, any rate) in the IMU frame m, at rest on a
        turntable or the rotating INS's own mechanism, starting at rest.
    lat_rad, h_m, lon_rad : the site (known; seed 001 S501), |lat| < 89 deg.
    config : SyscalConfig (noise densities, prior, 36 or 37 states).
    passes : runs of the filter; each pass is linearised about the previous pass's
        estimates (iterated linearisation), with the prior of ``config.prior`` centred on
        ``params0``: a pass that starts from estimates x_lin has its prior centred there
        instead, and its result is re-centred exactly (linear-Gaussian posterior:
        x += P_pp P0^-1 (params0 - x_lin)); without this the prior would be replaced by
        the previous pass's estimates, the data counted twice where the prior matters
        (weakly observed parameters: their reported sigma too small).
    params0 : prior mean of the parameters, SI, 27 or 28 (default 0: nominal IMU).
    rate_threshold_deg_s, min_static_s : segmentation (:func:`segment_record`).
    min_align_s : shortest first static interval (the coarse alignment).
    max_angle_per_sample_deg : turning faster than this per sample is refused.
    heading_rad : not used for the alignment (gyrocompassing gives it); kept for records
        whose gyros cannot see the Earth rate: then the first position's heading.
    checks : {"raise", "warn", "off"}
        A site latitude the Earth rate measured in the static intervals contradicts
        (more than 5 sigma of the prior's gyro bias and 2 deg away: the record was made
        elsewhere) raises :class:`CalibrationInputError`, warns or passes.

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
    config = config or SyscalConfig()
    lat = float(lat_rad)
    if not (np.isfinite(lat) and abs(lat) < np.radians(89.0)):
        raise CalibrationInputError(f"lat_rad = {float(lat_rad)!r}: the site's latitude must be within +-89 deg "
                                    "(in radians: np.radians)")
    h = as_scalar("h_m", h_m, "m", at_least=-1000.0, at_most=1e5)
    if not (isinstance(passes, int) and 1 <= passes <= 10):
        raise ValueError(f"passes must be an integer in 1..10; got {passes!r}")
    t_end, dt, dth, dv = record_increments(record)
    segs = segment_record(t_end, dth, rate_threshold_deg_s, min_static_s=min_static_s)
    check_record(t_end, dt, dth, dv, segs, lat, h, min_align_s, np.radians(max_angle_per_sample_deg),
                 gyro_std_rad_s=np.radians(config.prior.gyro_bias_deg_h) / 3600.0, checks=checks)
    n_p = config.n_states - 9
    p = np.zeros(N_PARAMS)
    if params0 is not None:
        v = as_array("params0", params0, (None,), "SI")
        p[:v.size] = v
    mu = p.copy()                                   # the prior's mean
    prior_var = config.prior.params_std()[:n_p] ** 2
    first = next(s for s in segs if s.kind == "static")
    notes = []
    t0 = float(t_end[0] - dt[0])
    pass_epochs = []
    for k in range(passes):
        # coarse alignment on the first static interval, with the current compensation
        errs = params_to_imu_errors(p)
        sl = slice(first.i0, first.i1)
        w_c, f_c = errs.compensate_increments(dth[sl], dv[sl], dt[sl])
        q0 = attitude_from_gravity_and_earth_rate(f_c.sum(axis=0), w_c.sum(axis=0))
        filt = SyscalFilter(config, lat, h, q0, lon_rad=lon_rad, params0=p, t0_s=t0)
        filt.run(t_end, dth, dv)
        P = filt.covariance()
        # the filter's prior was N(p, P0); the prior is N(mu, P0): the parameters are
        # constant states, so moving the prior's mean by d moves the posterior mean by
        # P_pp P0^-1 d (the covariance does not change)
        d = mu[:n_p] - p[:n_p]
        p = filt.params
        p[:n_p] += P[9:, 9:] @ (d / prior_var)
        pass_epochs.append(filt.epochs())
    est = p[:n_p].copy()
    std = np.sqrt(np.diag(P))[9:]
    prior = config.prior.params_std()[:n_p]
    ep = pass_epochs[-1]
    positions = []
    for s in segs:
        if s.kind != "static":
            continue
        m = (ep["t_s"] > s.t0_s) & (ep["t_s"] <= s.t1_s)
        rms = float(np.sqrt(np.mean(ep["residual_m_s"][m] ** 2))) if m.any() else float("nan")
        positions.append({"t0_s": s.t0_s, "t1_s": s.t1_s, "rms_residual_m_s": rms})
    return CalibrationReport(est, std, prior, PARAM_NAMES[:n_p], params_to_imu_errors(est),
                             float(p[-1]) if config.estimate_delay else 0.0, ep, segs,
                             positions, passes, q0, P, pass_epochs, notes)


# ---- forward model and studies ---------------------------------------------------------------

def random_params(rng: np.random.Generator, prior: Prior | None = None, n_params: int = 27) -> np.ndarray:
    """A random error set drawn from the prior (zero mean, the prior's 1-sigma), SI."""
    prior = prior or Prior()
    return rng.normal(0.0, prior.params_std()[:n_params])


def simulate_record(schedule, params_si, lat_rad: float, h_m: float, dt_s: float = 0.01, *,
                    duration_s: float | None = None, heading_rad: float = 0.0,
                    noise: ImuNoise | None = None, seed: int = 0, accel_delay_s: float = 0.0):
    """A raw record of an IMU with the errors ``params_si`` (27 or 28 values; a 28th is
    the accelerometer delay, overriding ``accel_delay_s``) turned by ``schedule``
    (:class:`gfins_fmi.sim.rotation.RotationSchedule`) on a static level base: exact
    increments (gf_rotation), the error model (gf_imu_error via
    :func:`params_to_imu_errors`), white noise (``noise``: its angle random walk and
    accelerometer white noise are used), seeded. Returns an ImuRecord of increments and
    the RotatingImuRecord of the truth."""
    p = as_array("params_si", params_si, (None,), "SI")
    if p.size == N_PARAMS:
        accel_delay_s = float(p[-1])
    dur = schedule.duration_s if duration_s is None else duration_s
    truth = simulate_static(schedule, dur, dt_s, lat_rad, h_m, heading_rad=heading_rad,
                            accel_delay_s=accel_delay_s)
    errs = params_to_imu_errors(p[:N_PARAMS - 1] if p.size == N_PARAMS else p)
    th, dv = errs.apply_increments(truth.dtheta_rad, truth.dv_m_s, dt_s)
    if noise is not None:
        rng = np.random.default_rng(seed)
        n = th.shape[0]
        arw = noise.gyro_arw_deg_sqrt_h * np.pi / 180.0 / 60.0
        asd = noise.accel_vrw_ug_sqrt_hz * UG
        th = th + rng.normal(0.0, arw * np.sqrt(dt_s), (n, 3))
        dv = dv + rng.normal(0.0, asd * np.sqrt(dt_s / 2.0), (n, 3))
    return truth.imu_record(th, dv, source="gfins_fmi.estimation.calibration36.simulate_record"), truth


def covariance_study(schedule, lat_rad: float, h_m: float, config: SyscalConfig | None = None,
                     dt_s: float = 0.05) -> dict:
    """What a path can observe, before anything is recorded: the filter run on the exact
    increments of ``schedule`` (no errors, no noise; the covariance of a linear filter
    does not depend on the data) gives the final 1-sigma of each parameter. Returns
    ``{"names", "std", "prior_std", "ratio"}`` (SI)."""
    config = config or SyscalConfig()
    truth = simulate_static(schedule, schedule.duration_s, dt_s, lat_rad, h_m)
    f = SyscalFilter(config, lat_rad, h_m, truth.q_mn[0], t0_s=0.0)
    f.run(truth.t_s, truth.dtheta_rad, truth.dv_m_s)
    n_p = config.n_states - 9
    std = f.std()[9:]
    prior = config.prior.params_std()[:n_p]
    return {"names": PARAM_NAMES[:n_p], "std": std, "prior_std": prior, "ratio": std / prior}


def plot_report(rep: CalibrationReport, folder, truth=None,
                names=("gyro_scale_x", "gyro_gamma_zx", "gyro_bias_z", "accel_scale_y",
                       "accel_alpha_yx", "accel_bias_z", "accel_k2_x", "lever_arm_y", "lever_arm_z"),
                tag: str = "", save=None) -> list:
    """Two figures in ``folder``: the first pass's estimates of nine parameters with
    +-1 sigma bands (and ``truth``, SI, if known), and the zero-velocity residuals of the
    last pass with the static intervals shaded. Returns their paths. ``save``: where a
    figure's bytes go, given its path (e.g. an output set's temporary,
    :meth:`gfins_fmi.io.output_set.OutputSet.file`); default: the path itself."""

    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ep = rep.pass_epochs[0]
    t = ep["t_s"] / 60.0
    fig, axes = plt.subplots(3, 3, figsize=(13, 9), constrained_layout=True)
    for ax, name in zip(axes.ravel(), names):
        k = PARAM_NAMES.index(name)
        unit, si = PARAM_UNITS[k]
        est, sd = ep["params"][:, k] / si, ep["std"][:, 9 + k] / si
        ax.fill_between(t, est - sd, est + sd, color="C0", alpha=0.3, label="estimate +- 1 sigma")
        ax.plot(t, est, "C0", lw=1)
        centre = est[-1]
        if truth is not None:
            ax.axhline(truth[k] / si, color="k", ls="--", lw=1, label="truth")
            centre = truth[k] / si
        ax.set_ylim(centre - 1.5 * sd[0], centre + 1.5 * sd[0])
        ax.set_title(f"{name} ({unit})", fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("time (min)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("system calibration, first pass from the prior: estimates with +-1 sigma")
    save = save or (lambda path: path)
    f1 = folder / f"syscal_convergence{tag}.png"
    fig.savefig(save(f1), dpi=90)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(12, 4), constrained_layout=True)
    for s in rep.segments:
        if s.kind == "static":
            ax.axvspan(s.t0_s / 60, s.t1_s / 60, color="0.9")
    last = rep.epochs
    for i, c in enumerate("ENU"):
        ax.plot(last["t_s"] / 60.0, last["residual_m_s"][:, i] * 1e3, lw=0.7, label=f"v_{c}")
    ax.set(xlabel="time (min); shaded: static intervals", ylabel="velocity residual (mm/s)",
           title="zero-velocity residual at each update (last pass)")
    ax.legend(fontsize=8)
    f2 = folder / f"syscal_residuals{tag}.png"
    fig.savefig(save(f2), dpi=90)
    plt.close(fig)
    return [f1, f2]
