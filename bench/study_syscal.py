"""System-level calibration by Monte Carlo (issue 12, seed 001): N random error sets
drawn from the seed's initial values (gyro misalignment 10", bias 0.01 deg/h,
accelerometer misalignment 10", K_a2 20 ug/g^2, bias 1000 ug, inner lever arm 3 cm;
scale factors 50 / 100 ppm), the seed's IMU noise class (0.01 deg/h laser gyros, 10 ug
accelerometers: ARW 0.002 deg/sqrt(h), accelerometer white noise 10 ug/sqrt(Hz)), a path
(seed 001's 18 positions run twice, or the 19-position turntable path processed as a raw
record), 100 Hz increments. Every record goes through gfins_fmi.calibration.system
.calibrate (segmentation, coarse alignment, the C filter, 2 passes). Reports, over all
(parameter, run) pairs, the fraction with |estimate - truth| <= 3 sigma, the mean z^2
and the average NEES (27 or 28 dof) against their chi-square bands, the mean final
1-sigma per parameter in datasheet units, and the time per calibration; writes the
convergence and residual figures of run 0.

    python bench/study_syscal.py [--runs 50] [--path seed|turntable19] [--repeats 2]
        [--delay-ms 0] [--states 36|37] [--workers 2] [--figures docs/figures] [--json out.json]
        [--npz runs.npz]
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import time

import numpy as np
from scipy.stats import chi2

from gfins_fmi.sim import rotation as rot
from gfins_fmi.analysis import montecarlo
from gfins_fmi.calibration import system as c36
from gfins_fmi.calibration import syscal_filter
from gfins_fmi.estimation.evaluation import chi2_band
from gfins_fmi.nav.imu_errors import UG

LAT, H = np.radians(40.0), 50.0
ARW_DEG_SQRT_H, ASD_UG_SQRT_HZ = 0.002, 10.0
UNITS = np.array([u[1] for u in syscal_filter.PARAM_UNITS])
# parameter blocks for the NEES breakdown: gyro (9), accelerometer (12), K_a2, lever arms, delay
BLOCKS = [np.arange(0, 9), np.arange(9, 21), np.arange(21, 24), np.arange(24, 27), np.arange(27, 28)]
BLOCK_NAMES = ["gyro", "accelerometer", "K_a2", "lever arms", "delay"]


def path(name: str, repeats: int) -> rot.RotationSchedule:
    if name == "seed":
        return rot.seed001_path(repeats=repeats)
    if name == "turntable19":
        return rot.turntable_path_19()
    raise SystemExit(f"unknown path {name!r}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--path", default="seed")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--delay-ms", type=float, default=0.0, help="true accelerometer delay")
    ap.add_argument("--states", type=int, default=36)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--prop-interval", type=float, default=0.1, help="covariance propagation interval (s)")
    ap.add_argument("--vel-std", type=float, default=1e-5, help="zero-velocity measurement std (m/s)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=12)
    ap.add_argument("--figures", default=None, help="folder for the figures of run 0")
    ap.add_argument("--json", default=None)
    ap.add_argument("--npz", default=None, help="per-run errors and covariances (for analysis)")
    a = ap.parse_args(argv)
    sched = path(a.path, a.repeats)
    t0 = time.perf_counter()
    truth = rot.simulate_static(sched, sched.duration_s, a.dt, LAT, H, accel_delay_s=a.delay_ms * 1e-3)
    print(f"path {a.path}: {len(sched.turns)} turns, {sched.duration_s:.0f} s, {truth.t_s.size} samples "
          f"at {1 / a.dt:g} Hz (exact increments in {time.perf_counter() - t0:.1f} s)")
    cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=ARW_DEG_SQRT_H, accel_vrw_ug_sqrt_hz=ASD_UG_SQRT_HZ,
                           vel_std_m_s=a.vel_std, estimate_delay=a.states == 37, prop_interval_s=a.prop_interval,
                           model="seed")
    n_p = a.states - 9
    n_true = 27                                  # the delay is fixed by --delay-ms
    keep = {}

    def task(k, rng):
        p = c36.random_params(rng, cfg.prior, n_true)
        errs = syscal_filter.params_to_imu_errors(p)
        th, dv = errs.apply_increments(truth.dtheta_rad, truth.dv_m_s, a.dt)
        n = th.shape[0]
        th += rng.normal(0.0, ARW_DEG_SQRT_H * np.pi / 180 / 60 * np.sqrt(a.dt), (n, 3))
        dv += rng.normal(0.0, ASD_UG_SQRT_HZ * UG * np.sqrt(a.dt / 2), (n, 3))
        rec = truth.imu_record(th, dv)
        # the site as given to the tool: the truth with an error drawn from the prior
        # (1 m; in height also a gravity error, 2 g dh / R = 0.3 ug per m)
        site_h = H + rng.normal(0.0, cfg.prior.position_m)
        t1 = time.perf_counter()
        rep = c36.calibrate(rec, LAT, site_h, config=cfg, passes=a.passes, check_model=False)
        el = time.perf_counter() - t1
        p_all = np.r_[p, a.delay_ms * 1e-3][:n_p]
        e = rep.estimate - p_all
        P = rep.covariance[9:, 9:]
        if k == 0:
            keep["report"], keep["truth"] = rep, p_all
        R = P / np.outer(rep.std, rep.std)
        blocks = np.array([e[b] @ np.linalg.solve(P[np.ix_(b, b)], e[b]) for b in BLOCKS if b[-1] < n_p])
        return {"z": e / rep.std, "nees": np.array(e @ np.linalg.solve(P, e)), "std": rep.std,
                "nees_block": blocks, "e": e, "P": P,
                "time_s": np.array(el), "nis": np.array(rep.epochs["nis"].mean()),
                "trR2": np.array(np.trace(R @ R))}

    with cf.ThreadPoolExecutor(max_workers=a.workers) as ex:   # the C calls release the GIL
        r = montecarlo.run(task, a.runs, a.seed, executor=ex)
    z, nees = r["z"], r["nees"]
    pairs = z.size
    inside = float(np.mean(np.abs(z) <= 3.0))
    mz2 = float(np.mean(z ** 2))
    lo_z, hi_z = chi2.ppf(0.005, pairs) / pairs, chi2.ppf(0.995, pairs) / pairs
    lo_n, hi_n = chi2_band(n_p, a.runs, 0.99)
    print(f"{a.runs} runs x {n_p} parameters = {pairs} pairs; |z| <= 3 in {100 * inside:.2f}% "
          f"({int(np.sum(np.abs(z) > 3))} outside); max |z| {np.abs(z).max():.2f}")
    # the z of one run are correlated (the filter's correlation matrix R): sum z^2 has
    # variance 2 tr(R^2) instead of 2 n_p, i.e. n_p^2 / tr(R^2) effective degrees of freedom
    dof = a.runs * n_p ** 2 / float(np.mean(r["trR2"]))
    lo_c, hi_c = chi2.ppf(0.005, dof) / dof, chi2.ppf(0.995, dof) / dof
    print(f"mean z^2 {mz2:.3f}; 99% band of chi2({pairs})/{pairs} (z taken as independent): "
          f"[{lo_z:.3f}, {hi_z:.3f}]; with the filter's correlations ({n_p ** 2 / np.mean(r['trR2']):.1f} "
          f"effective dof per run): [{lo_c:.3f}, {hi_c:.3f}]")
    print(f"average NEES {nees.mean():.2f} for {n_p} dof (99% band over {a.runs} runs: "
          f"[{lo_n:.2f}, {hi_n:.2f}]); mean NIS {r['nis'].mean():.3f} (3 dof)")
    for k, nb in enumerate(r["nees_block"].mean(axis=0)):
        b = BLOCKS[k]
        lo, hi = chi2_band(b.size, a.runs, 0.99)
        print(f"  NEES of the {BLOCK_NAMES[k]} block: {nb:.2f} for {b.size} dof (99% band [{lo:.2f}, {hi:.2f}])")
    print(f"time per calibration ({a.passes} passes): median {np.median(r['time_s']):.2f} s")
    std = r["std"].mean(axis=0) / UNITS[:n_p]
    print("| parameter | unit | prior 1-sigma | mean final 1-sigma | mean z^2 |")
    print("|---|---|---|---|---|")
    prior = cfg.prior.params_std()[:n_p] / UNITS[:n_p]
    for k, name in enumerate(syscal_filter.PARAM_NAMES[:n_p]):
        print(f"| {name} | {syscal_filter.PARAM_UNITS[k][0]} | {prior[k]:.3g} | {std[k]:.3g} | "
              f"{np.mean(z[:, k] ** 2):.2f} |")
    out = {"runs": a.runs, "path": a.path, "states": a.states, "delay_ms": a.delay_ms, "pairs": pairs,
           "inside_3sigma": inside, "mean_z2": mz2, "mean_z2_band": [lo_z, hi_z],
           "mean_z2_band_correlated": [lo_c, hi_c],
           "nees_mean": float(nees.mean()), "nees_band": [lo_n, hi_n], "max_abs_z": float(np.abs(z).max()),
           "time_s_median": float(np.median(r["time_s"])), "std_units": std.tolist(),
           "per_param_mean_z2": np.mean(z ** 2, axis=0).tolist()}
    if a.npz:
        np.savez(a.npz, e=r["e"], P=r["P"], z=z, nees=nees)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    if a.figures:
        for f in c36.plot_report(keep["report"], a.figures, keep["truth"], tag=f"_{a.path}"):
            print(f"figure: {f}")
    return out


if __name__ == "__main__":
    main()
