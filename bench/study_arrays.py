"""Which accelerometer arrays work with which rate strategy: the geometry report's
verdicts over random arrays, and the loop analysis against a simulation.

    python bench/study_arrays.py [--arrays 600] [--seed 1402] [--out docs/figures/gyrofree]

Draws random arrays of N = 6..30 single-axis accelerometers (positions uniform within
0.2 m, directions uniform on the sphere), tabulates per N the observed product
combinations and the verdict of each strategy (gfins_fmi.geometry_report, |w| <= 5 rad/s,
100 Hz), and plots (a) the share of arrays each strategy navigates (stable or marginal
loop) against N, (b) for one 10-sensor array, the rate error of a constant-rate
simulation of 'integrate' (predicted unstable) beside the analysis' growth exp(g t), and
'sqrt' and 'fused' on the same array (both stable).
"""
from __future__ import annotations

import argparse
import pathlib
import warnings

import numpy as np

import gfins_fmi as gf
from gfins_fmi.gyrofree.rate_solver import UnstableRateLoopWarning

STRATEGIES = ("integrate", "sqrt", "eigen", "fused")


def random_geometry(rng, n):
    u = rng.uniform(-0.2, 0.2, (n, 3))
    th = rng.normal(size=(n, 3))
    return gf.ArrayGeometry(u, th / np.linalg.norm(th, axis=1, keepdims=True))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arrays", type=int, default=600)
    ap.add_argument("--seed", type=int, default=1402)
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/gyrofree"))
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    Ns = np.arange(6, 31)
    counts = {n: {"arrays": 0, "n_obs": [], **{s: {"stable": 0, "marginal": 0, "unstable": 0,
                                                    "not applicable": 0} for s in STRATEGIES}}
              for n in Ns}
    example = None
    for _ in range(args.arrays):
        n = int(rng.integers(6, 31))
        g = random_geometry(rng, n)
        rep = gf.geometry_report(g)
        c = counts[n]
        c["arrays"] += 1
        c["n_obs"].append(len(rep.observed))
        for s in STRATEGIES:
            c[s][rep.stability[s].verdict] += 1
        if (example is None and n == 10 and rep.stability["integrate"].verdict == "unstable"
                and rep.stability["fused"].verdict == "stable"):
            example = (g, rep)

    print("| N | arrays | observed products | integrate s/m/u | sqrt s/u/n.a. | eigen s/n.a. | fused s/m/u/n.a. |")
    print("|---|---|---|---|---|---|---|")
    for n in Ns:
        c = counts[n]
        if not c["arrays"]:
            continue
        obs = sorted(set(c["n_obs"]))
        print(f"| {n} | {c['arrays']} | {obs[0]}" + (f"–{obs[-1]}" if len(obs) > 1 else "")
              + f" | {c['integrate']['stable']}/{c['integrate']['marginal']}/{c['integrate']['unstable']}"
              + f" | {c['sqrt']['stable']}/{c['sqrt']['unstable']}/{c['sqrt']['not applicable']}"
              + f" | {c['eigen']['stable']}/{c['eigen']['not applicable']}"
              + f" | {c['fused']['stable']}/{c['fused']['marginal']}/{c['fused']['unstable']}/"
                f"{c['fused']['not applicable']} |")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    for s, marker in zip(STRATEGIES, "os^D"):
        share = [(counts[n][s]["stable"] + counts[n][s]["marginal"]) / max(counts[n]["arrays"], 1)
                 for n in Ns]
        ax[0].plot(Ns, share, marker + "-", label=s)
    ax[0].set(xlabel="number of single-axis accelerometers N", ylabel="share of random arrays navigated",
              title=f"{args.arrays} random arrays: loop stable or marginal (|w| <= 5 rad/s)")
    ax[0].legend()
    ax[0].grid(alpha=0.3)
    if example is not None:
        g, rep = example
        st = rep.stability["integrate"]
        w_star = st.worst_rate_rad_s
        n = 3001
        f = np.tile([0.0, 0.0, 9.8], (n, 1))
        A = gf.forward_model(g, f, np.tile(w_star, (n, 1)), np.zeros((n, 3)))
        t = np.arange(n) * 0.01
        e0 = np.array([0.6, -0.48, 0.64]) * 1e-12
        for s in ("integrate", "sqrt", "fused"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UnstableRateLoopWarning)
                solver = gf.RateSolver(g, s, w_star + e0, accel_noise_m_s2=1e-6, allow_unstable=True)
            try:
                w = solver.solve(A, 0.01).omega_rad_s
            except gf.SampleError as exc:
                w = exc.partial.omega_rad_s
            err = np.linalg.norm(w - w_star, axis=1)
            ax[1].semilogy(t[:err.size], np.maximum(err, 1e-17), label=f"{s}: simulated rate error")
        ax[1].semilogy(t, 1e-12 * np.exp(st.growth_rate_s * t), "k--",
                       label=f"analysis: 1e-12 exp({st.growth_rate_s:.3g} t)")
        ax[1].set_ylim(1e-17, 10)
        ax[1].set(xlabel="time (s)", ylabel="|rate error| (rad/s)",
                  title="one 10-sensor array at the worst constant rate of 'integrate' (|w| = 5 rad/s)")
        ax[1].legend(fontsize=8)
        ax[1].grid(alpha=0.3)
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "arrays.png"
    fig.savefig(path, dpi=100)
    print(f"figure: {path}")


if __name__ == "__main__":
    main()
