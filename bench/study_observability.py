"""What a calibration path observes (issue 12 item 4, issue 22 item 6): the final 1-sigma
of every parameter, relative to its prior, for several paths, from
calibration.system.covariance_study (the filter on the path's exact increments: the
covariance of the linearised filter does not depend on the errors or the noise), 20 Hz.

    python bench/study_observability.py                  # seed 001's 36 states, its noise
    python bench/study_observability.py --model full     # the full model (40 states), the
                                                         # navigation grade's defaults
    python bench/study_observability.py --grades         # the full model on the 19-position
        # path with each grade's defaults: the 1-sigma each parameter reaches, in its unit
"""
from __future__ import annotations

import argparse

import numpy as np

from gfins_fmi.sim import rotation as rot
from gfins_fmi.calibration import grades, syscal_filter
from gfins_fmi.calibration import system as c36

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


def grade_table():
    """The full model's final 1-sigma per grade on the 19-position path (units)."""
    sched = rot.turntable_path_19()
    res = {g: c36.covariance_study(sched, np.radians(34.0), 80.0, grades.config_for_grade(grades.grade(g)),
                                   dt_s=0.05) for g in grades.GRADES}
    names, units = syscal_filter.param_names("full", True), syscal_filter.param_units("full", True)
    print("full model, 19-position path (23.3 min, 34 deg), each grade's defaults (prior and white "
          "noise): prior 1-sigma -> final 1-sigma\n")
    print("| parameter | unit | " + " | ".join(res) + " |")
    print("|---|---|" + "---|" * len(res))
    for k, n in enumerate(names):
        u = units[k]
        cells = [f"{r['prior_std'][k] / u[1]:.3g} -> {r['std'][k] / u[1]:.3g}" for r in res.values()]
        print(f"| {n} | {u[0]} | " + " | ".join(cells) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=("seed", "full"), default="seed")
    ap.add_argument("--grades", action="store_true")
    a = ap.parse_args()
    if a.grades:
        return grade_table()
    if a.model == "seed":
        cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0, model="seed",
                                         estimate_delay=False)
    else:
        cfg = grades.config_for_grade(grades.grade("navigation"))
    res = {name: c36.covariance_study(s, LAT, H, cfg, dt_s=0.05) for name, s in paths().items()}
    names = cfg.names
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
