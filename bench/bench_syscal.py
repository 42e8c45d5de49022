"""Speed of the system-level calibration (issue 12's and issue 22's acceptance: a
20-minute 100 Hz record in <= 2 s on one core): a 20-minute record at 100 Hz through
gfins_fmi.calibration.system.calibrate with 1 and 2 passes, and the C filter alone
(gf_syscal_run, one pass), for the full model (40 states: the laboratory tool's errors
with transverse lever arms and a delay, navigation-grade noise, the 19-position path's
first 20 minutes; the grade's defaults) and seed 001's model (36 states: the seed's
errors and noise on its path, as issue 12 measured). Times are the median of --repeat
runs, wall clock and CPU time of this process (one thread: the C filter does not use
more), so a loaded machine shows in the difference.

    python bench/bench_syscal.py [--repeat 5] [--minutes 20] [--model full|seed|both]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.calibration import compensation as cmp
from gfins_fmi.calibration import grades, segmentation, syscal_filter
from gfins_fmi.calibration import system as c36
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim import rotation as rot
from gfins_fmi.sim.scenarios import NAVIGATION


def _case(model: str, minutes: float):
    T = 60.0 * minutes
    if model == "full":
        lat, h = np.radians(34.0), 80.0
        sched = rot.turntable_path_19()
        errs = cmp.from_compensation(cmp.laboratory_example())
        noise = ImuNoise(gyro_arw_deg_sqrt_h=NAVIGATION.gyro_arw_deg_sqrt_h,
                         accel_vrw_ug_sqrt_hz=NAVIGATION.accel_vrw_ug_sqrt_hz)
        cfg = grades.config_for_grade(grades.grade("navigation"))
    else:
        lat, h = np.radians(40.0), 50.0
        sched = rot.seed001_path(1)
        errs = c36.random_params(np.random.default_rng(3))
        noise = ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
        cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0, model="seed",
                                         estimate_delay=False)
    rec, truth = c36.simulate_record(sched, errs, lat, h, 0.01, duration_s=T, noise=noise, seed=4)
    return lat, h, rec, truth, cfg


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--minutes", type=float, default=20.0)
    ap.add_argument("--model", choices=("full", "seed", "both"), default="both")
    a = ap.parse_args(argv)
    rows = []
    for model in (("full", "seed") if a.model == "both" else (a.model,)):
        lat, h, rec, truth, cfg = _case(model, a.minutes)
        segs = segmentation.segment_record(rec.t_s[1:], np.asarray(rec.gyro)[1:])
        print(f"{model} model ({cfg.n_states} states): {len(rec)} samples over {a.minutes:g} min at 100 Hz, "
              f"{sum(s.kind == 'turn' for s in segs)} turns")
        kw = {"config": cfg, "check_model": False}
        c36.calibrate(rec, lat, h, passes=1, **kw)                 # warm-up (imports, caches)
        for name, fn in (
                ("calibrate(), 1 pass", lambda: c36.calibrate(rec, lat, h, passes=1, **kw)),
                ("calibrate(), 2 passes (the default)", lambda: c36.calibrate(rec, lat, h, passes=2, **kw)),
                ("C filter alone (gf_syscal_run), 1 pass",
                 lambda: syscal_filter.SyscalFilter(cfg, lat, h, truth.q_mn[0]).run(truth.t_s, rec.gyro, rec.accel))):
            wall, cpu = [], []
            for _ in range(a.repeat):
                w0, c0 = time.perf_counter(), time.process_time()
                fn()
                wall.append(time.perf_counter() - w0)
                cpu.append(time.process_time() - c0)
            rows.append((f"{model} ({cfg.n_states} states): {name}", np.median(wall), np.median(cpu)))
    print("| what | wall clock, median (s) | CPU time, median (s) |")
    print("|---|---|---|")
    for name, w, c in rows:
        print(f"| {name} | {w:.3f} | {c:.3f} |")


if __name__ == "__main__":
    main()
