"""``gfins demo``: the main job end to end (:mod:`gfins_fmi.experiments.demo`) and its
verdict."""
from __future__ import annotations

from gfins_fmi.experiments import demo

__all__ = ["run"]


def run(args) -> int:
    res = demo.run(out_dir=args.out, duration_s=args.duration, dt_s=args.dt, l_m=args.lever_arm,
                   noise_m_s2=args.noise)
    ok = all(res[f"fmi{v}"]["problems"] == [] and res[f"fmi{v}"]["max_rel_diff"] <= 1e-12
             for v in (2, 3)) and res["sins"]["fmu_max_rel_diff"] <= 1e-12 \
        and res["cosim"]["master_diff"] == 0.0 and res["cosim"]["ssp_diff"] == 0.0
    print("\ndemo " + ("passed: C core, FMUs and analysis agree" if ok else "FAILED"))
    return 0 if ok else 1
