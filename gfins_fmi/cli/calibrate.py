"""``gfins calibrate``: system-level calibration of a recorded multi-position run
(usage: ``gfins calibrate --help``, :data:`gfins_fmi.cli.parser.CALIBRATE_DESCRIPTION`):
prints the segments, every parameter with its 1-sigma and its shift against the prior,
the checks and warnings, the compensation form; writes the report, the JSON of both
conventions and FMU start values, the compensation form, the figures, and the effective
configuration beside them (``R.config.json``: every option with its value and unit, the
grade and filter settings the run chose, the inputs; ``gfins calibrate --config
R.config.json`` repeats the run). ``--config FILE`` (TOML or YAML) gives the options from a
file, ``--print-config`` prints its template (gfins_fmi.cli.config_file)."""
from __future__ import annotations

import dataclasses
import json

import numpy as np

from gfins_fmi.calibration import compensation
from gfins_fmi.calibration.grades import config_for_grade, detect_grade, grade, measured_noise
from gfins_fmi.calibration.segmentation import record_increments, segment_record
from gfins_fmi.calibration.syscal_filter import (Prior, SyscalConfig, core_gravity_m_s2,
                                                 imu_errors_to_params, param_names, params_to_c)
from gfins_fmi.calibration.system import calibrate, plot_report, random_params, simulate_record
from gfins_fmi.cli import calibrate_poses
from gfins_fmi.cli.config_file import config_beside, config_template, configured, recording
from gfins_fmi.cli.files import read_imu, run_writing
from gfins_fmi.cli.parser import RAW_FORMATS, build_parser, check_calibrate
from gfins_fmi.io import read_raw_imu
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim import rotation as rot

__all__ = ["run"]


def _simulate(args) -> None:
    """The record of --simulate: seed errors drawn as before issue 22 (the same records for
    the same options), or a laboratory tool's (lever arms across the axes, the delay);
    the record and its truth written as one output set."""
    truth = args.imu.with_name(args.imu.name + ".truth.json")
    run_writing(lambda a, outs: _simulate_into(a, outs, truth), args, files=(truth, args.imu))


def _simulate_into(args, outs, truth) -> None:
    sched = rot.seed001_path(2) if args.simulate == "seed001" else rot.turntable_path_19()
    rng = np.random.default_rng(args.sim_seed)
    noise = ImuNoise(gyro_arw_deg_sqrt_h=0.002 if args.arw is None else args.arw,
                     accel_vrw_ug_sqrt_hz=10.0 if args.vrw is None else args.vrw)
    if args.sim_errors == "seed":
        prior = dataclasses.replace(Prior(), **dict(args.prior))
        p = random_params(rng, prior, 28 if args.delay else 27)
        names = list(param_names("seed", bool(args.delay)))
        truth_doc = {"model": "seed", "names": names, "si": p.tolist()}
    else:
        cf = compensation.random_compensation(rng)
        p = compensation.from_compensation(cf)
        full = imu_errors_to_params(p, "full", True)
        truth_doc = {"model": "full", "names": list(param_names("full", True)), "si": full.tolist(),
                     "compensation_form": cf.to_dict()}
    rec, _ = simulate_record(sched, p, np.radians(args.lat), args.height, noise=noise,
                             seed=args.sim_seed + 1)
    rec.to_csv(outs.file(args.imu))
    outs.write_text(truth, json.dumps(truth_doc, indent=1))
    print(f"simulated {args.simulate}: {len(rec)} samples written to {args.imu} (truth: {truth})")


def _read(args):
    if args.format in RAW_FORMATS:
        return read_raw_imu(args.imu, RAW_FORMATS[args.format], args.raw_kind, args.gyro_unit,
                            args.accel_unit, args.time_scale)
    return read_imu(args.imu, args.format)


def _config(args, imu) -> tuple:
    """The filter settings: the grade's (named or read from the first static interval),
    then the options given. Returns (config, grade name, what the static interval showed)."""
    lat, h = np.radians(args.lat), args.height
    figures = {}
    if args.grade == "auto":
        t_end, dt, dth, dv = record_increments(imu)
        first = next((s for s in segment_record(t_end, dth) if s.kind == "static"), None)
        if first is None:
            gr = grade("navigation")          # calibrate() refuses the record and says why
        else:
            sl = slice(first.i0, first.i1)
            gr, figures = detect_grade(dth[sl], dv[sl], dt[sl], lat, h, args.gravity)
    else:
        gr = grade(args.grade)
    delay = args.model == "full" if args.delay is None else args.delay
    changes = {"model": args.model, "estimate_delay": delay,
               "prior": dataclasses.replace(gr.prior, **dict(args.prior)),
               **(measured_noise(gr, figures) if figures else {})}
    if args.arw is not None:
        changes["gyro_arw_deg_sqrt_h"] = args.arw
    if args.vrw is not None:
        changes["accel_vrw_ug_sqrt_hz"] = args.vrw
    if args.vel_std is not None:
        changes["vel_std_m_s"] = args.vel_std if args.vel_std > 0 else 1e-6
    return config_for_grade(gr, **changes), gr.name, figures


def _prior_mean(args, config: SyscalConfig):
    if args.prior_mean is None:
        return None
    e = compensation.from_compensation(compensation.read_compensation(args.prior_mean))
    if config.model == "seed":
        pos = e.lever_arm_matrix_cm
        if np.any(pos[~np.eye(3, dtype=bool)]):
            e = dataclasses.replace(e, lever_arm_cm=np.diag(pos))
            print(f"note: {args.prior_mean} has lever arms across the axes; the seed model keeps "
                  "those along the axes")
    return params_to_c(imu_errors_to_params(e, config.model, True), config.model, True)


def run(args) -> int:
    parser = build_parser()[1]["calibrate"]
    if args.print_config:
        print(config_template(parser, "calibrate"), end="")
        return 0
    configured(args, parser, "calibrate", check_calibrate)
    if args.module == "calibrate_poses":      # `calibrate poses RECORD` given by the configuration file
        return calibrate_poses.run(args)
    if args.simulate:
        _simulate(args)
    args.resolved = {}
    saved = config_beside(args, (args.report, args.json, args.compensation), args.plot, "calibrate")
    inputs = (args.imu, args.prior_mean)
    return run_writing(recording(_calibrate, parser, "calibrate", saved, inputs), args, inputs=inputs,
                       files=(args.report, args.json, args.compensation, saved), folder=args.plot)


def _calibrate(args, outs) -> int:
    imu = _read(args)
    config, grade_name, figures = _config(args, imu)
    # what the run chose itself (the grade read from the record, its priors and noise): recorded with it
    args.resolved = {"grade": grade_name, "grade_figures": figures, "syscal_config": dataclasses.asdict(config)}
    rep = calibrate(imu, np.radians(args.lat), args.height, lon_rad=np.radians(args.lon),
                    config=config, passes=args.passes, params0=_prior_mean(args, config),
                    gravity_m_s2=args.gravity, widen_priors=args.widen_priors,
                    max_rounds=args.max_rounds, progress=args.progress,
                    heading_rad=None if args.heading is None else np.radians(args.heading))
    rep.grade, rep.grade_figures = grade_name, figures
    segs = [s.describe() for s in rep.segments]
    g_normal = core_gravity_m_s2(np.radians(args.lat), args.height)
    seen = (f" (first static interval: ARW {figures['arw_deg_sqrt_h']:.3g} deg/sqrt(h), accelerometer "
            f"white noise {figures['vrw_ug_sqrt_hz']:.3g} ug/sqrt(Hz), |gyro bias| >= "
            f"{figures['gyro_bias_bound_deg_h']:.3g} deg/h, |accel bias| >= {figures['accel_bias_bound_ug']:.3g} ug)"
            if figures else "")
    text = [f"# calibration of {args.imu}", "",
            f"{len(imu)} samples; {sum(s.kind == 'static' for s in rep.segments)} static intervals, "
            f"{sum(s.kind == 'turn' for s in rep.segments)} turns; {rep.passes} passes, {rep.n_states} "
            f"states ({rep.model} model{', delay' if config.estimate_delay else ''}); grade {grade_name}{seen}; "
            f"gravity {rep.gravity_m_s2:.7g} m/s^2 (normal gravity {g_normal:.7g})", "",
            "segments: " + "; ".join(segs), "", rep.table(), ""]
    if rep.unobservable:
        text.append("not observed by this record (estimate = prior, 1-sigma = prior): "
                    + ", ".join(rep.unobservable))
    if rep.weak:
        text.append("weakly observed (1-sigma above 30% of the prior): " + ", ".join(rep.weak))
    text += [rep.summary(), "", "## the result in the compensation form (PSINS clbt fields, "
             "accelerometer frame; docs/calibration_conventions.md)", "", "```",
             rep.compensation().text(), "```"]
    text += [f"note: {n}" for n in rep.notes]
    out = "\n".join(text)
    print(out)
    if args.report:
        outs.write_text(args.report, out + "\n")
    if args.json:
        outs.write_text(args.json, json.dumps(rep.document(), indent=1))
    if args.compensation:
        compensation.write_compensation(rep.compensation(), outs.file(args.compensation))
    if args.plot:
        for f in plot_report(rep, args.plot, save=outs.file):
            print(f"figure: {f}")
    return 0
