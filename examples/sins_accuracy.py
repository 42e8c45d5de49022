"""Accuracy of the strapdown mechanization on the closed-form motions of
gfins_fmi.sim.trajectory: the figures of docs/sins.md (table printed, figure written).

    python examples/sins_accuracy.py [--out docs/figures/sins_accuracy.png]
"""
from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests"))
from conftest import attitude_error_rad, horizontal_error_m  # noqa: E402


def run(motion, duration, dt=0.01, **cfg):
    tr = tj.sample(motion, duration, dt)
    sol = gf.Strapdown(gf.NavState.from_trajectory(tr, 0), gf.SinsConfig(**cfg)).run(
        tr.dtheta_rad, tr.dv_m_s, dt_s=dt)
    horiz = horizontal_error_m(sol.lat_rad, sol.lon_rad, tr.lat_rad[1:], tr.lon_rad[1:])
    att = np.degrees(np.linalg.norm(attitude_error_rad(sol.q_bn, tr.q_bn[1:]), axis=1))
    return tr, sol, horiz, att


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/sins_accuracy.png"))
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 2, figsize=(12, 8), constrained_layout=True)
    rows = []
    for name, motion, dur in [("stationary", tj.Stationary(), 3600.0),
                              ("sine velocity", tj.SineVelocity(), 3600.0),
                              ("circle", tj.Circle(), 3600.0),
                              ("vehicle run (seed 001)", tj.VehicleRun(), 1320.0),
                              ("airdrop (seed 002)", tj.Airdrop(), 200.0)]:
        tr, sol, horiz, att = run(motion, dur)
        rows.append((name, dur, horiz.max(), att.max(), np.abs(sol.h_m - tr.h_m[1:]).max()))
        ax[0, 0].semilogy(sol.t_s / 60, horiz + 1e-9, label=name)
        ax[0, 1].semilogy(sol.t_s / 60, att + 1e-12, label=name)
    ax[0, 0].set(xlabel="time (min)", ylabel="horizontal position error (m)",
                 title="Increments at 100 Hz, two-sample algorithm, free vertical channel")
    ax[0, 1].set(xlabel="time (min)", ylabel="attitude error (deg)")
    ax[0, 0].legend(fontsize=8)
    ax[0, 1].legend(fontsize=8)

    # coning: one-sample vs two-sample
    a, f, dt = np.radians(1.0), 5.0, 0.01
    trc = tj.sample(tj.Coning(half_angle_rad=a, frequency_hz=f), 20.0, dt)
    for coning, style in ((False, "-"), (True, "--")):
        sol = gf.Strapdown(gf.NavState.from_trajectory(trc, 0), gf.SinsConfig(coning=coning)).run(
            trc.dtheta_rad, trc.dv_m_s, dt_s=dt)
        err = attitude_error_rad(sol.q_bn, trc.q_bn[1:])[:, 2]
        ax[1, 0].plot(sol.t_s, np.degrees(np.abs(err)), style,
                      label="two-sample" if coning else "one-sample")
    lam = 2 * np.pi * f * dt
    ratio = (lam - np.sin(lam)) / ((lam - np.sin(lam)) - 2 / 3 * np.sin(lam / 2) ** 2 * np.sin(lam))
    ax[1, 0].set(xlabel="time (s)", ylabel="|attitude error| about the cone axis (deg)", yscale="log",
                 title=f"Coning 1 deg at 5 Hz, 100 Hz updates: theory ratio {ratio:.1f}")
    ax[1, 0].legend(fontsize=8)

    # Schuler
    trs = tj.sample(tj.Stationary(), 3 * 5100.0, 0.1)
    x0 = gf.NavState.from_trajectory(trs, 0)
    x0.v_n_m_s = x0.v_n_m_s + [0.0, 0.1, 0.0]
    sol = gf.Strapdown(x0, gf.SinsConfig(vertical="hold", hold_height_m=float(trs.h_m[0]))).run(
        trs.dtheta_rad, trs.dv_m_s, dt_s=0.1)
    ax[1, 1].plot(sol.t_s / 60, sol.v_n_m_s[:, 1] - trs.v_n_m_s[1:, 1], label="north")
    ax[1, 1].plot(sol.t_s / 60, sol.v_n_m_s[:, 0] - trs.v_n_m_s[1:, 0], label="east")
    for k in range(1, 4):
        ax[1, 1].axvline(84.4 * k, color="k", lw=0.5, ls=":")
    ax[1, 1].set(xlabel="time (min)", ylabel="velocity error (m/s)",
                 title="Initial 0.1 m/s north error: Schuler oscillation (dotted: 84.4 min)")
    ax[1, 1].legend(fontsize=8)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=100)
    print(f"{'motion':26s} {'duration':>9s} {'horizontal':>12s} {'attitude':>11s} {'height':>10s}")
    for name, dur, h, a_, z in rows:
        print(f"{name:26s} {dur:8.0f}s {h:11.3g}m {a_:10.3g}° {z:9.3g}m")
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
