"""The full lever-arm model by Monte Carlo (issue 22's acceptance): N random error sets at
the magnitudes a laboratory tool injects by default (calibration.compensation
.random_compensation: scale 10-30 ppm, gyro misalignment to 60 arcsec, accelerometer
misalignment lower-triangular to 30 arcsec, gyro bias 0.1-0.3 deg/h, accelerometer bias
10-30 ug, K_a2 10-30 ug/g^2, the x and y accelerometers at 1-6 cm from the z one in every
direction, delay 0.5-1.5 ms), converted to our forward model and simulated on the
19-position turntable path (0.01 s, 34 deg latitude) with navigation-grade white noise
(sim.scenarios.NAVIGATION: ARW 0.003 deg/sqrt(h), 72 ug/sqrt(Hz)) or none
(--noise-free). Every record goes through gfins_fmi.calibration.system.calibrate with the
navigation grade's defaults (the full model with the delay, 40 states, 2 passes).

Reports, over all (parameter, run) pairs, the fraction with |estimate - truth| <= 3 sigma,
the mean z^2, the average NEES (31 dof) and per block against their chi-square bands,
the mean NIS, the worst error in the issue's units against its tolerances (noise-free),
the mean final 1-sigma per parameter, the warnings raised, and the time per calibration.

    python bench/study_syscal_full.py [--runs 50] [--noise-free] [--workers 2] [--seed 22]
        [--json out.json] [--figures DIR]
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import json
import time

import numpy as np

from gfins_fmi.analysis import montecarlo
from gfins_fmi.calibration import compensation as cmp
from gfins_fmi.calibration import syscal_filter, system
from gfins_fmi.estimation.evaluation import chi2_band
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim import rotation as rot
from gfins_fmi.sim.scenarios import NAVIGATION

LAT, H, DT = np.radians(34.0), 80.0, 0.01
TOL = {"ppm": 0.5, "arcsec": 0.5, "deg/h": 0.002, "ug": 0.5, "ug/g^2": 1.0, "cm": 0.1, "ms": 0.01}
NAMES = syscal_filter.param_names("full", True)
UNITS = syscal_filter.param_units("full", True)
FIELDS = syscal_filter.prior_fields("full", True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--noise-free", action="store_true")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=22)
    ap.add_argument("--json", default=None)
    ap.add_argument("--figures", default=None, help="folder for the figures of run 0")
    a = ap.parse_args(argv)
    sched = rot.turntable_path_19()
    noise = None if a.noise_free else ImuNoise(gyro_arw_deg_sqrt_h=NAVIGATION.gyro_arw_deg_sqrt_h,
                                               accel_vrw_ug_sqrt_hz=NAVIGATION.accel_vrw_ug_sqrt_hz)
    keep = {}

    def task(k, rng):
        errs = cmp.from_compensation(cmp.random_compensation(rng))
        truth = syscal_filter.imu_errors_to_params(errs, "full", True)
        rec, _ = system.simulate_record(sched, errs, LAT, H, DT, noise=noise, seed=int(rng.integers(1 << 31)))
        t0 = time.perf_counter()
        rep = system.calibrate(rec, LAT, H, grade="navigation")
        el = time.perf_counter() - t0
        e = rep.estimate - truth
        P = rep.covariance[9:, 9:]
        blocks = [np.flatnonzero(np.array(FIELDS) == f) for f in dict.fromkeys(FIELDS)]
        if k == 0:
            keep["report"], keep["truth"] = rep, truth
        return {"z": e / rep.std, "e_units": e / np.array([u[1] for u in UNITS]),
                "nees": np.array(e @ np.linalg.solve(P, e)),
                "nees_block": np.array([e[b] @ np.linalg.solve(P[np.ix_(b, b)], e[b]) for b in blocks]),
                "std": rep.std, "nis": np.array(rep.diagnostics.nis["mean"]), "time_s": np.array(el),
                "warned": np.array([len(rep.warnings)]),
                "fights": np.array([len(rep.diagnostics.fights)])}

    t_all = time.perf_counter()
    with cf.ThreadPoolExecutor(max_workers=a.workers) as ex:     # the C calls release the GIL
        r = montecarlo.run(task, a.runs, a.seed, executor=ex)
    z, nees = r["z"], r["nees"]
    pairs = z.size
    inside = float(np.mean(np.abs(z) <= 3.0))
    lo_n, hi_n = chi2_band(31, a.runs, 0.99)
    print(f"{a.runs} runs x 31 parameters = {pairs} pairs ({'noise-free' if a.noise_free else 'navigation-grade noise'}); "
          f"|z| <= 3 in {100 * inside:.2f}% ({int(np.sum(np.abs(z) > 3))} outside); max |z| {np.abs(z).max():.2f}; "
          f"mean z^2 {np.mean(z ** 2):.3f}")
    print(f"average NEES {nees.mean():.2f} for 31 dof (99% band over {a.runs} runs: [{lo_n:.2f}, {hi_n:.2f}]); "
          f"median {np.median(nees):.2f}; mean NIS {r['nis'].mean():.3f} (3 dof)")
    for k, f in enumerate(dict.fromkeys(FIELDS)):
        dof = FIELDS.count(f)
        lo, hi = chi2_band(dof, a.runs, 0.99)
        print(f"  NEES of {f}: {r['nees_block'][:, k].mean():.2f} for {dof} dof (99% band [{lo:.2f}, {hi:.2f}])")
    worst = np.abs(r["e_units"]).max(axis=0)
    bad = [f"{n} {w:.3g} {u[0]}" for n, w, u in zip(NAMES, worst, UNITS) if w > TOL[u[0]]]
    print("worst |error| against the issue's tolerances: " + (", ".join(bad) if bad else "every parameter within"))
    print(f"runs with warnings: {int(np.sum(r['warned'] > 0))}; with a parameter fighting its prior: "
          f"{int(np.sum(r['fights'] > 0))}")
    print(f"time per calibration (2 passes, wall clock with {a.workers} workers): median "
          f"{np.median(r['time_s']):.2f} s; whole study {time.perf_counter() - t_all:.0f} s")
    print("| parameter | unit | prior 1-sigma | mean final 1-sigma | worst abs error | mean z^2 |")
    print("|---|---|---|---|---|---|")
    prior = keep["report"].prior_std / np.array([u[1] for u in UNITS])
    std = r["std"].mean(axis=0) / np.array([u[1] for u in UNITS])
    for k, name in enumerate(NAMES):
        print(f"| {name} | {UNITS[k][0]} | {prior[k]:.3g} | {std[k]:.3g} | {worst[k]:.3g} | {np.mean(z[:, k] ** 2):.2f} |")
    out = {"runs": a.runs, "noise_free": a.noise_free, "pairs": pairs, "inside_3sigma": inside,
           "mean_z2": float(np.mean(z ** 2)), "nees_mean": float(nees.mean()), "nees_band": [lo_n, hi_n],
           "max_abs_z": float(np.abs(z).max()), "nis_mean": float(r["nis"].mean()),
           "worst_units": worst.tolist(), "std_units": std.tolist(),
           "time_s_median": float(np.median(r["time_s"]))}
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    if a.figures:
        for f in system.plot_report(keep["report"], a.figures, keep["truth"], tag="_full"):
            print(f"figure: {f}")
    return out


if __name__ == "__main__":
    main()
