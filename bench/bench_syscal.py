"""Speed of the system-level calibration (issue 12 acceptance: a 20-minute 100 Hz record
in <= 2 s on one core): a 20-minute record of seed 001's path (600 s alignment, then its
first turns, 100 Hz, the seed's errors and noise) through calibration36.calibrate with 1
and 2 passes, and the C filter alone (gf_syscal_run, one pass). Times are the median of
--repeat runs, wall clock and CPU time of this process (one thread: the C filter does
not use more), so a loaded machine shows in the difference.

    python bench/bench_syscal.py [--repeat 5] [--minutes 20]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.sim import rotation as rot
from gfins_fmi.calibration import system as c36
from gfins_fmi.calibration import segmentation, syscal_filter
from gfins_fmi.nav.imu_errors import ImuNoise


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--minutes", type=float, default=20.0)
    a = ap.parse_args(argv)
    lat, h = np.radians(40.0), 50.0
    T = 60.0 * a.minutes
    sched = rot.seed001_path(1)
    p = c36.random_params(np.random.default_rng(3))
    rec, truth = c36.simulate_record(sched, p, lat, h, 0.01, duration_s=T,
                                     noise=ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0),
                                     seed=4)
    cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
    segs = segmentation.segment_record(rec.t_s[1:], np.asarray(rec.gyro)[1:])
    print(f"record: {len(rec)} samples over {T / 60:g} min at 100 Hz, "
          f"{sum(s.kind == 'turn' for s in segs)} turns")
    c36.calibrate(rec, lat, h, config=cfg, passes=1)           # warm-up (imports, caches)
    rows = []
    for name, fn in (
            ("calibrate(), 1 pass", lambda: c36.calibrate(rec, lat, h, config=cfg, passes=1)),
            ("calibrate(), 2 passes", lambda: c36.calibrate(rec, lat, h, config=cfg, passes=2)),
            ("C filter alone (gf_syscal_run), 1 pass",
             lambda: syscal_filter.SyscalFilter(cfg, lat, h, truth.q_mn[0]).run(truth.t_s, rec.gyro, rec.accel))):
        wall, cpu = [], []
        for _ in range(a.repeat):
            w0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall.append(time.perf_counter() - w0)
            cpu.append(time.process_time() - c0)
        rows.append((name, np.median(wall), np.median(cpu)))
    print("| what | wall clock, median (s) | CPU time, median (s) |")
    print("|---|---|---|")
    for name, w, c in rows:
        print(f"| {name} | {w:.3f} | {c:.3f} |")


if __name__ == "__main__":
    main()
