"""The result of a system-level calibration (:func:`gfins_fmi.calibration.system.calibrate`)
and how it is read: the table of estimates with their sigmas, priors and shifts against
the prior, the checks and warnings (:mod:`gfins_fmi.calibration.diagnostics`), both
conventions of the result (our forward model as :class:`gfins_fmi.ImuErrors`, the
compensation form of :mod:`gfins_fmi.calibration.compensation`), the JSON document of
``gfins calibrate --json`` and the figures."""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi.calibration.compensation import to_compensation
from gfins_fmi.nav.imu_errors import ImuErrors

__all__ = ["CalibrationReport", "plot_report"]


@dataclass
class CalibrationReport:
    """Result of :func:`gfins_fmi.calibration.system.calibrate`.

    Attributes
    ----------
    estimate, std, prior_std, prior_mean : (n_params,) SI, model order (``names``)
    names, units : the model's parameters and their (label, SI value of one unit)
    model, n_states : "full" or "seed"; the filter's state count
    ratio : std / prior_std (1: the record says nothing about the parameter)
    unobservable, weak : names with ratio > 0.9 and 0.3 < ratio <= 0.9
    errors : ImuErrors of the estimates (forward model, IMU = gyro frame; use it to
        compensate: ImuErrors.compensate, or the SINS FMU: errors.fmu_parameters())
    accel_delay_s : estimated delay (0 unless estimated)
    covariance : the final covariance of the states (n_states x n_states)
    epochs, pass_epochs : the updates of the last pass, and of every pass
    segments, positions : the static intervals and turns; per static interval the RMS
        velocity residual (m/s) of the last pass
    diagnostics : :class:`gfins_fmi.calibration.diagnostics.Diagnostics` (prior shifts,
        block tests, NIS, missing terms); ``warnings`` its sentences
    grade, grade_figures : the IMU grade whose defaults were used (None: the caller's
        configuration) and what the first static interval showed
    rounds : the priors of each round when the run widened them (widen_priors)
    gravity_m_s2 : the site's gravity the filter used
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
    prior_mean: np.ndarray = None
    units: tuple = ()
    model: str = "seed"
    diagnostics: object = None
    grade: str | None = None
    grade_figures: dict = field(default_factory=dict)
    rounds: list = field(default_factory=list)
    gravity_m_s2: float = float("nan")

    def __post_init__(self):
        if self.prior_mean is None:
            self.prior_mean = np.zeros_like(self.estimate)

    @property
    def n_states(self) -> int:
        return int(self.covariance.shape[0])

    @property
    def ratio(self) -> np.ndarray:
        return self.std / self.prior_std

    @property
    def unobservable(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if r > 0.9]

    @property
    def weak(self) -> list:
        return [n for n, r in zip(self.names, self.ratio) if 0.3 < r <= 0.9]

    @property
    def warnings(self) -> list:
        return list(self.diagnostics.warnings) if self.diagnostics is not None else []

    def in_units(self, values_si) -> np.ndarray:
        """Values in the datasheet units of ``units``."""
        return np.asarray(values_si) / np.array([u[1] for u in self.units[:len(self.names)]])

    def compensation(self):
        """The result in the compensation form (PSINS clbt fields, accelerometer frame):
        :class:`gfins_fmi.calibration.compensation.CompensationForm`."""
        return to_compensation(self.errors)

    def table(self) -> str:
        """Markdown: parameter, estimate, 1-sigma, prior 1-sigma, std/prior, shift against the
        prior (prior sigmas), note."""
        lines = ["| parameter | unit | estimate | 1-sigma | prior 1-sigma | std/prior | shift (prior sigma) |",
                 "|---|---|---|---|---|---|---|"]
        est, sd, pr = self.in_units(self.estimate), self.in_units(self.std), self.in_units(self.prior_std)
        shift = (self.estimate - self.prior_mean) / self.prior_std
        fights = set(self.diagnostics.fights) if self.diagnostics is not None else set()
        for k, name in enumerate(self.names):
            note = " (not observed)" if self.ratio[k] > 0.9 else " (weak)" if self.ratio[k] > 0.3 else ""
            fight = " **fights its prior**" if name in fights else ""
            lines.append(f"| {name} | {self.units[k][0]} | {est[k]:.5g} | {sd[k]:.3g} | {pr[k]:.3g} | "
                         f"{self.ratio[k]:.3g}{note} | {shift[k]:+.3g}{fight} |")
        return "\n".join(lines)

    def summary(self) -> str:
        """The checks in a few lines: NIS, block tests, missing terms, warnings."""
        d = self.diagnostics
        if d is None:
            return ""
        nis = d.nis
        out = [f"mean NIS of the zero-velocity updates: {nis['mean']:.3g} (99% band "
               f"[{nis['band'][0]:.3g}, {nis['band'][1]:.3g}] for {nis['n']} updates; at rest "
               f"{nis['rest']['mean']:.3g}, turning {nis['turning']['mean']:.3g}"
               f"{'; ' + str(nis['refused']) + ' refused' if nis['refused'] else ''})"]
        blocks = ", ".join(f"{b['field']} {b['nees']:.3g}/{b['dof']}{'' if b['ok'] else ' (!)'}"
                           for b in d.blocks)
        out.append(f"prior consistency per block (chi-square / dof; 99.9% bound): {blocks}")
        if d.missing is not None:
            m = d.missing
            vals = ", ".join(f"{n} {v / u[1]:.3g} +- {s / u[1]:.2g} {u[0]}"
                             for n, v, s, u in zip(m["names"], m["values"], m["stds"], m["units"]))
            out.append(f"terms the {self.model} model lacks (full-model pass): {vals}; chi-square "
                       f"{m['chi2']:.3g} (99.9% bound {m['bound']:.3g}){' FLAGGED' if m['flagged'] else ''}")
        if self.rounds:
            out.append(f"priors widened over {len(self.rounds)} rounds: " +
                       "; ".join(", ".join(f"{k} {v:g}" for k, v in r.items()) or "-" for r in self.rounds))
        out += [f"WARNING: {w}" for w in d.warnings]
        return "\n".join(out)

    def document(self) -> dict:
        """The JSON document of ``gfins calibrate --json``: both conventions, the checks."""
        d = self.diagnostics
        doc = {"model": self.model, "n_states": self.n_states, "grade": self.grade,
               "names": list(self.names), "estimate_si": self.estimate.tolist(),
               "std_si": self.std.tolist(), "prior_std_si": self.prior_std.tolist(),
               "units": [u[0] for u in self.units[:len(self.names)]],
               "estimate_units": self.in_units(self.estimate).tolist(),
               "std_units": self.in_units(self.std).tolist(),
               "shift_prior_sigma": ((self.estimate - self.prior_mean) / self.prior_std).tolist(),
               "unobservable": self.unobservable, "weak": self.weak,
               "fmu_parameters": self.errors.fmu_parameters(), "accel_delay_s": self.accel_delay_s,
               "compensation_form": self.compensation().to_dict(),
               "gravity_m_s2": self.gravity_m_s2, "warnings": self.warnings}
        if d is not None:
            doc["nis"] = {"mean": d.nis["mean"], "band": list(d.nis["band"]), "refused": d.nis["refused"]}
            doc["fights_prior"] = list(d.fights)
        return doc


def plot_report(rep: CalibrationReport, folder, truth=None, names=None, tag: str = "",
                save=None) -> list:
    """Two figures in ``folder``: the first pass's estimates of nine parameters with
    +-1 sigma bands (and ``truth``, SI, model order, if known), and the zero-velocity
    residuals of the last pass with the static intervals shaded. Returns their paths.
    ``save``: where a figure's bytes go, given its path (e.g. an output set's temporary,
    :meth:`gfins_fmi.io.output_set.OutputSet.file`); default: the path itself."""
    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if names is None:
        lever = ("lever_ry_x", "lever_rx_z") if rep.model == "full" else ("lever_arm_y", "lever_arm_z")
        names = ("gyro_scale_x", "gyro_gamma_zx", "gyro_bias_z", "accel_scale_y", "accel_alpha_yx",
                 "accel_bias_z", "accel_k2_x") + lever
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ep = rep.pass_epochs[0]
    t = ep["t_s"] / 60.0
    fig, axes = plt.subplots(3, 3, figsize=(13, 9), constrained_layout=True)
    for ax, name in zip(axes.ravel(), names):
        k = rep.names.index(name)
        unit, si = rep.units[k]
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
