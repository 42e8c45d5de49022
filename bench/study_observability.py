"""What a calibration path observes (issue 12 item 4): the final 1-sigma of every
parameter of the 36-state filter, relative to its prior, for several paths, from
calibration36.covariance_study (the filter on the path's exact increments: the
covariance of the linearised filter does not depend on the errors or the noise). The
seed's IMU noise (ARW 0.002 deg/sqrt(h), 10 ug/sqrt(Hz)), 20 Hz.

    python bench/study_observability.py
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.sim import rotation as rot
from gfins_fmi.calibration import system as c36
from gfins_fmi.calibration import syscal_filter

LAT, H = np.radians(40.0), 50.0


def paths():
    return {
        "seed 001, 18 positions x 2": rot.seed001_path(2),
        "seed 001, 18 positions x 1": rot.seed001_path(1),
        "19-position turntable": rot.turntable_path_19(),
        "first 9 seed turns only (gyro part)": rot.RotationSchedule(rot.seed001_path(1).turns[:10]),
        "last 9 seed turns only (accelerometer part)": rot.RotationSchedule(
            (rot.rest(600.0),) + rot.seed001_path(1).turns[10:]),
        "inner axis only, 4 x 90 deg": rot.RotationSchedule(
            (rot.rest(600.0),) + tuple(rot.inner(90.0, 180.0) for _ in range(4))),
        "8-position indexing, one cycle": rot.RotationSchedule(
            (rot.rest(600.0),) + rot.indexing_scheme(8, dwell_s=180.0, rate_deg_s=5.0).turns),
    }


def main():
    cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
    res = {name: c36.covariance_study(s, LAT, H, cfg, dt_s=0.05) for name, s in paths().items()}
    names = syscal_filter.PARAM_NAMES[:27]
    print("final 1-sigma / prior 1-sigma (1: not observed; > 0.9 marked *, > 0.3 marked ~)\n")
    print("| parameter | " + " | ".join(res) + " |")
    print("|---|" + "---|" * len(res))
    for k, n in enumerate(names):
        cells = []
        for r in res.values():
            v = r["ratio"][k]
            cells.append(f"{v:.3g}{' *' if v > 0.9 else ' ~' if v > 0.3 else ''}")
        print(f"| {n} | " + " | ".join(cells) + " |")
    print("\nduration (min): " + ", ".join(f"{n}: {s.duration_s / 60:.1f}" for n, s in paths().items()))


if __name__ == "__main__":
    main()
