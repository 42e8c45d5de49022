"""``gfins calibrate``: system-level calibration of a recorded multi-position run
(usage: ``gfins calibrate --help``, :data:`gfins_fmi.cli.parser.CALIBRATE_DESCRIPTION`):
prints the segments, every parameter with its 1-sigma, the parameters the path cannot
observe; writes the report, the JSON of estimates and FMU start values, the figures."""
from __future__ import annotations

import dataclasses
import json

import numpy as np

from gfins_fmi.calibration.syscal_filter import PARAM_NAMES, PARAM_UNITS, Prior, SyscalConfig
from gfins_fmi.calibration.system import calibrate, plot_report, random_params, simulate_record
from gfins_fmi.cli.files import outputs, read_imu
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim import rotation as rot

__all__ = ["run"]


def _simulate(args, config) -> None:
    with outputs() as outs:
        truth = outs.claim(args.imu.with_name(args.imu.name + ".truth.json"))
        outs.claim(args.imu)
        _simulate_into(args, config, outs, truth)
        outs.commit()


def _simulate_into(args, config, outs, truth) -> None:
    sched = rot.seed001_path(2) if args.simulate == "seed001" else rot.turntable_path_19()
    rng = np.random.default_rng(args.sim_seed)
    p = random_params(rng, config.prior, 28 if args.delay else 27)
    rec, _ = simulate_record(sched, p, np.radians(args.lat), args.height,
                                 noise=ImuNoise(gyro_arw_deg_sqrt_h=args.arw,
                                                accel_vrw_ug_sqrt_hz=args.vrw),
                                 seed=args.sim_seed + 1)
    rec.to_csv(outs.file(args.imu))
    outs.write_text(truth, json.dumps({"names": list(PARAM_NAMES[:p.size]), "si": p.tolist()}, indent=1))
    print(f"simulated {args.simulate}: {len(rec)} samples written to {args.imu} (truth: {truth})")


def run(args) -> int:
    prior = dataclasses.replace(Prior(), **dict(args.prior))
    config = SyscalConfig(vel_std_m_s=args.vel_std if args.vel_std > 0 else 1e-6,
                              gyro_arw_deg_sqrt_h=args.arw, accel_vrw_ug_sqrt_hz=args.vrw,
                              estimate_delay=args.delay, prior=prior)
    if args.simulate:
        _simulate(args, config)
    with outputs(args.imu) as outs:
        for path in (args.report, args.json):
            if path:
                outs.claim(path)
        if args.plot:
            outs.claim_folder(args.plot)
        status = _calibrate(args, config, outs)
        outs.commit()
        return status


def _calibrate(args, config, outs) -> int:
    imu = read_imu(args.imu, args.format)
    rep = calibrate(imu, np.radians(args.lat), args.height, lon_rad=np.radians(args.lon),
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
        outs.write_text(args.report, out + "\n")
    if args.json:
        doc = {"names": list(rep.names), "estimate_si": rep.estimate.tolist(), "std_si": rep.std.tolist(),
               "units": [u[0] for u in PARAM_UNITS[:len(rep.names)]],
               "estimate_units": rep.in_units(rep.estimate).tolist(),
               "std_units": rep.in_units(rep.std).tolist(), "unobservable": rep.unobservable,
               "fmu_parameters": rep.errors.fmu_parameters(), "accel_delay_s": rep.accel_delay_s}
        outs.write_text(args.json, json.dumps(doc, indent=1))
    if args.plot:
        for f in plot_report(rep, args.plot, save=outs.file):
            print(f"figure: {f}")
    return 0
