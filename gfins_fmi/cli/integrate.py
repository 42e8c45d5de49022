"""``gfins integrate``: integrated navigation of recorded files from the shell.

    gfins integrate IMU GNSS OUT.csv [--imu-format csv|kfgins|rtk_walk] [--gnss-format pos|kfgins|csv]
                    [--truth NAV] [--grade consumer|tactical|navigation | --noise-file NOISE.toml]
                    [--filter ekf|ukf] [--smooth]
                    [--outages DURATION:PERIOD:FIRST] [--plot DIR] ...

Writes the solution (time, position, velocity, attitude, 1-sigma, sensor estimates) to
OUT.csv, the innovation log to OUT.innovations.csv, and prints a summary; with --truth
the errors against it; with --outages the outage protocol's score.
"""
from __future__ import annotations

import sys

import numpy as np

from gfins_fmi import io
from gfins_fmi.cli.files import compensated, read_gnss, read_imu, read_optional, read_truth, write_table
from gfins_fmi.cli.initial import from_initial_option, record_start_s
from gfins_fmi.cli.noise import imu_noise
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.estimation.alignment import align_static_then_gnss
from gfins_fmi.estimation.config import (MEAS_TYPES, SENSOR_NAMES, UPDATE_STATUS, FilterConfig,
                                         FilterError, InitialState)
from gfins_fmi.estimation.evaluation import navigation_errors, outage_drift, outage_windows, plot_errors
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.io.columns import INNOVATION_COLUMNS, integrated_columns
from gfins_fmi.nav.earth import deg

__all__ = ["run"]


def _write(path, sol, extra_note=""):
    """The solution table: position, velocity and attitude in degrees, the 1-sigma (attitude
    in degrees), the sensor estimates."""
    to_deg = 180.0 / np.pi
    e = sol.euler_rad * to_deg
    table = np.column_stack([sol.t_s, sol.lat_rad * to_deg, sol.lon_rad * to_deg, sol.h_m, sol.v_n_m_s, e,
                             sol.std[:, 0:6], sol.std[:, 6:9] * to_deg, sol.sensors])
    write_table(path, integrated_columns(SENSOR_NAMES), [table[:, j] for j in range(table.shape[1])])
    print(f"{len(sol)} samples{extra_note} -> {path}")


def _write_innovations(path, sol):
    """The innovation log: one row per update, its kind and outcome by name; Python's
    notation for the numbers (the log's format since before TableWriter)."""
    inn = sol.innovations
    kinds = np.array([MEAS_TYPES[int(x)] for x in inn["type"]], dtype=str)
    status = np.array([UPDATE_STATUS[int(x)] for x in inn["status"]], dtype=str)
    cols = [inn["t_s"], kinds, status, inn["m"], inn["nis"], *inn["r"].T, *inn["s_std"].T]
    write_table(path, INNOVATION_COLUMNS, cols,
                [np.float64, str, str, np.int64, np.float64] + [np.float64] * 6, float_format="repr")


def run(args) -> int:
    imu = read_imu(args.imu, args.imu_format, args.gps_week)
    gnss = read_gnss(args.gnss, args.gnss_format, args.gps_week)
    baro = read_optional(io.BaroRecord, args.baro)
    odo = read_optional(io.OdometerRecord, args.odometer)
    truth = read_truth(args.truth, args.gps_week)
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
        dur, per, first = args.outages
        windows = outage_windows(gnss.t_s[0], min(gnss.t_s[-1], rec.t_s[-1]), dur, per, first)
        g_used = gnss.with_outages([tuple(w) for w in windows])
        print(f"{len(windows)} simulated GNSS outages of {dur:g} s")
    nav = IntegratedNavigator(cfg, init)
    status = 0
    try:
        sol = nav.run(rec, g_used, baro, odo, smoother=args.smooth, progress=args.progress)
    except FilterError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sol, status = exc.partial, 1
    _write(args.output, sol)
    inn_path = args.output.with_suffix(".innovations.csv")
    _write_innovations(inn_path, sol)
    counts = {k: int(np.sum(sol.innovations["status"] == v)) for k, v in
              (("accepted", 0), ("gated", 1), ("singular", 2), ("stale", 3), ("forced", 4))}
    print(f"updates: {counts} -> {inn_path}")
    sm = None
    if args.smooth and status == 0:
        sm = sol.smooth(progress=args.progress)
        _write(args.output.with_suffix(".smoothed.csv"), sm, " (smoothed)")
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
            args.plot.mkdir(parents=True, exist_ok=True)
            p = plot_errors(e, args.plot / f"integrate_{name}.png", std=s.std if truth is not None else None,
                            title=f"{name} vs {what}", windows=windows)
            print("figure:", p)
    return status
