"""``gfins align``: initial alignment of recorded IMU files from the shell (issue 13).

    gfins align static IMU --position LAT,LON,H [--window T0,T1] [--grade G] [--disturbed]
                       [--heading DEG [--heading-std DEG]] [--fine [--fine-end T1]]
    gfins align motion IMU SPEED --initial LAT,LON,H,HEADING,PITCH,ROLL [--depth DEPTH]
                       [--passes N] [--grade G] [--heading-std DEG] [--output PASSES.csv]

static: levelling and gyrocompassing over the window at rest (motion in it is refused;
a swaying base is warned of, with the --disturbed hint), or with --disturbed the
inertial-frame coarse alignment; --heading gives the heading when gyrocompassing cannot
(or replaces it); then with --fine the zero-velocity fine alignment from the window's end
to --fine-end (default: the record's end; after --disturbed with a 0.1 m/s velocity std:
the base sways). motion: the
seed-003 in-motion alignment with a speed sensor (OdometerRecord CSV: t_s, speed_m_s,
std_m_s) and optionally depth (BaroRecord CSV, h_m = -depth), forward-backward passes
over the stored record; prints the attitude after each pass and writes the pass table.
Exit status 0 when aligned, 1 when the alignment reports that it has not converged (the
pass table is written all the same), 2 on bad input.
"""
from __future__ import annotations

import dataclasses
import math
import sys
import warnings

import numpy as np

from gfins_fmi import io
from gfins_fmi.cli.files import compensated, outputs
from gfins_fmi.cli.initial import from_initial_option, record_start_s
from gfins_fmi.cli.noise import imu_noise
from gfins_fmi.estimation.alignment import coarse_align, coarse_align_inertial
from gfins_fmi.estimation.config import UG, FilterConfig, InitialState
from gfins_fmi.estimation.fine_alignment import align_in_motion, fine_align
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.io.columns import ALIGNMENT_PASS_COLUMNS

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
    with outputs(args.imu, args.speed, args.depth) as outs:
        if args.output:
            outs.claim(args.output)
        status = _run(args, outs)
        outs.commit()
        return status


def _run(args, outs) -> int:
    deg = math.pi / 180.0
    noise = imu_noise(args.grade)
    imu = io.ImuRecord.from_csv(args.imu)
    if args.imu_errors:
        imu = compensated(imu, read_imu_errors(args.imu_errors))
    gb, ab = _biases(args, noise)
    if args.mode == "static":
        lat, lon, h = args.position
        span = 300.0 if args.disturbed else 60.0
        t0, t1 = args.window if args.window else (imu.t_s[0] - 1e-9, imu.t_s[0] + span)
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
