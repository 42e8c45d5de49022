"""Filter consistency by Monte Carlo (issue 11): a simulated 30-minute drive with a
tactical-grade IMU, 1 Hz GNSS (position and velocity) and two 60 s outages; N runs with
independent IMU and GNSS errors on the same trajectory. The average NEES (15 states, at
every covariance epoch) and NIS (GNSS updates) over the runs are compared with their 95%
chi-square bands; the fraction of epochs inside is printed per filter, and a figure is
written.

    python bench/study_consistency.py [--runs 100] [--minutes 30] [--filters ekf ukf] [--out docs/figures]
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
from gfins_fmi.estimation.evaluation import chi2_band, nees, plot_consistency, state_errors
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.nav.strapdown import NavState
from gfins_fmi.nav.earth import quat_multiply
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--filters", nargs="+", default=["ekf", "ukf"])
    ap.add_argument("--out", default=None, help="folder for the figure")
    ap.add_argument("--progress", action="store_true", help="a progress bar per filter")
    executor_arguments(ap)
    a = ap.parse_args(argv)
    T = 60.0 * a.minutes
    profile = town_drive(T)
    outages = ((0.40 * T, 0.40 * T + 60.0), (0.75 * T, 0.75 * T + 60.0))
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.0, 2.0),
                      vel_std_m_s=(0.05, 0.05, 0.1), outages_s=outages)
    dt = 0.01
    truth0 = simulate_vehicle(profile, T, dt)
    with montecarlo.executor(a.scheduler, a.workers) as ex:   # one cluster connection for all
        for filt in a.filters:
            cfg = FilterConfig(imu=TACTICAL, filter=filt, propagation_interval_s=0.1, gate_probability=None)

            def one_run(run, _rng):
                # fixed seeds per run (1000 + run: the drive, 5000 + run: the initial errors),
                # so the figures do not depend on where the runs execute
                d = simulate_drive(profile, T, dt, imu=TACTICAL, gnss=rx, seed=1000 + run, truth=truth0)
                rng = np.random.default_rng(5000 + run)
                init = InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                                    attitude_std_rad=(0.005, 0.005, 0.02))
                # the initial errors drawn from the initial covariance
                P0 = init.covariance(cfg)
                x0 = rng.normal(size=15) * np.sqrt(np.diag(P0))
                phi = x0[6:9]
                ang = np.linalg.norm(phi)
                qphi = np.r_[np.cos(ang / 2), np.sin(ang / 2) * phi / ang]      # q(-phi) below
                s0 = d.initial
                nav0 = NavState(quat_multiply(np.r_[qphi[0], -qphi[1:]], s0.q_bn), s0.v_n_m_s + x0[0:3],
                                s0.lat_rad + x0[3], s0.lon_rad + x0[4], s0.h_m + x0[5], s0.t_s)
                init.nav = nav0
                # the sensor states start at 0 with the true biases drawn from the same model
                sol = IntegratedNavigator(cfg, init).run(d.imu, d.gnss, smoother=True)
                e = state_errors(sol.epochs, d.truth, d.gyro_bias_rad_s, d.accel_bias_m_s2)
                inn = sol.innovations
                return dict(nees=nees(sol.epochs, e), nis=inn["nis"], t_ep=sol.epochs["t_s"],
                            t_nis=inn["t_s"])

            t0 = time.perf_counter()
            c0 = time.process_time()
            r = montecarlo.run(one_run, a.runs, executor=ex, progress=a.progress, desc=filt.upper())
            nees_sum, nis_sum = r["nees"].sum(axis=0), r["nis"].sum(axis=0)
            t_ep, t_nis = r["t_ep"][0], r["t_nis"][0]
            el, cpu = time.perf_counter() - t0, time.process_time() - c0
            N = a.runs
            mean_nees, mean_nis = nees_sum / N, nis_sum / N
            lo, hi = chi2_band(15, N)
            inside = np.mean((mean_nees >= lo) & (mean_nees <= hi))
            lo3, hi3 = chi2_band(3, N)
            ins_nis = np.mean((mean_nis >= lo3) & (mean_nis <= hi3))
            print(f"{filt.upper()}: {N} runs of {a.minutes:g} min in {el:.1f} s (CPU of this process "
                  f"{cpu:.1f} s); average NEES (15 states) inside [{lo:.2f}, {hi:.2f}] at "
                  f"{100 * inside:.1f}% of {len(mean_nees)} epochs (median {np.median(mean_nees):.2f}); "
                  f"average NIS (3 dof) inside [{lo3:.2f}, {hi3:.2f}] at {100 * ins_nis:.1f}% of "
                  f"{len(mean_nis)} updates (median {np.median(mean_nis):.2f})")
            if a.out:
                p = plot_consistency(f"{a.out}/consistency_{filt}.png", t_ep, mean_nees, (lo, hi), t_nis,
                                     mean_nis, (lo3, hi3), title=f"{filt.upper()}: {N} Monte-Carlo runs, "
                                     "tactical IMU, 1 Hz GNSS, two 60 s outages")
                print("figure:", p)


if __name__ == "__main__":
    main()
