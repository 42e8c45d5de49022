"""Noise identification against the simulated truth over seeded records (issue 23's
acceptance: fitted ARW, VRW, bias instability and rate random walk within 10% of the
simulated values on a 10-hour record), and the calibration of the fit's stated 1-sigma:
the spread of each estimate over the seeds divided by its mean stated 1-sigma.

    python bench/study_noise_id.py [--hours 10] [--rate 100] [--seeds 10] [--first-seed 0]

Prints, per term and sensor, the truth, the mean and spread of the estimates (over three
axes and the seeds), the largest relative error, the fraction within 10%, and the ratio
spread / stated sigma. Results: docs/characterise_imu.md, "How well it works".
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.analysis.allan import allan_deviation
from gfins_fmi.analysis.noise_id import fit_noise_terms
from gfins_fmi.nav.imu_errors import DEG_H, UG, ImuNoise

#: the simulated consumer MEMS IMU (each term dominating a decade of tau on a 10 h record)
MODEL = ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=10.0, gyro_correlation_time_s=60.0,
                 gyro_rrw_deg_h_sqrt_h=40.0, accel_vrw_ug_sqrt_hz=100.0, accel_bias_instability_ug=200.0,
                 accel_correlation_time_s=60.0, accel_rrw_ug_sqrt_s=3.0)


def truth():
    m = MODEL
    return {"gyro": {"white": m.gyro_arw_deg_sqrt_h * np.pi / 180 / 60,
                     "gm_sigma": m.gyro_bias_instability_deg_h * DEG_H, "gm_tau_s": m.gyro_correlation_time_s,
                     "rate_random_walk": m.gyro_rrw_deg_h_sqrt_h * DEG_H / 60},
            "accel": {"white": m.accel_vrw_ug_sqrt_hz * UG / np.sqrt(2), "gm_sigma": m.accel_bias_instability_ug * UG,
                      "gm_tau_s": m.accel_correlation_time_s, "rate_random_walk": m.accel_rrw_ug_sqrt_s * UG}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=10.0)
    ap.add_argument("--rate", type=float, default=100.0)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first-seed", type=int, default=0)
    a = ap.parse_args(argv)
    dt = 1 / a.rate
    n = int(a.hours * 3600 / dt)
    est = {s: {k: [] for k in ("white", "gm_sigma", "gm_tau_s", "rate_random_walk")} for s in ("gyro", "accel")}
    std = {s: {k: [] for k in est[s]} for s in est}
    models = []
    t0 = time.perf_counter()
    for seed in range(a.first_seed, a.first_seed + a.seeds):
        g, acc = MODEL.sample(n, dt, np.random.default_rng(seed))
        ad = allan_deviation(np.c_[g, acc], dt)
        del g, acc
        for c in range(6):
            t = fit_noise_terms(ad, c)
            s = "gyro" if c < 3 else "accel"
            models.append(t.model)
            for k in est[s]:
                est[s][k].append(t.values[k])
                std[s][k].append(t.stds[k])
        print(f"seed {seed} done ({time.perf_counter() - t0:.0f} s)", flush=True)
    tr = truth()
    print(f"\n{a.seeds} records of {a.hours:g} h at {a.rate:g} Hz; floor models: "
          f"{models.count('gauss-markov')} gauss-markov, {models.count('flicker')} flicker")
    print("| sensor | term | truth | mean estimate | spread (std) | max rel. error | within 10% | spread / stated sigma |")
    print("|---|---|---|---|---|---|---|---|")
    for s in est:
        for k in est[s]:
            e, sd = np.array(est[s][k]), np.array(std[s][k])
            rel = np.abs(e / tr[s][k] - 1)
            print(f"| {s} | {k} | {tr[s][k]:.4g} | {e.mean():.4g} | {e.std(ddof=1):.3g} | {rel.max():.3f} | "
                  f"{np.mean(rel <= 0.10):.2f} | {e.std(ddof=1) / sd.mean():.2f} |")


if __name__ == "__main__":
    main()
