"""Predicted versus simulated error growth: the scenarios and the ``gfins analyze`` report.

Each scenario runs the C core ``runs`` times with random sensor errors (through
``montecarlo.run``, so on any executor) and propagates the same errors through the
matching python-control model (``strapdown_errors``, ``gyrofree_errors``); the report puts both side by side,
as a table of 1-sigma values and ratios and as a figure per configuration.

Scenarios (sensor errors are random constants plus white noise, 1-sigma per sensor):

* ``sins``: strapdown at rest at 30 deg latitude, 1 h at 10 Hz, height held; gyro bias
  0.01 deg/h, accelerometer bias 50 ug, ARW 0.002 deg/sqrt(h), accelerometer white noise
  20 ug/sqrt(Hz).
* ``cube6``, ``qin9``, ``12``: gyro-free INS at rest (rate strategy ``integrate``, flat
  frame with g = 9.8 m/s^2, lever arm 0.1 m), 20 s at 100 Hz; accelerometer bias
  1e-5 m/s^2 and white noise 1e-4 m/s^2 per sample. The vertical position is reported
  but its linear prediction is known to fail (second-order tilt term g |phi|^2 / 2).
* ``qin9-sqrt``, ``12-sqrt``, ``qin9-fused``, ``12-fused``: the same arrays and errors
  rotating at a constant body rate ``ROTATION_RAD_S`` about a point fixed in the frame,
  rate strategy ``sqrt`` (seed 000: |w_k| from the measured w_k^2) or ``fused`` (the EKF
  on [w, w_dot bias] with its default tuning).
"""
from __future__ import annotations

import concurrent.futures as cf
import pathlib
from dataclasses import dataclass

import numpy as np

from gfins_fmi.analysis import montecarlo as mc
from gfins_fmi.analysis.covariance import covariance, propagate
from gfins_fmi.analysis.gyrofree_errors import gyrofree_error_model, gyrofree_fused_std
from gfins_fmi.analysis.strapdown_errors import sins_error_model
from gfins_fmi.estimation.config import UG as _UG
from gfins_fmi.gyrofree.array import forward_model
from gfins_fmi.gyrofree.geometry import layout
from gfins_fmi.gyrofree.navigator import GyroFreeNavigator
from gfins_fmi.nav.earth import (attitude_error_rad, euler_to_quat, quat_multiply, quat_to_dcm, radii,
                                 rotation_matrix)
from gfins_fmi.nav.imu_errors import DEG_H as _DEG_H
from gfins_fmi.nav.strapdown import NavState, SinsConfig, Strapdown
from gfins_fmi.sim import trajectory as tj

__all__ = ["CONFIGS", "GrowthComparison", "compare", "write_report"]

CONFIGS = ("sins", "cube6", "qin9", "12", "qin9-sqrt", "12-sqrt", "qin9-fused", "12-fused")
#: the rotating scenarios' constant body rate (rad/s): every component away from zero
ROTATION_RAD_S = (1.0, -0.8, 0.6)


@dataclass
class GrowthComparison:
    """Predicted and Monte-Carlo 1-sigma of some navigation errors.

    Attributes
    ----------
    config : str
    t_s : (k,) times (s)
    labels : output names (attitude in rad, position in m)
    predicted, simulated : (k, len(labels)) 1-sigma
    runs : int
    linear_fails : labels whose linear prediction is known not to hold
    """
    config: str
    t_s: np.ndarray
    labels: tuple
    predicted: np.ndarray
    simulated: np.ndarray
    runs: int
    linear_fails: tuple = ()

    @property
    def ratio(self) -> np.ndarray:
        """simulated / predicted."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.simulated / self.predicted


def _sins(runs, seed, executor, progress, times):
    dt = 0.1
    times = np.asarray(times if times is not None else [300, 600, 1200, 1800, 2400, 3000, 3600], float)
    tr = tj.sample(tj.Stationary(), float(times[-1]), dt)
    x0 = NavState.from_trajectory(tr, 0)
    sbg, sba = 0.01 * _DEG_H, 50 * _UG
    arw, vrw = 0.002 * np.pi / 180 / 60, 20 * _UG
    idx = np.round(times / dt).astype(int) - 1
    cfg = SinsConfig(vertical="hold")          # held at the initial height
    RM, RN, _, _ = radii(tr.lat_rad[0])

    def task(k, rng):
        n = len(tr.dtheta_rad)
        dth = tr.dtheta_rad + rng.normal(0, sbg, 3) * dt + rng.normal(0, arw * np.sqrt(dt), (n, 3))
        dv = tr.dv_m_s + rng.normal(0, sba, 3) * dt + rng.normal(0, vrw * np.sqrt(dt), (n, 3))
        sol = Strapdown(x0, cfg).run(dth, dv, dt_s=dt)
        att = attitude_error_rad(sol.q_bn[idx], tr.q_bn[1:][idx])
        dn = (sol.lat_rad[idx] - tr.lat_rad[1:][idx]) * RM
        de = (sol.lon_rad[idx] - tr.lon_rad[1:][idx]) * RN * np.cos(tr.lat_rad[0])
        return dict(out=np.c_[att, dn, de])

    out = mc.run(task, runs, seed=seed, executor=executor, progress=progress, desc="sins")["out"]
    sys = sins_error_model(tr.lat_rad[0], tr.q_bn[0], tr.h_m[0])
    pred = covariance(sys, times, sbg, sba, arw, vrw, dt_s=1.0).std[:, [0, 1, 2, 5, 6]]
    return GrowthComparison("sins", times, ("phi_E", "phi_N", "phi_U", "north", "east"),
                            pred, out.std(axis=0), runs)


def _gyrofree(config, runs, seed, executor, progress, times):
    name, _, strategy = config.partition("-")
    strategy = strategy or "integrate"
    w = np.array(ROTATION_RAD_S if strategy != "integrate" else (0.0, 0.0, 0.0))
    dt, g, b_std, sigma = 0.01, 9.8, 1e-5, 1e-4
    times = np.asarray(times if times is not None else [2.5, 5, 7.5, 10, 12.5, 15, 17.5, 20], float)
    idx = np.round(times / dt).astype(int)
    q0 = euler_to_quat(0.1, -0.05, 0.7)
    n = int(idx[-1]) + 1
    t = np.arange(n) * dt
    # truth: rotation about a fixed axis, C(t) = C0 exp([w x] t), q(t) = q0 (x) q(w t)
    C = quat_to_dcm(q0) @ np.array([rotation_matrix(w * tk) for tk in t])
    fb = np.einsum("kji,j->ki", C, np.array([0.0, 0.0, g]))
    rate = np.linalg.norm(w)
    axis = w / rate if rate > 0 else w
    q_true = quat_multiply(np.tile(q0, (n, 1)), np.c_[np.cos(rate * t / 2), np.sin(rate * t / 2)[:, None] * axis])
    geo = layout(name, 0.1)
    A0 = forward_model(geo, fb, np.tile(w, (n, 1)), np.zeros((n, 3)))
    x0 = NavState(q0, np.zeros(3), 0.0, 0.0, 0.0, 0.0, np.zeros(3))
    cfg = SinsConfig(earth="flat", flat_gravity_m_s2=g)

    def task(k, rng):
        A = A0 + rng.normal(0, b_std, A0.shape[1]) + rng.normal(0, sigma, A0.shape)
        sol, _ = GyroFreeNavigator(geo, x0, strategy, w, accel_noise_m_s2=sigma, sins=cfg).run(A, dt)
        att = attitude_error_rad(sol.q_bn[idx], q_true[idx])
        return dict(out=np.c_[att, sol.pos_m[idx]])

    out = mc.run(task, runs, seed=seed, executor=executor, progress=progress, desc=config)["out"]
    # a sampled white noise of std sigma at interval dt has density sigma sqrt(dt)
    if strategy == "fused":
        pred = gyrofree_fused_std(geo, times, b_std, sigma, q0, g, w, dt)
    else:
        model = gyrofree_error_model(geo, q0, g, strategy, w, dt)
        pred = propagate(model, times, b_std, sigma * np.sqrt(dt), dt_s=dt)
    return GrowthComparison(config, times, ("phi_x", "phi_y", "phi_z", "x", "y", "z"),
                            pred.std[:, [0, 1, 2, 6, 7, 8]], out.std(axis=0), runs,
                            ("z",) if strategy == "integrate" else ())


def compare(config: str, runs: int = 200, seed: int = 0, executor: cf.Executor | None = None,
            progress: bool = False, times=None) -> GrowthComparison:
    """Run one scenario (see the module docstring): ``runs`` Monte-Carlo runs of the C
    core and the model's prediction at ``times`` (s; default: a scenario-specific grid).

    Raises
    ------
    ValueError
        Unknown configuration, or runs < 2.
    """
    if config not in CONFIGS:
        raise ValueError(f"unknown configuration {config!r}; choose one of {', '.join(CONFIGS)}")
    if not isinstance(runs, (int, np.integer)) or runs < 2:
        raise ValueError(f"runs must be an integer >= 2 (a standard deviation needs two); got {runs!r}")
    if config == "sins":
        return _sins(runs, seed, executor, progress, times)
    return _gyrofree(config, runs, seed, executor, progress, times)


def _plot(c: GrowthComparison, path: pathlib.Path) -> None:
    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    att = [i for i, n in enumerate(c.labels) if n.startswith("phi")]
    pos = [i for i, n in enumerate(c.labels) if not n.startswith("phi")]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    t_unit, ts = ("min", c.t_s / 60) if c.t_s[-1] > 600 else ("s", c.t_s)
    for ax, cols, scale, unit in ((axes[0], att, np.degrees(1.0), "deg"), (axes[1], pos, 1.0, "m")):
        for j, i in enumerate(cols):
            color = f"C{j}"
            ax.plot(ts, c.predicted[:, i] * scale, "-", color=color, label=f"{c.labels[i]} model")
            ax.plot(ts, c.simulated[:, i] * scale, "o", color=color, mfc="none",
                    label=f"{c.labels[i]} Monte Carlo" + (" (nonlinear)" if c.labels[i] in c.linear_fails else ""))
        ax.set_xlabel(f"time ({t_unit})")
        ax.set_ylabel(f"1σ ({unit})")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title(f"{c.config}: attitude error")
    axes[1].set_title(f"{c.config}: position error")
    fig.suptitle(f"Predicted (python-control) vs {c.runs}-run Monte Carlo of the C core")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_report(out_dir, configs=CONFIGS, runs: int = 1000, seed: int = 0,
                 executor: cf.Executor | None = None, progress: bool = True) -> pathlib.Path:
    """Run the scenarios of ``configs`` and write ``report.md`` with one figure per
    configuration into ``out_dir``; returns the report's path. Ratios outside 0.9..1.1
    are marked; the sampling error of a std over N runs is about 1/sqrt(2N)."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    lines = ["# Error growth: python-control models against Monte-Carlo runs of the C core", "",
             f"{runs} runs per configuration, seed {seed}; the sampling error of a standard "
             f"deviation over {runs} runs is about {100 / np.sqrt(2 * runs):.1f}%. "
             "Attitude in degrees, position in metres; ratio = Monte Carlo / model "
             "(**bold**: outside 0.9..1.1).", ""]
    for config in configs:
        c = compare(config, runs, seed, executor, progress)
        fig = out / f"error_growth_{config}.png"
        _plot(c, fig)
        lines += [f"## {config}", "", f"![{config}]({fig.name})", ""]
        scale = [np.degrees(1.0) if n.startswith("phi") else 1.0 for n in c.labels]
        lines.append("| t (s) | " + " | ".join(f"{n} model / MC / ratio" for n in c.labels) + " |")
        lines.append("|---" * (len(c.labels) + 1) + "|")
        for k, t in enumerate(c.t_s):
            cells = []
            for i in range(len(c.labels)):
                r = c.ratio[k, i]
                rs = f"{r:.3f}" if abs(r - 1) <= 0.1 else f"**{r:.3f}**"
                cells.append(f"{c.predicted[k, i] * scale[i]:.3g} / {c.simulated[k, i] * scale[i]:.3g} / {rs}")
            lines.append(f"| {t:g} | " + " | ".join(cells) + " |")
        if c.linear_fails:
            lines += ["", f"Linearisation known to fail for {', '.join(c.linear_fails)}: the "
                      "vertical channel is driven by the second-order tilt term g|φ|²/2, which "
                      "outgrows the linear (bias) term."]
        lines.append("")
    path = out / "report.md"
    path.write_text("\n".join(lines))
    return path
