"""``gfins calibrate``: system-level calibration of a recorded multi-position run.

    gfins calibrate IMU --lat DEG --height M [--lon DEG] [--format csv|kfgins]
                    [--arw DEG_SQRT_H] [--vrw UG_SQRT_HZ] [--delay] [--passes N]
                    [--prior NAME=VALUE ...] [--report REPORT.md] [--json PARAMS.json] [--plot DIR]
                    [--simulate seed001|turntable19 [--sim-seed N]]

Prints the static intervals and turns found, every parameter with its 1-sigma and the
parameters the path cannot observe; ``--json`` writes the estimates, their stds and the
error model as start values of the SINS and vehicle FMUs; ``--simulate`` first writes a
simulated raw record of that path to IMU (its true errors beside it, IMU.truth.json).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib

from gfins_fmi.estimation.cli import _finite, _nonneg

__all__ = ["add_parser", "run"]


def _latitude(text: str) -> float:
    v = _finite(text)
    if not abs(v) < 89.0:
        raise argparse.ArgumentTypeError(f"the latitude must be within +-89 deg (in degrees); got {v}")
    return v


def _prior(text: str):
    from gfins_fmi.estimation.calibration36 import Prior
    names = [f.name for f in dataclasses.fields(Prior)]
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--prior takes NAME=VALUE with NAME one of {', '.join(names)}")
    k, v = text.split("=", 1)
    if k not in names:
        raise argparse.ArgumentTypeError(f"--prior: unknown {k!r}; one of {', '.join(names)}")
    val = _finite(v)
    if not (val > 0 or (k == "gravity_ug" and val >= 0)):
        raise argparse.ArgumentTypeError(f"--prior {k} must be > 0; got {val}")
    return k, val


def add_parser(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("calibrate", help="system-level calibration (seed 001's 36-state filter) of a "
                       "raw multi-position record", description=__doc__,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("imu", type=pathlib.Path, help="raw IMU record (IMU frame), starting at rest")
    p.add_argument("--format", choices=("csv", "kfgins"), default="csv",
                   help="csv: gfins_fmi.io ImuRecord CSV (increments or rates); kfgins: KF-GINS IMU file")
    p.add_argument("--lat", type=_latitude, required=True, help="site latitude, deg")
    p.add_argument("--lon", type=_finite, default=0.0, help="site longitude, deg (default 0)")
    p.add_argument("--height", type=_finite, required=True, help="site ellipsoidal height, m")
    p.add_argument("--arw", type=_nonneg, default=0.002,
                   help="gyro angle random walk, deg/sqrt(h) (default 0.002: seed 001's laser gyros)")
    p.add_argument("--vrw", type=_nonneg, default=10.0,
                   help="accelerometer white noise, ug/sqrt(Hz) (default 10)")
    p.add_argument("--vel-std", type=_nonneg, default=1e-3,
                   help="std of the zero-velocity measurement (base sway), m/s (default 0.001)")
    p.add_argument("--delay", action="store_true",
                   help="estimate the accelerometer sample delay (37th state)")
    p.add_argument("--passes", type=int, default=2, choices=range(1, 11), metavar="N",
                   help="filter passes, each linearised about the previous estimates, the prior kept (default 2)")
    p.add_argument("--prior", type=_prior, action="append", default=[], metavar="NAME=VALUE",
                   help="prior 1-sigma (calibration36.Prior field, its unit), e.g. gyro_bias_deg_h=0.05")
    p.add_argument("--report", type=pathlib.Path, help="write the report (markdown) here")
    p.add_argument("--json", type=pathlib.Path, help="write estimates, stds and FMU parameters here")
    p.add_argument("--plot", type=pathlib.Path, help="folder for the convergence and residual figures")
    p.add_argument("--simulate", choices=("seed001", "turntable19"),
                   help="first write a simulated record of this path to IMU (random errors at the "
                        "prior's level, the noise of --arw/--vrw)")
    p.add_argument("--sim-seed", type=int, default=0, help="seed of --simulate (default 0)")
    p.set_defaults(func=run)
    return p


def _simulate(args, config) -> None:
    import numpy as np

    import gfins_fmi.rotation as rot
    from gfins_fmi.estimation import calibration36 as c36
    from gfins_fmi.imu_errors import ImuNoise
    sched = rot.seed001_path(2) if args.simulate == "seed001" else rot.turntable_path_19()
    rng = np.random.default_rng(args.sim_seed)
    p = c36.random_params(rng, config.prior, 28 if args.delay else 27)
    rec, _ = c36.simulate_record(sched, p, np.radians(args.lat), args.height,
                                 noise=ImuNoise(gyro_arw_deg_sqrt_h=args.arw,
                                                accel_vrw_ug_sqrt_hz=args.vrw),
                                 seed=args.sim_seed + 1)
    rec.to_csv(args.imu)
    truth = args.imu.with_name(args.imu.name + ".truth.json")
    truth.write_text(json.dumps({"names": list(c36.PARAM_NAMES[:p.size]), "si": p.tolist()}, indent=1),
                     encoding="utf-8")
    print(f"simulated {args.simulate}: {len(rec)} samples written to {args.imu} (truth: {truth})")


def run(args) -> int:
    import numpy as np

    from gfins_fmi import io
    from gfins_fmi.estimation import calibration36 as c36
    prior = dataclasses.replace(c36.Prior(), **dict(args.prior))
    config = c36.SyscalConfig(vel_std_m_s=args.vel_std if args.vel_std > 0 else 1e-6,
                              gyro_arw_deg_sqrt_h=args.arw, accel_vrw_ug_sqrt_hz=args.vrw,
                              estimate_delay=args.delay, prior=prior)
    if args.simulate:
        _simulate(args, config)
    imu = io.ImuRecord.from_csv(args.imu) if args.format == "csv" else io.read_kfgins_imu(args.imu)
    rep = c36.calibrate(imu, np.radians(args.lat), args.height, lon_rad=np.radians(args.lon),
                        config=config, passes=args.passes)
    segs = [s.describe() for s in rep.segments]
    text = [f"# calibration of {args.imu}", "",
            f"{len(imu)} samples; {sum(s.kind == 'static' for s in rep.segments)} static intervals, "
            f"{sum(s.kind == 'turn' for s in rep.segments)} turns; {rep.passes} passes, "
            f"{len(rep.names) + 9} states", "", "segments: " + "; ".join(segs), "", rep.table(), ""]
    if rep.unobservable:
        text.append("not observed by this record (estimate = prior, 1-sigma = prior): "
                    + ", ".join(rep.unobservable))
    if rep.weak:
        text.append("weakly observed (1-sigma above 30% of the prior): " + ", ".join(rep.weak))
    nis = float(np.mean(rep.epochs["nis"]))
    text.append(f"mean NIS of the zero-velocity updates: {nis:.3g} (3 for a consistent filter; far "
                "above: more base motion or sensor noise than configured)")
    out = "\n".join(text)
    print(out)
    if args.report:
        args.report.write_text(out + "\n", encoding="utf-8")
    if args.json:
        doc = {"names": list(rep.names), "estimate_si": rep.estimate.tolist(), "std_si": rep.std.tolist(),
               "units": [u[0] for u in c36.PARAM_UNITS[:len(rep.names)]],
               "estimate_units": rep.in_units(rep.estimate).tolist(),
               "std_units": rep.in_units(rep.std).tolist(), "unobservable": rep.unobservable,
               "fmu_parameters": rep.errors.fmu_parameters(), "accel_delay_s": rep.accel_delay_s}
        args.json.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    if args.plot:
        from gfins_fmi.estimation.calibration36 import plot_report
        for f in plot_report(rep, args.plot):
            print(f"figure: {f}")
    return 0
