"""Covariance prediction of the drift during a GNSS outage (python-control error model,
Van Loan discretisation, from the filter's covariance at the outage start) against a
Monte Carlo of the C filter (issue 11: agreement within 10%).

A 12-minute drive, tactical IMU, 1 Hz GNSS; outages of 60 s at 240 s, 420 s and 600 s.
For each outage: the RMS over the runs of the horizontal position error at the outage's
end, the python-control 1-sigma, and the filter's own 1-sigma there.

    python bench/study_outage_prediction.py [--runs 200] [--filter ekf] [--out docs/figures]
        [--workers N | --scheduler ADDRESS [--workers N]]

The runs go through gfins_fmi.analysis.montecarlo.run: N threads here, or a dask cluster (see
docs/analysis.md, "Running on a cluster"); the figures do not depend on which.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.analysis import montecarlo
from gfins_fmi.cli.parser import executor_arguments
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.evaluation import navigation_errors, predict_outage_std
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--filter", default="ekf")
    ap.add_argument("--outage-s", type=float, default=60.0)
    ap.add_argument("--out", default=None)
    ap.add_argument("--progress", action="store_true", help="a progress bar")
    executor_arguments(ap)
    a = ap.parse_args(argv)
    T, dt = 720.0, 0.01
    profile = town_drive(T)
    starts = np.array([240.0, 420.0, 600.0])
    win = np.c_[starts, starts + a.outage_s]
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.0, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1),
                      outages_s=tuple(map(tuple, win)))
    truth = simulate_vehicle(profile, T, dt)
    cfg = FilterConfig(imu=TACTICAL, filter=a.filter, gate_probability=None)
    # rows of the solution at the outage ends (the last IMU sample before the end)
    t_imu = truth.t_s[1:]
    k_end = np.searchsorted(t_imu, win[:, 1]) - 1

    def drive_and_filter(r, smoother=False):
        # fixed seed per run (the drive's errors: seed r), whatever executes it
        d = simulate_drive(profile, T, dt, imu=TACTICAL, gnss=rx, seed=r, truth=truth)
        init = InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                            attitude_std_rad=(0.005, 0.005, 0.02))
        return d, IntegratedNavigator(cfg, init).run(d.imu, d.gnss, smoother=smoother)

    def one_run(r, _rng):
        d, sol = drive_and_filter(r)
        return dict(err=navigation_errors(sol, d.truth).pos_enu_m[k_end, :2])

    t0 = time.perf_counter()
    c0 = time.process_time()
    with montecarlo.executor(a.scheduler, a.workers) as ex:
        err_end = montecarlo.run(one_run, a.runs, executor=ex, progress=a.progress)["err"]
    print(f"{a.runs} runs in {time.perf_counter() - t0:.1f} s (CPU of this process "
          f"{time.process_time() - c0:.1f} s)")
    # run 0 again, keeping the filter's covariance epochs (RTS smoother storage)
    ref_sol = drive_and_filter(0, smoother=True)[1]
    ep = ref_sol.epochs
    n = ep["n_states"]
    iu = np.triu_indices(n)
    rows = []
    for i, (w0, w1) in enumerate(win):
        # the filter's covariance after the last update before the outage
        j = int(np.searchsorted(ep["t_s"], w0, side="left")) - 1
        P0 = np.zeros((n, n))
        P0[iu] = ep["P_post"][j]
        P0 = P0 + np.triu(P0, 1).T
        sel = (truth.t_s >= ep["t_s"][j]) & (truth.t_s <= w1 + 0.01)
        pr = predict_outage_std(P0, truth.t_s[sel], truth.lat_rad[sel], truth.h_m[sel], truth.v_n_m_s[sel],
                                truth.q_bn[sel], truth.accel_m_s2[sel], truth.gyro_rad_s[sel], cfg, step_s=0.1)
        pred = float(np.interp(t_imu[k_end[i]], pr["t_s"], pr["horizontal_m"]))
        mc = float(np.sqrt(np.mean(np.sum(err_end[:, i] ** 2, axis=1))))
        own = float(np.hypot(*ref_sol.std[k_end[i], 3:5]))
        # statistical uncertainty of the Monte-Carlo RMS (2 r.v. per run): ~ 1 / (2 sqrt(N))
        rows.append((w0, mc, pred, own))
        print(f"outage [{w0:.0f}, {w1:.0f}) s: Monte Carlo RMS horizontal error at its end {mc:.3f} m, "
              f"python-control prediction {pred:.3f} m (ratio {mc / pred:.3f}), filter's own sigma {own:.3f} m; "
              f"MC sampling uncertainty ~{100 / (2 * np.sqrt(a.runs)):.1f}%")
    if a.out:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4))
        x = np.arange(len(rows))
        r = np.array(rows)
        ax.bar(x - 0.2, r[:, 1], 0.4, label=f"Monte Carlo RMS ({a.runs} runs)")
        ax.bar(x + 0.2, r[:, 2], 0.4, label="python-control prediction (1 sigma)")
        ax.set_xticks(x, [f"outage at {w:.0f} s" for w in r[:, 0]])
        ax.set_ylabel(f"horizontal error after {a.outage_s:g} s (m)")
        ax.legend(fontsize=8)
        ax.grid(True, axis="y", lw=0.3)
        fig.tight_layout()
        p = f"{a.out}/outage_prediction.png"
        fig.savefig(p, dpi=110)
        print("figure:", p)


if __name__ == "__main__":
    main()
