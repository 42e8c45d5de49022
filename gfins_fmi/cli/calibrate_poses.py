"""``gfins calibrate poses RECORD``: calibration of a hand-turned IMU at unknown static poses
(usage: ``gfins calibrate --help``; the method: :mod:`gfins_fmi.calibration.poses`,
docs/characterise_imu.md). Prints the poses found, the fits' residuals before and after,
every parameter with its 1-sigma; writes the IMU errors for ``gfins integrate
--imu-errors``, the residual tables, the report and the figure."""
from __future__ import annotations

import numpy as np

from gfins_fmi.calibration.poses import calibrate_poses
from gfins_fmi.calibration.poses_report import (UNITS, parameter_table, plot_pose_calibration, pose_rows,
                                                turn_rows)
from gfins_fmi.calibration.still import StillDetector
from gfins_fmi.cli.config_file import config_beside, recording
from gfins_fmi.cli.files import read_imu, run_writing
from gfins_fmi.cli.parser import build_parser
from gfins_fmi.estimation.noise_file import imu_errors_text
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.io.tables import TableReader
from gfins_fmi.nav.imu_errors import G0

__all__ = ["run"]


def _record(args) -> ImuRecord:
    if args.format == "csv" and args.counts:
        # raw counts: t, gyro x y z, accel x y z in LSB, one line per sample
        with TableReader(args.record, what="raw IMU counts (t_s, 3 gyro, 3 accel)") as r:
            if r.n_columns != 7:
                raise ValueError(f"{args.record}: {r.n_columns} columns; raw counts are t_s, gyro x y z, "
                                 "accel x y z (7 columns)")
            tab = np.concatenate([b for _, b in r])
        g_lsb, a_lsb = args.counts
        if not (g_lsb > 0 and a_lsb > 0):
            raise ValueError("--counts: both sensitivities must be > 0 (LSB per deg/s, LSB per g)")
        return ImuRecord(tab[:, 0], np.radians(tab[:, 1:4] / g_lsb), tab[:, 4:7] / a_lsb * G0, "rates",
                         f"{args.record.name}: counts / ({g_lsb:g} LSB/(deg/s), {a_lsb:g} LSB/g)")
    rec = read_imu(args.record, args.format)
    if args.counts:
        raise ValueError("--counts is for a CSV of raw counts (t_s and six count columns)")
    return rec


def _tables(args):
    return [(suffix, args.table.with_name(f"{args.table.name}.{suffix}.csv")) for suffix in ("poses", "turns")]


def run(args) -> int:
    tables = [path for _, path in _tables(args)] if args.table else []
    saved = config_beside(args, (args.output, args.report, *tables), args.plot, "calibrate")
    inputs = [args.record]
    return run_writing(recording(_run, build_parser()[1]["calibrate"], "calibrate", saved, inputs), args, inputs,
                       [args.report, args.output, *tables, saved], args.plot)


def _run(args, outs) -> int:
    imu = _record(args)
    det = StillDetector(initial_s=args.initial_still, window_s=args.still_window, accel_factor=args.still_accel,
                        gyro_factor=args.still_gyro, min_still_s=args.min_still)
    cal = calibrate_poses(imu, gravity_m_s2=args.gravity,
                          lat_rad=None if args.lat is None else np.radians(args.lat),
                          h_m=0.0 if args.height is None else args.height, detector=det,
                          accel_k2=args.k2, gyro_bias=args.gyro_bias)
    text = [f"# calibration at unknown poses of {args.record}", "",
            f"{len(imu)} samples, {imu.t_s[-1] - imu.t_s[0]:.1f} s; gravity {cal.g_m_s2:.6f} m/s^2", ""]
    text += [f"- {n}" for n in cal.notes]
    text += ["", "Parameters in the accelerometer-defined body frame (x along the x accelerometer, y in "
             "the x-y accelerometer plane):", "", parameter_table(cal), ""]
    out = "\n".join(text)
    print(out)
    if args.report:
        outs.write_text(args.report, out + "\n")
        print(f"report -> {args.report}")
    if args.output:
        std = {}
        for key, pref in (("accel_scale_ppm", "accel_scale"), ("accel_bias_ug", "accel_bias"),
                          ("gyro_scale_ppm", "gyro_scale"), ("gyro_bias_deg_h", "gyro_bias")):
            f = UNITS[pref][1]
            std[key] = [s * f for n, s in zip(cal.names, cal.std) if n.startswith(pref + "_")]
        header = (f"`gfins calibrate poses` of {args.record.name}: {len(cal.still)} poses; "
                  f"{cal.notes[-2]}\n{cal.notes[-1]}")
        outs.write_text(args.output, imu_errors_text(cal.errors, header, std))
        print(f"IMU errors -> {args.output} (gfins integrate --imu-errors {args.output})")
    if args.table:
        rows = {"poses": pose_rows(cal), "turns": turn_rows(cal)}
        for suffix, path in _tables(args):
            outs.write_table(path, *rows[suffix])
            print(f"{suffix} residuals -> {path}")
    if args.plot:
        figure = args.plot / "pose_calibration.png"
        plot_pose_calibration(cal, imu, outs.file(figure), title=args.record.name)
        print("figure:", figure)
    return 0
