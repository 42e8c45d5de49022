"""The chain of issue 23's third acceptance point, with more runs than the default test:
a static record of a consumer MEMS -> ``gfins noise`` -> the noise block -> the filter on
N seeded 300 s drives with that IMU (1 Hz GNSS): the fraction of epochs (after 60 s) at
which the average NEES (15 states) is inside its 95% chi-square band; the same with the
true noise model, and with the identified one understated 3x (the check can fail).

    python bench/study_noise_to_filter.py [--runs 10 50] [--static-hours 2]

The default test (tests/cli/test_noise_command.py) runs 10 drives and asks >= 80%.
"""
from __future__ import annotations

import argparse
import dataclasses
import pathlib
import tempfile

import numpy as np

from gfins_fmi.cli import main as gfins
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.evaluation import chi2_band, nees, state_errors
from gfins_fmi.estimation.noise_file import read_noise_file
from gfins_fmi.io import ImuRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim.scenarios import simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle

IMU = ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=10.0, gyro_correlation_time_s=100.0,
               accel_vrw_ug_sqrt_hz=100.0, accel_bias_instability_ug=300.0, accel_correlation_time_s=100.0)


def mean_nees(cfg, runs, prof, T, rx, truth):
    acc = None
    for seed in range(runs):
        d = simulate_drive(prof, T, 0.01, imu=IMU, gnss=rx, seed=300 + seed, truth=truth)
        init = InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                            attitude_std_rad=(0.005, 0.005, 0.02))
        sol = IntegratedNavigator(cfg, init).run(d.imu, d.gnss, smoother=True)
        v = nees(sol.epochs, state_errors(sol.epochs, d.truth, d.gyro_bias_rad_s, d.accel_bias_m_s2))
        acc = v if acc is None else acc + v
    return acc / runs, sol.epochs["t_s"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, nargs="+", default=[10, 50])
    ap.add_argument("--static-hours", type=float, default=2.0)
    a = ap.parse_args(argv)
    d = pathlib.Path(tempfile.mkdtemp(prefix="noise_to_filter_"))
    dt = 0.02
    n = int(a.static_hours * 3600 / dt)
    g, acc = IMU.sample(n, dt, np.random.default_rng(5))
    t = np.arange(1, n + 1) * dt
    ImuRecord(t, g * dt, (acc + [0.0, 0.0, 9.8]) * dt, "increments", "static").to_csv(d / "static.csv")
    gfins(["noise", str(d / "static.csv"), "--output", str(d / "noise.toml")])
    model = read_noise_file(d / "noise.toml")
    low = dataclasses.replace(model, gyro_arw_deg_sqrt_h=model.gyro_arw_deg_sqrt_h / 3,
                              accel_vrw_ug_sqrt_hz=model.accel_vrw_ug_sqrt_hz / 3,
                              gyro_bias_instability_deg_h=model.gyro_bias_instability_deg_h / 3,
                              accel_bias_instability_ug=model.accel_bias_instability_ug / 3)
    T = 300.0
    prof = town_drive(T)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1))
    truth = simulate_vehicle(prof, T, 0.01)
    for runs in a.runs:
        lo, hi = chi2_band(15, runs)
        for label, m in (("identified (the file)", model), ("true model", IMU), ("identified / 3", low)):
            mean, te = mean_nees(FilterConfig(imu=m, gate_probability=None), runs, prof, T, rx, truth)
            sel = te > 60
            inside = np.mean((mean[sel] >= lo) & (mean[sel] <= hi))
            print(f"{runs} runs, {label}: average NEES inside [{lo:.2f}, {hi:.2f}] at {100 * inside:.1f}% of "
                  f"{sel.sum()} epochs (median {np.median(mean[sel]):.2f})", flush=True)


if __name__ == "__main__":
    main()
