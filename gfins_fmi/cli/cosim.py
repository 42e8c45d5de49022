"""``gfins cosim``: the vehicle FMU with a navigator FMU (seed 001's run), through the
Python master, an SSP file and a container FMU, each checked against cffi (the
integrated navigator: against the batch API, with GNSS, barometer and odometer)."""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi.cli.files import outputs
from gfins_fmi.fmi.reference import compare_runners
from gfins_fmi.sim.vehicle import VehicleProfile

__all__ = ["run"]


def run(args) -> int:
    out = pathlib.Path(args.out)
    res = compare_runners(args.navigator, VehicleProfile.seed001(align_s=args.align),
                                args.seconds, out, step_s=args.step, fmi_version=args.fmi,
                                progress=not args.quiet)
    e = res["master"]["errors"]
    integrated = args.navigator == "ins_gnss"
    print(f"vehicle + {args.navigator}, {args.seconds:g} s at {1 / args.step:g} Hz"
          + (" (GNSS 1 Hz 0.37 s off the grid, 0.1 s latency, out 300-360 s; barometer, "
             "odometer; tactical IMU)" if integrated else ""))
    print(f"  navigation error: horizontal max {e['horizontal_m'].max():.4g} m (final "
          f"{e['horizontal_m'][-1]:.4g} m), velocity max {e['velocity_m_s'].max():.3g} m/s, "
          f"attitude max {np.degrees(np.linalg.norm(e['attitude_rad'], axis=1).max()):.3g} deg")
    names = {"master": f"Python master (FMI {args.fmi}.0)", "ssp": "fmpy SSP simulator",
             "container": "fmpy container FMU (FMI 2.0)"}
    reference = "the batch API (IntegratedNavigator.run)" if integrated else "the cffi navigator"
    for runner, r in res.items():
        where = f" {r['path']}" if r["path"] else ""
        print(f"  {names[runner]}{where}: {r['wall_s']:.1f} s; vs {reference} on the "
              f"same sensor data |dlat| {r['diff']['lat_rad']:.3g} rad, |dv| "
              f"{r['diff']['v_m_s']:.3g} m/s"
              + (f", |dq| {r['diff']['q']:.3g}, |dstd| {r['diff']['std']:.3g}" if integrated else ""))
    with outputs() as outs:     # written beside its name, renamed when complete
        np.savetxt(outs.file(out / "cosim_errors.csv"),
                   np.c_[e["t_s"], e["horizontal_m"], e["velocity_m_s"],
                         np.linalg.norm(e["attitude_rad"], axis=1)], delimiter=",",
                   header="t_s,horizontal_error_m,velocity_error_m_s,attitude_error_rad", comments="")
        outs.commit()
    print(f"  errors -> {out / 'cosim_errors.csv'}")
    ok = all(max(r["diff"].values()) == 0.0 for r in res.values())
    print("cosim " + (f"passed: every co-simulation equals {reference} bit for bit"
                      if ok else f"FAILED: a co-simulation differs from {reference}"))
    return 0 if ok else 1
