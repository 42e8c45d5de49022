"""``gfins integrate``: integrated navigation of recorded files from the shell.

    gfins integrate IMU GNSS OUT.csv [--imu-format csv|kfgins|rtk_walk] [--gnss-format pos|kfgins|csv]
                    [--truth NAV] [--grade consumer|tactical|navigation | --noise-file NOISE.toml]
                    [--filter ekf|ukf] [--smooth]
                    [--outages DURATION:PERIOD:FIRST] [--plot DIR] ...

Writes the solution (time, position, velocity, attitude, 1-sigma, sensor estimates) to
OUT.csv, the innovation log to OUT.innovations.csv, what the run used (inputs, options,
filter settings, initial state) to OUT.config.json, and prints a summary; with --truth
the errors against it; with --outages the outage protocol's score. The files are one set
(gfins_fmi.io.output_set): they appear together when the run has succeeded; after a
refused sample the tables before it go to OUT.partial.csv and OUT.innovations.partial.csv.
Records that the run could not use (no epoch inside the IMU record) are refused before it.
"""
from __future__ import annotations

import dataclasses
import datetime
import json
import os
import pathlib
import sys

import numpy as np

from gfins_fmi import io
from gfins_fmi._version import __version__
from gfins_fmi.cli.files import cause, compensated, outputs, read_gnss, read_imu, read_optional, read_truth
from gfins_fmi.cli.initial import from_initial_option, record_start_s
from gfins_fmi.cli.noise import imu_noise
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.estimation.alignment import align_static_then_gnss
from gfins_fmi.estimation.config import (MEAS_TYPES, SENSOR_NAMES, UPDATE_STATUS, FilterConfig,
                                         FilterError, InitialState)
from gfins_fmi.estimation.evaluation import navigation_errors, outage_drift, outage_windows, plot_errors
from gfins_fmi.estimation.measurement_checks import unusable_measurements
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.io.columns import INNOVATION_COLUMNS, integrated_columns
from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.strapdown import quat_to_euler

__all__ = ["run"]


def _write(outs, path, sol, extra_note="", quiet=False):
    """The solution table: position, velocity and attitude in degrees, the 1-sigma (attitude
    in degrees), the sensor estimates."""
    to_deg = 180.0 / np.pi
    e = sol.euler_rad * to_deg
    table = np.column_stack([sol.t_s, sol.lat_rad * to_deg, sol.lon_rad * to_deg, sol.h_m, sol.v_n_m_s, e,
                             sol.std[:, 0:6], sol.std[:, 6:9] * to_deg, sol.sensors])
    outs.write_table(path, integrated_columns(SENSOR_NAMES), [table[:, j] for j in range(table.shape[1])])
    if not quiet:
        print(f"{len(sol)} samples{extra_note} -> {path}")


def _write_innovations(outs, path, sol):
    """The innovation log: one row per update, its kind and outcome by name; Python's
    notation for the numbers (the log's format since before TableWriter)."""
    inn = sol.innovations
    kinds = np.array([MEAS_TYPES[int(x)] for x in inn["type"]], dtype=str)
    status = np.array([UPDATE_STATUS[int(x)] for x in inn["status"]], dtype=str)
    cols = [inn["t_s"], kinds, status, inn["m"], inn["nis"], *inn["r"].T, *inn["s_std"].T]
    outs.write_table(path, INNOVATION_COLUMNS, cols,
                     [np.float64, str, str, np.int64, np.float64] + [np.float64] * 6, float_format="repr")


def _input(path) -> dict | None:
    if not path:
        return None
    st = os.stat(path)
    return {"path": str(path), "bytes": st.st_size,
            "modified_utc": datetime.datetime.fromtimestamp(st.st_mtime, datetime.timezone.utc).isoformat()}


def _effective_config(args, cfg, init, windows) -> str:
    """What the run used, to read back or rerun it: the inputs (path, size, time), every
    option, the filter's settings (FilterConfig, datasheet units), the initial state and
    its 1-sigma (as gf_ins_initial_std holds them), the simulated outages."""
    nav = init.nav
    doc = {
        "gfins_fmi": __version__, "command": "integrate",
        "inputs": {k: _input(getattr(args, k)) for k in ("imu", "gnss", "baro", "odometer", "truth")},
        "options": {k: (str(v) if isinstance(v, pathlib.Path) else v) for k, v in sorted(vars(args).items())
                    if k not in ("check", "module", "function")},
        "filter": dataclasses.asdict(cfg),
        "initial": {"t_s": float(nav.t_s), "lat_deg": float(np.degrees(nav.lat_rad)),
                    "lon_deg": float(np.degrees(nav.lon_rad)), "h_m": float(nav.h_m),
                    "v_enu_m_s": [float(x) for x in nav.v_n_m_s],
                    "heading_pitch_roll_deg": [float(x) for x in np.degrees(quat_to_euler(nav.q_bn))],
                    "std": init.std_blocks(cfg),
                    "sensors": None if init.sensors is None else [float(x) for x in init.sensors]},
        "outages_s": None if windows is None else [[float(a), float(b)] for a, b in windows],
    }
    return json.dumps(doc, indent=1, default=float) + "\n"


def _outage_windows(args, gnss, rec):
    """The simulated outages of --outages, refused when none falls inside the record."""
    dur, per, first = args.outages
    t0, t1 = float(gnss.t_s[0]), float(min(gnss.t_s[-1], rec.t_s[-1]))
    windows = outage_windows(t0, t1, dur, per, first)
    if len(windows) == 0:
        raise ValueError(f"--outages {dur:g},{per:g},{first:g}: no outage of {dur:g} s starting "
                         f"{first:g} s after the first GNSS epoch ends inside the aided span "
                         f"({t0:.10g} to {t1:.10g} s, {t1 - t0:.6g} s long): give a DURATION and a FIRST "
                         f"whose sum is below {t1 - t0:.6g} s")
    return windows


def run(args) -> int:
    inn_path = args.output.with_suffix(".innovations.csv")
    sm_path = args.output.with_suffix(".smoothed.csv")
    with outputs(args.imu, args.gnss, args.baro, args.odometer, args.truth) as outs:
        # every file of the run claimed before it: inputs, folders, links refused now
        outs.claim(args.output)
        outs.claim(inn_path)
        outs.claim(sm_path, produced=args.smooth)
        outs.claim(args.output.with_suffix(".config.json"))
        figures = {}
        if args.plot:
            outs.claim_folder(args.plot)
            for name in ("filter", "smoother"):
                figures[name] = outs.claim(args.plot / f"integrate_{name}.png",
                                           produced=name == "filter" or args.smooth)
        return _run(args, outs, inn_path, sm_path, figures)


def _run(args, outs, inn_path, sm_path, figures) -> int:
    imu = read_imu(args.imu, args.imu_format, args.gps_week)
    gnss = read_gnss(args.gnss, args.gnss_format, args.gps_week)
    baro = read_optional(io.BaroRecord, args.baro)
    odo = read_optional(io.OdometerRecord, args.odometer)
    truth = read_truth(args.truth, args.gps_week)
    # records the run could not use: refused before it (two time scales, most likely)
    problems = unusable_measurements(record_start_s(imu), float(imu.t_s[-1]), gnss=gnss, barometer=baro,
                                     odometer=odo, truth=truth)
    if problems:
        raise ValueError(f"{problems[0]}; nothing was run")
    if args.imu_errors:
        imu = compensated(imu, read_imu_errors(args.imu_errors))
        print(f"IMU record compensated with {args.imu_errors}")
    if args.subsamples > 1 and imu.kind == "rates":
        # the multi-sample coning/sculling corrections are formed from increments: the
        # trapezoid over each interval (what the filter's rate input assumes too)
        imu = imu.to_increments()
    cfg = FilterConfig(imu=imu_noise(args.grade, args.noise, args.noise_file), filter=args.filter, input=imu.kind,
                       propagation_interval_s=args.propagation_interval,
                       gnss_lever_arm_m=tuple(args.lever_arm), zupt=args.zupt, nhc=args.nhc,
                       odometer_mount=args.odometer_mount, subsamples=args.subsamples)
    if args.initial:
        nav0 = from_initial_option(args.initial, record_start_s(imu))
        init = InitialState(nav0, position_std_m=5.0, velocity_std_m_s=0.5,
                            attitude_std_rad=(2 * deg, 2 * deg, 10 * deg))
        rec = imu
    else:
        static = args.static or 5.0
        sp = align_static_then_gnss(imu, gnss, (imu.t_s[0], imu.t_s[0] + static),
                                    gyro_bias_std_rad_s=cfg.noise_si()["gyro_bias_std_rad_s"],
                                    accel_bias_std_m_s2=max(cfg.noise_si()["accel_bias_std_m_s2"], 1e-4))
        for note in sp.notes:
            print("alignment:", note)
        init = InitialState(sp.nav, position_std_m=(0.5, 0.5, 1.0), velocity_std_m_s=0.05,
                            attitude_std_rad=np.maximum(sp.attitude_std_rad, 1e-3), sensors=sp.sensors)
        sel = imu.t_s > sp.nav.t_s
        rec = io.ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind=imu.kind,
                           source=imu.source)
    windows = None
    g_used = gnss
    if args.outages:
        windows = _outage_windows(args, gnss, rec)
        g_used = gnss.with_outages([tuple(w) for w in windows])
        print(f"{len(windows)} simulated GNSS outages of {args.outages[0]:g} s")
    nav = IntegratedNavigator(cfg, init)
    outs.write_text(args.output.with_suffix(".config.json"), _effective_config(args, cfg, init, windows))
    try:
        # checked above, on the whole record ("warn": the alignment may have taken its start)
        sol = nav.run(rec, g_used, baro, odo, smoother=args.smooth, progress=args.progress, checks="warn")
    except FilterError as exc:
        sol = exc.partial
        _write(outs, args.output, sol, quiet=True)
        _write_innovations(outs, inn_path, sol)
        why = cause(exc)
        outs.keep_partial(f"the filter stopped at IMU sample {exc.index} of {args.imu}: {why}; the "
                          f"{len(sol)} rows here are the solution before it")
        print(f"error: {why}; the {len(sol)} samples before it are in "
              f"{', '.join(map(str, outs.partial))} ({outs.outcome().split('; ', 1)[1]})", file=sys.stderr)
        return 1
    _write(outs, args.output, sol)
    _write_innovations(outs, inn_path, sol)
    counts = {k: int(np.sum(sol.innovations["status"] == v)) for k, v in
              (("accepted", 0), ("gated", 1), ("singular", 2), ("stale", 3), ("forced", 4))}
    print(f"updates: {counts} -> {inn_path}")
    sm = None
    if args.smooth:
        sm = sol.smooth(progress=args.progress)
        _write(outs, sm_path, sm, " (smoothed)")
    ref = truth if truth is not None else gnss
    what = "truth" if truth is not None else "GNSS (all epochs)"
    for name, s in (("filter", sol), ("smoother", sm)):
        if s is None or len(s) == 0:
            continue
        e = navigation_errors(s, ref)
        print(f"{name}: horizontal difference to {what}: RMS {e.rms()['horizontal_m']:.3f} m")
        if windows is not None:
            d = outage_drift(s, ref, windows)
            print(f"{name}: outage protocol: RMS of the maximum drift per outage "
                  f"{np.sqrt(np.mean(d['max_m'] ** 2)):.3f} m (max {d['max_m'].max():.3f} m)")
        if args.plot:
            plot_errors(e, outs.file(figures[name]), std=s.std if truth is not None else None,
                        title=f"{name} vs {what}", windows=windows)
            print("figure:", figures[name])
    outs.commit()
    return 0
