"""``gfins align``: initial alignment of recorded IMU files from the shell (issue 13).

    gfins align --print-config                    # a commented template of the configuration file
    gfins align [MODE IMU ...] --config FILE.toml [options]   # settings from a file; options override it
    gfins align static IMU --position LAT,LON,H [--window T0,T1] [--grade G] [--disturbed]
                       [--heading DEG [--heading-std DEG]] [--fine [--fine-end T1]]
    gfins align motion IMU SPEED --initial LAT,LON,H,HEADING,PITCH,ROLL [--depth DEPTH]
                       [--passes N] [--grade G] [--heading-std DEG] [--output PASSES.csv]
    gfins align transfer SLAVE_IMU MASTER_NAV [--matching velocity|velocity+attitude]
                       [--mount H,P,R] [--lever X,Y,Z] [--time-offset S] [--fix lever|offset]
                       [--flexure STD_DEG,TAU_S] [--grade consumer] [--gyro-bias DEG_H]
                       [--accel-bias UG] [--truth T.csv] [--truth-json T.json]
                       [--output EST.csv] [--plot FIG.png] [--simulate SECONDS]

static: levelling and gyrocompassing over the window at rest (motion in it is refused;
a swaying base is warned of, with the --disturbed hint), or with --disturbed the
inertial-frame coarse alignment; --heading gives the heading when gyrocompassing cannot
(or replaces it); then with --fine the zero-velocity fine alignment from the window's end
to --fine-end (default: the record's end; after --disturbed with a 0.1 m/s velocity std:
the base sways). motion: the
seed-003 in-motion alignment with a speed sensor (OdometerRecord CSV: t_s, speed_m_s,
std_m_s) and optionally depth (BaroRecord CSV, h_m = -depth), forward-backward passes
over the stored record; prints the attitude after each pass and writes the pass table.
transfer: a slave IMU aligned and calibrated against a master INS on the same host
(gfins_fmi.estimation.transfer): prints the mounting, lever arm, time offset, biases and
attitude with their 1-sigma (and, against a truth, the errors and the share outside 3
sigma), writes the estimates over time and the convergence figure. Exit status 0 when
aligned, 1 when the alignment reports that it has not converged (motion: its verdict;
transfer: the mounting's 1-sigma above --tolerance; the outputs are written all the
same), 2 on bad input.

Every run that writes a file writes its effective configuration beside it
(``OUT.config.json``: every option with its value and unit, the grade and bias 1-sigma
and the window the run chose, the inputs), or where ``--save-config FILE`` says; ``gfins
align --config OUT.config.json`` repeats the run (gfins_fmi.cli.config_file).
"""
from __future__ import annotations

import dataclasses
import json
import math
import pathlib
import sys
import warnings

import numpy as np

from gfins_fmi import io
from gfins_fmi.cli.config_file import config_beside, config_template, configured, recording
from gfins_fmi.cli.files import compensated, outputs, run_writing
from gfins_fmi.cli.initial import from_initial_option, record_start_s
from gfins_fmi.cli.noise import imu_noise
from gfins_fmi.cli.parser import build_parser, check_align
from gfins_fmi.estimation.alignment import coarse_align, coarse_align_inertial
from gfins_fmi.estimation.config import UG, FilterConfig, InitialState
from gfins_fmi.estimation.fine_alignment import align_in_motion, fine_align
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.estimation.transfer import MasterErrors, TransferTruth, transfer_align
from gfins_fmi.io.columns import ALIGNMENT_PASS_COLUMNS, TRANSFER_COLUMNS
from gfins_fmi.io.navigation import read_navigation, write_navigation
from gfins_fmi.sim.transfer import SlaveInstallation, simulate_transfer

__all__ = ["run"]


def _biases(args, noise):
    deg = math.pi / 180.0
    gb = (args.gyro_bias if args.gyro_bias is not None else noise.gyro_bias_instability_deg_h) * deg / 3600
    ab = (args.accel_bias if args.accel_bias is not None else noise.accel_bias_instability_ug) * UG
    return max(gb, 1e-12), max(ab, 1e-9)


def _sway(imu, t0: float, t1: float):
    """The largest angle (rad) the body turned away from its mean rate inside the window,
    and what white gyro noise alone would give (3 sigma of its random walk, from the first
    differences of the increments, which a slow sway does not reach)."""
    t = np.asarray(imu.t_s)
    sel = (t > t0) & (t <= t1)
    g = np.asarray(imu.gyro)[sel]
    if imu.kind != "increments":
        g = g * float(np.median(np.diff(t[sel])))
    if len(g) < 10:
        return 0.0, 0.0
    dev = g - g.mean(axis=0)
    excursion = float(np.linalg.norm(np.cumsum(dev, axis=0), axis=1).max())
    white = float(np.linalg.norm(np.diff(g, axis=0).std(axis=0)) / math.sqrt(2.0))
    return excursion, 3.0 * white * math.sqrt(len(g))


def _given_heading(co, args):
    """The coarse alignment with --heading in place of its heading (1-sigma --heading-std)."""
    deg = math.pi / 180.0
    e = co.euler_rad.copy()
    e[0] = (args.heading % 360.0) * deg
    return dataclasses.replace(co, euler_rad=e, heading_std_rad=args.heading_std * deg, heading_method="given")


def run(args) -> int:
    parser = build_parser()[1]["align"]
    if args.print_config:
        print(config_template(parser, "align"), end="")
        return 0
    configured(args, parser, "align", check_align)
    args.resolved = {}
    saved = config_beside(args, (args.output, args.plot), command="align")
    if args.mode == "transfer":
        if args.simulate is not None:
            _simulate(args)
        inputs = (args.imu, args.speed, args.truth, args.truth_json, args.imu_errors)
        return run_writing(recording(_transfer, parser, "align", saved, inputs), args, inputs=inputs,
                           files=(args.output, args.plot, saved))
    inputs = (args.imu, args.speed, args.depth, args.imu_errors)
    return run_writing(recording(_run, parser, "align", saved, inputs), args, inputs=inputs,
                       files=(args.output, saved))


def _resolved_biases(args, grade: str, gb: float, ab: float) -> None:
    """The grade and turn-on bias 1-sigma the run used, for its effective configuration."""
    args.resolved.update({"grade": grade, "gyro_bias_1sigma_deg_h": gb * 180.0 / math.pi * 3600.0,
                          "accel_bias_1sigma_ug": ab / UG})


def _run(args, outs) -> int:
    deg = math.pi / 180.0
    noise = imu_noise(args.grade or "navigation")
    imu = io.ImuRecord.from_csv(args.imu)
    if args.imu_errors:
        imu = compensated(imu, read_imu_errors(args.imu_errors))
    gb, ab = _biases(args, noise)
    _resolved_biases(args, args.grade or "navigation", gb, ab)
    if args.mode == "static":
        lat, lon, h = args.position
        span = 300.0 if args.disturbed else 60.0
        t0, t1 = args.window if args.window else (imu.t_s[0] - 1e-9, imu.t_s[0] + span)
        args.resolved["window_s"] = [float(t0), float(t1)]
        align = coarse_align_inertial if args.disturbed else coarse_align
        co = align(imu, t0, t1, lat * deg, gyro_bias_std_rad_s=gb, accel_bias_std_m_s2=ab)
        if not args.disturbed:
            moved, noise_only = _sway(imu, t0, t1)
            if moved > max(noise_only, 1e-4):
                warnings.warn(f"the base turned up to {moved / deg:.3g} deg inside the window at rest (white gyro "
                              f"noise alone: {noise_only / deg:.2g} deg): on a swaying base (a moored ship, an idling "
                              "vehicle) the static alignment's attitude is the window's mean and gyrocompassing is "
                              "biased beyond its reported 1-sigma; use --disturbed",
                              UserWarning, stacklevel=2)
        if args.heading is not None:
            co = _given_heading(co, args)
        e = co.euler_rad / deg
        print(f"coarse ({co.heading_method}): heading {e[0]:.4f} deg, pitch {e[1]:.4f} deg, roll {e[2]:.4f} deg; "
              f"tilt 1-sigma {co.tilt_std_rad / deg:.4f} deg, heading 1-sigma {co.heading_std_rad / deg:.4f} deg")
        for note in co.notes:
            print("note:", note)
        if args.fine:
            if not math.isfinite(co.euler_rad[0]):
                raise ValueError("the coarse alignment has no heading (see the note above): give one with "
                                 "--heading DEG (and its 1-sigma with --heading-std DEG) for --fine")
            cfg = FilterConfig(imu=noise, input=imu.kind, gate_probability=None)
            given = {"heading_std_rad": co.heading_std_rad} if co.heading_method == "given" else {}
            fa = fine_align(imu, lat * deg, lon * deg, h, config=cfg, coarse=co, gyro_bias_std_rad_s=gb,
                            accel_bias_std_m_s2=ab, t1_s=args.fine_end,
                            velocity_std_m_s=0.1 if args.disturbed else 1e-3, **given)
            e, s = fa.euler_rad / deg, fa.attitude_std_rad / deg
            t_end = float(imu.t_s[-1]) if args.fine_end is None else args.fine_end
            print(f"fine ({co.t_s[1]:.10g} to {t_end:.10g} s): heading {e[0]:.4f} deg, pitch {e[1]:.4f} deg, roll {e[2]:.4f} deg; 1-sigma E/N/U "
                  f"{s[0]:.4f}/{s[1]:.4f}/{s[2]:.4f} deg")
        return 0
    speed = io.OdometerRecord.from_csv(args.speed)
    depth = io.BaroRecord.from_csv(args.depth) if args.depth else None
    hd = args.initial[3]
    s0 = float(speed.speed_m_s[0])
    v0 = np.array([s0 * math.sin(hd * deg), s0 * math.cos(hd * deg), 0.0])
    nav0 = from_initial_option(args.initial, record_start_s(imu), v0)
    sv = max(s0 * args.heading_std * deg, 0.1)
    init = InitialState(nav0, position_std_m=1.0, velocity_std_m_s=(sv, sv, 0.1),
                        attitude_std_rad=(args.tilt_std * deg, args.tilt_std * deg, args.heading_std * deg),
                        gyro_bias_std_rad_s=gb, accel_bias_std_m_s2=ab)
    cfg = FilterConfig(imu=noise, input=imu.kind, gate_probability=0.9999, gate_reset_count=0)
    al = align_in_motion(imu, speed, depth=depth, config=cfg, initial=init, passes=args.passes,
                         keep_rows=args.progress, progress=args.progress)
    e = al.pass_euler_rad / deg
    for k, row in enumerate(al.passes):
        what = "forward " if row["direction"] > 0 else "backward"
        print(f"pass {k:3d} {what} t = {row['t_s']:.3f} s: heading {e[k, 0]:9.4f} deg, pitch {e[k, 1]:8.4f} deg, "
              f"roll {e[k, 2]:8.4f} deg; 1-sigma heading {row['std9'][8] / deg:.4f} deg; updates "
              f"{int(row['n_updates'])}, rejected {int(row['n_rejected'])}")
    for note in al.notes:
        print("note:", note)
    if args.output:
        cols = [al.passes["t_s"], al.passes["direction"].astype(float), e[:, 0], e[:, 1], e[:, 2],
                *(al.passes["std9"][:, 6 + i] / deg for i in range(3)),
                al.passes["n_updates"].astype(float), al.passes["n_rejected"].astype(float)]
        outs.write_table(args.output, ALIGNMENT_PASS_COLUMNS, cols)
        print(f"{len(al.passes)} passes -> {args.output}")
    if not al.converged:
        print("gfins align: warning: the alignment has not converged (see the note above); exit status 1",
              file=sys.stderr)
        return 1
    return 0


# ---- transfer alignment ---------------------------------------------------------------------

_ARCMIN = math.pi / 180.0 / 60.0
_MG = 9.80665e-3


def _simulate(args) -> None:
    """--simulate: the study's scenario (bench/study_transfer.py) written where the command
    then reads it, with its truth beside the slave's record."""
    inst = SlaveInstallation(mount_rad=(20 * _ARCMIN, -15 * _ARCMIN, 25 * _ARCMIN), lever_arm_m=(0.1, 0.0, 0.0),
                             time_offset_s=0.015)
    sc = simulate_transfer(args.simulate, installation=inst, seed=args.sim_seed)
    truth = args.imu.with_name(args.imu.name + ".truth.csv")
    truth_json = args.imu.with_name(args.imu.name + ".truth.json")
    info = {"mount_deg": [math.degrees(x) for x in inst.mount_rad], "lever_arm_m": list(inst.lever_arm_m),
            "time_offset_s": inst.time_offset_s,
            "gyro_bias_deg_h": [math.degrees(x) * 3600 for x in sc.slave_gyro_bias_rad_s],
            "accel_bias_mg": [x / _MG for x in sc.slave_accel_bias_m_s2]}
    with outputs() as outs:     # the scenario's four files as one set (the alignment's inputs)
        for path in (args.imu, args.speed, truth, truth_json):
            outs.claim(path)
        sc.slave_imu.to_csv(outs.file(args.imu))
        write_navigation(outs.file(args.speed), sc.master, sc.master_rate_rad_s)
        sc.truth.to_csv(outs.file(truth))
        outs.write_text(truth_json, json.dumps(info, indent=1) + "\n")
        outs.commit()
    print(f"simulated {args.simulate:g} s: slave -> {args.imu}, master -> {args.speed}, truth -> {truth}, "
          f"{truth_json}")


def _read_truth_json(path) -> dict:
    try:
        d = json.loads(pathlib.Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"--truth-json {path}: {exc}") from exc
    conv = {"mount_deg": ("mount_rad", math.pi / 180), "lever_arm_m": ("lever_arm_m", 1.0),
            "time_offset_s": ("time_offset_s", 1.0), "gyro_bias_deg_h": ("gyro_bias_rad_s", math.pi / 180 / 3600),
            "accel_bias_mg": ("accel_bias_m_s2", _MG)}
    unknown = set(d) - set(conv)
    if unknown:
        raise ValueError(f"--truth-json {path}: unknown keys {sorted(unknown)}; known: {sorted(conv)}")
    return {conv[k][0]: np.asarray(v, float) * conv[k][1] for k, v in d.items()}


def _transfer(args, outs) -> int:
    deg = math.pi / 180.0
    noise = imu_noise(args.grade or "consumer")
    imu = io.ImuRecord.from_csv(args.imu)
    if args.imu_errors:
        imu = compensated(imu, read_imu_errors(args.imu_errors))
    if args.speed.suffix == ".nav":
        master, rates = io.read_kfgins_nav(args.speed), None
    else:
        master, rates = read_navigation(args.speed)
    gb, ab = _biases(args, noise)
    _resolved_biases(args, args.grade or "consumer", gb, ab)
    flex = args.flexure is not None
    cfg = FilterConfig(imu=noise, input=imu.kind, master_mount=args.matching == "velocity+attitude",
                       master_lever="lever" not in args.fix, master_time_offset="offset" not in args.fix,
                       flexure=flex, flexure_std_rad=args.flexure[0] * deg if flex else 1e-3,
                       flexure_tau_s=args.flexure[1] if flex else 1.0,
                       master_mount_rad=tuple(x * deg for x in args.mount), master_lever_arm_m=tuple(args.lever),
                       master_time_offset_s=args.time_offset, gate_probability=0.9999)
    tilt, heading = (x * deg for x in args.master_att_std)
    bt, bh = (x * deg for x in args.master_att_bias)
    errors = MasterErrors(velocity_std_m_s=args.master_vel_std, attitude_std_rad=(tilt, tilt, heading),
                          attitude_bias_std_rad=(bt, bt, bh))
    ms = args.mount_std * deg
    res = transfer_align(imu, master, config=cfg, master_rate_rad_s=rates, matching=args.matching,
                         position=args.master_position, master_errors=errors, progress=args.progress,
                         attitude_std_rad=1e-3, gyro_bias_std_rad_s=gb, accel_bias_std_m_s2=ab, mount_std_rad=ms,
                         lever_std_m=args.lever_std, time_offset_std_s=args.offset_std)
    if rates is None:
        print("note: the master record has no rate columns: its angular rate is taken from its attitude "
              "(central differences)")
    for line in res.report():
        print(line)
    if res.mount_derived:
        print("note: without attitude matching the mounting is the rotation between the slave's estimated "
              "attitude and the master's")
    truth = None
    if args.truth or args.truth_json:
        kw = _read_truth_json(args.truth_json) if args.truth_json else {}
        slave = io.TruthRecord.from_csv(args.truth) if args.truth else None
        truth = TransferTruth(slave=slave, **kw)
        units = {"mount_rad": ("arcmin", 1 / _ARCMIN), "lever_arm_m": ("m", 1.0), "time_offset_s": ("ms", 1e3),
                 "gyro_bias_rad_s": ("deg/h", 3600 / deg), "accel_bias_m_s2": ("mg", 1 / _MG),
                 "attitude": ("arcmin", 1 / _ARCMIN)}
        for name, e in res.errors(truth).items():
            unit, k = units[name]
            err = ", ".join(f"{x * k:.3g}" for x in np.atleast_1d(e["final_error"]))
            print(f"against the truth: {name} error at the end {err} {unit}; outside 3 sigma in "
                  f"{100 * e['outside_3sigma']:.2f}% of the (row, axis) pairs")
    if args.output:
        k = {"m": 1 / deg, "g": 3600 / deg, "a": 1 / _MG}
        cols = [res.t_s, *(res.mount_rad * k["m"]).T, *(res.mount_std_rad * k["m"]).T, *res.lever_arm_m.T,
                *res.lever_std_m.T, res.time_offset_s, res.time_offset_std_s, *(res.gyro_bias_rad_s * k["g"]).T,
                *(res.gyro_bias_std_rad_s * k["g"]).T, *(res.accel_bias_m_s2 * k["a"]).T,
                *(res.accel_bias_std_m_s2 * k["a"]).T, *(res.euler_rad * k["m"]).T, *(res.attitude_std_rad * k["m"]).T]
        outs.write_table(args.output, TRANSFER_COLUMNS, cols)
        print(f"{len(res.t_s)} rows -> {args.output}")
    if args.plot:
        res.plot(outs.file(args.plot), truth)
        print(f"figure -> {args.plot}")
    sig = res.mount_std_rad[-1]
    if not (sig[0] <= args.tolerance * _ARCMIN and sig[2] <= args.tolerance * _ARCMIN):
        print(f"gfins align: warning: the mounting's heading/roll 1-sigma ({sig[0] / _ARCMIN:.3g}, "
              f"{sig[2] / _ARCMIN:.3g} arcmin) is above --tolerance {args.tolerance:g} arcmin: not "
              "converged (a longer record, attitude matching or more manoeuvre; exit status 1)",
              file=sys.stderr)
        return 1
    return 0
