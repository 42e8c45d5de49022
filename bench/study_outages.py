"""GNSS outage protocol on a simulated drive (issue 11): a navigation-grade IMU (ARW
0.003 deg/sqrt(h), VRW 0.03 m/s/sqrt(h), gyro bias 0.027 deg/h, accelerometer bias
15 mGal) with 1 Hz RTK GNSS; 60 s outages every 180 s after a first 300 s; score = RMS
over the outages of the maximum horizontal drift during each, for the EKF and for the
RTS smoother.

    python bench/study_outages.py [--minutes 60] [--seeds 5] [--filter ekf] [--subsamples 1]
                                  [--out docs/figures]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.estimation import FilterConfig, InitialState
from gfins_fmi.estimation.evaluation import outage_protocol, plot_outages
from gfins_fmi.sim.scenarios import NAVIGATION, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle

RTK = dict(rate_hz=1.0, offset_s=0.21, pos_std_m=(0.02, 0.02, 0.04), vel_std_m_s=(0.01, 0.01, 0.02),
           quality=1)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--filter", default="ekf")
    ap.add_argument("--subsamples", type=int, default=1, help="IMU samples per navigation update")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    T = 60.0 * a.minutes
    profile = town_drive(T)
    dt = 0.01
    truth0 = simulate_vehicle(profile, T, dt)
    cfg = FilterConfig(imu=NAVIGATION, filter=a.filter, propagation_interval_s=0.1, subsamples=a.subsamples)
    scores, smooth_scores = [], []
    for seed in range(a.seeds):
        t0 = time.perf_counter()
        d = simulate_drive(profile, T, dt, imu=NAVIGATION, gnss=GnssReceiver(**RTK), seed=seed, truth=truth0)
        init = InitialState(d.initial, position_std_m=(0.02, 0.02, 0.04), velocity_std_m_s=0.01,
                            attitude_std_rad=np.radians([0.005, 0.005, 0.05]))
        r = outage_protocol(d.imu, d.gnss, d.truth, config=cfg, initial=init, outage_s=60.0,
                            period_s=180.0, first_s=300.0)
        scores.append(r.filter_score_m)
        smooth_scores.append(r.smoother_score_m)
        print(f"seed {seed}: {len(r.windows)} outages, filter score {r.filter_score_m:.3f} m "
              f"(max {r.filter_max_m.max():.3f}), smoother {r.smoother_score_m:.3f} m "
              f"(ratio {r.smoother_score_m / r.filter_score_m:.3f}) [{time.perf_counter() - t0:.1f} s]")
        if a.out and seed == 0:
            print("figure:", plot_outages(f"{a.out}/outages_navigation_grade.png", r, d.truth,
                                          title="navigation-grade IMU, 1 Hz RTK, 60 s outages every 180 s"))
    print(f"mean over {a.seeds} seeds: filter {np.mean(scores):.3f} m, smoother {np.mean(smooth_scores):.3f} m")


if __name__ == "__main__":
    main()
