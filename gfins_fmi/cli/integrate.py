"""``gfins integrate``: integrated navigation of recorded files from the shell.

    gfins integrate IMU GNSS OUT.csv [--imu-format csv|kfgins|rtk_walk] [--gnss-format pos|kfgins|csv]
                    [--truth NAV] [--grade consumer|tactical|navigation] [--filter ekf|ukf] [--smooth]
                    [--outages DURATION:PERIOD:FIRST] [--plot DIR] ...

Writes the solution (time, position, velocity, attitude, 1-sigma, sensor estimates) to
OUT.csv, the innovation log to OUT.innovations.csv, and prints a summary; with --truth
the errors against it; with --outages the outage protocol's score.
"""
from __future__ import annotations

import argparse
import math
import pathlib
import sys

__all__ = ["add_parser", "run"]

_GRADES = ("consumer", "tactical", "navigation")


def _floats(text: str, n: int, what: str):
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{what}: expected {n} comma-separated numbers, got {text!r}")
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"{what}: expected {n} finite comma-separated numbers, got {text!r}")
    return vals


# argparse types of the estimation CLIs (integrate, calibrate, align), in one place

def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}")
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v


def _positive(text: str) -> float:
    v = _finite(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return v


def _nonneg(text: str) -> float:
    v = _finite(text)
    if not v >= 0:
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return v


def _count(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}")
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return v


def add_parser(sub) -> None:
    p = sub.add_parser("integrate", help="integrated navigation (INS/GNSS EKF or UKF, optional RTS "
                       "smoother) of recorded IMU and GNSS files",
                       description="Integrated navigation of recorded files (docs/estimation.md).")
    p.add_argument("imu", type=pathlib.Path, help="IMU file")
    p.add_argument("gnss", type=pathlib.Path, help="GNSS file")
    p.add_argument("output", type=pathlib.Path, help="solution CSV to write")
    p.add_argument("--imu-format", choices=("csv", "kfgins", "rtk_walk"), default="csv",
                   help="csv: gfins_fmi.io ImuRecord CSV; kfgins: KF-GINS IMU text/.bin (increments, "
                        "front-right-down); rtk_walk: the rtk_walk CSV (rates in g and rad/s)")
    p.add_argument("--gnss-format", choices=("pos", "kfgins", "csv"), default="pos",
                   help="pos: RTKLIB .pos; kfgins: KF-GINS GNSS text; csv: GnssRecord CSV")
    p.add_argument("--gps-week", type=int, default=None,
                   help="KF-GINS files: GPS week, to put seconds-of-week on the RTKLIB time scale")
    p.add_argument("--baro", type=pathlib.Path, help="BaroRecord CSV (barometric height)")
    p.add_argument("--odometer", type=pathlib.Path, help="OdometerRecord CSV (forward speed)")
    p.add_argument("--odometer-mount", action="store_true",
                   help="estimate the odometer's boresight (pitch, heading of the vehicle axes in "
                        "the IMU's; FilterConfig.odometer_mount): with --odometer and/or --nhc")
    p.add_argument("--truth", type=pathlib.Path, help="reference: KF-GINS .nav or TruthRecord CSV")
    p.add_argument("--grade", choices=_GRADES, default="tactical",
                   help="IMU noise model (gfins_fmi.estimation.scenarios); overridden by --noise")
    p.add_argument("--noise", type=lambda s: _floats(s, 5, "--noise"), default=None,
                   metavar="ARW,VRW,GB,AB,TAU",
                   help="IMU noise: ARW deg/sqrt(h), accelerometer noise ug/sqrt(Hz), gyro bias "
                        "instability deg/h, accelerometer bias instability ug, correlation time s")
    p.add_argument("--filter", choices=("ekf", "ukf"), default="ekf")
    p.add_argument("--smooth", action="store_true", help="also run the RTS smoother (its solution is "
                   "written to OUT.smoothed.csv)")
    p.add_argument("--propagation-interval", type=_nonneg, default=0.1,
                   help="covariance propagation interval, s (0: every IMU sample)")
    p.add_argument("--subsamples", type=int, choices=(1, 2, 3, 4), default=1,
                   help="IMU increments per navigation update between measurement and propagation "
                        "instants (multi-sample coning/sculling; one output row per update; a rate "
                        "record is turned into increments by the trapezoid); 2 makes the filter ~1.5x "
                        "faster on a 200 Hz IMU")
    p.add_argument("--static", type=_positive, default=None, metavar="SECONDS",
                   help="the record starts at rest for SECONDS: level (and gyrocompass if the gyros "
                        "allow; otherwise heading from GNSS velocity); default when no --initial")
    p.add_argument("--initial", type=lambda s: _floats(s, 6, "--initial"), default=None,
                   metavar="LAT,LON,H,HEADING,PITCH,ROLL",
                   help="initial state (deg, deg, m, deg, deg, deg) at the first IMU time, at rest")
    p.add_argument("--lever-arm", type=lambda s: _floats(s, 3, "--lever-arm"), default=(0.0, 0.0, 0.0),
                   metavar="X,Y,Z", help="IMU -> GNSS antenna, body right, front, up, m")
    p.add_argument("--outages", type=lambda s: _floats(s, 3, "--outages"), default=None,
                   metavar="DURATION,PERIOD,FIRST",
                   help="simulate GNSS outages of DURATION s every PERIOD s from FIRST s after the "
                        "first epoch, and score the drift (needs --truth or scores against GNSS)")
    p.add_argument("--zupt", action="store_true", help="zero-velocity updates at detected standstill")
    p.add_argument("--nhc", action="store_true", help="non-holonomic constraints (ground vehicles)")
    p.add_argument("--plot", type=pathlib.Path, default=None, help="folder for figures")
    p.add_argument("--progress", action="store_true", help="progress bar")
    p.set_defaults(func=run)
    return p


def _read(args):
    from gfins_fmi import io
    if args.imu_format == "csv":
        imu = io.ImuRecord.from_csv(args.imu)
    elif args.imu_format == "kfgins":
        imu = io.read_kfgins_imu(args.imu, gps_week=args.gps_week)
    else:
        imu = io.read_rtk_walk_imu(args.imu, io.rtk_walk_mounting())
    if args.gnss_format == "pos":
        gnss = io.read_rtklib_pos(args.gnss)
    elif args.gnss_format == "kfgins":
        gnss = io.read_kfgins_gnss(args.gnss, gps_week=args.gps_week)
    else:
        gnss = io.GnssRecord.from_csv(args.gnss)
    baro = io.BaroRecord.from_csv(args.baro) if args.baro else None
    odo = io.OdometerRecord.from_csv(args.odometer) if args.odometer else None
    truth = None
    if args.truth:
        truth = (io.read_kfgins_nav(args.truth, gps_week=args.gps_week) if args.truth.suffix == ".nav"
                 else io.TruthRecord.from_csv(args.truth))
    return imu, gnss, baro, odo, truth


def _noise(args):
    from gfins_fmi.estimation import scenarios
    from gfins_fmi.imu_errors import ImuNoise
    if args.noise:
        arw, vrw, gb, ab, tau = args.noise
        return ImuNoise(gyro_arw_deg_sqrt_h=arw, accel_vrw_ug_sqrt_hz=vrw, gyro_bias_instability_deg_h=gb,
                        accel_bias_instability_ug=ab, gyro_correlation_time_s=tau,
                        accel_correlation_time_s=tau)
    return {"consumer": scenarios.CONSUMER, "tactical": scenarios.TACTICAL,
            "navigation": scenarios.NAVIGATION}[args.grade]


def _write(path, sol, extra_note=""):
    import numpy as np
    from gfins_fmi.estimation import SENSOR_NAMES
    from gfins_fmi.io.tables import TableWriter
    deg = 180.0 / np.pi
    e = sol.euler_rad * deg
    table = np.column_stack([sol.t_s, sol.lat_rad * deg, sol.lon_rad * deg, sol.h_m, sol.v_n_m_s, e,
                             sol.std[:, 0:6], sol.std[:, 6:9] * deg, sol.sensors])
    names = ("t_s,lat_deg,lon_deg,h_m,v_e_m_s,v_n_m_s,v_u_m_s,heading_deg,pitch_deg,roll_deg,"
             "std_v_e_m_s,std_v_n_m_s,std_v_u_m_s,std_e_m,std_n_m,std_u_m,std_att_e_deg,std_att_n_deg,"
             "std_att_u_deg").split(",") + list(SENSOR_NAMES)
    # written beside its name and renamed when complete: nothing half-written is left
    with TableWriter(path, names) as w:
        w.write([table[:, j] for j in range(table.shape[1])])
        w.commit()
    print(f"{len(sol)} samples{extra_note} -> {path}")


def _write_innovations(path, sol):
    import numpy as np
    from gfins_fmi.estimation import MEAS_TYPES, UPDATE_STATUS
    inn = sol.innovations
    tmp = pathlib.Path(str(path) + ".part")
    with open(tmp, "w") as fh:
        fh.write("t_s,kind,status,m,nis,r0,r1,r2,s0,s1,s2\n")
        for row in inn:
            fh.write(f"{float(row['t_s'])!r},{MEAS_TYPES[int(row['type'])]},"
                     f"{UPDATE_STATUS[int(row['status'])]},{int(row['m'])},{float(row['nis'])!r}," +
                     ",".join(repr(float(x)) for x in row['r']) + "," +
                     ",".join(repr(float(x)) for x in row['s_std']) + "\n")
    tmp.replace(path)
    del np


def run(args) -> int:
    import numpy as np
    from gfins_fmi.estimation import FilterConfig, FilterError, InitialState, IntegratedNavigator
    from gfins_fmi.estimation.alignment import align_static_then_gnss
    from gfins_fmi.estimation.evaluation import (navigation_errors, outage_drift, outage_windows,
                                                 plot_errors)
    from gfins_fmi.io import ImuRecord
    from gfins_fmi.sins import NavState, euler_to_quat
    imu, gnss, baro, odo, truth = _read(args)
    if args.subsamples > 1 and imu.kind == "rates":
        # the multi-sample coning/sculling corrections are formed from increments: the
        # trapezoid over each interval (what the filter's rate input assumes too)
        imu = imu.to_increments()
    cfg = FilterConfig(imu=_noise(args), filter=args.filter, input=imu.kind,
                       propagation_interval_s=args.propagation_interval,
                       gnss_lever_arm_m=tuple(args.lever_arm), zupt=args.zupt, nhc=args.nhc,
                       odometer_mount=args.odometer_mount, subsamples=args.subsamples)
    deg = math.pi / 180.0
    if args.initial:
        lat, lon, h, hd, pt, rl = args.initial
        t0 = imu.t_s[0] if imu.kind == "rates" else imu.t_s[0] - float(np.median(np.diff(imu.t_s[:100])))
        nav0 = NavState(euler_to_quat(np.array([hd, pt, rl]) * deg), np.zeros(3), lat * deg, lon * deg, h, t0)
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
        rec = ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind=imu.kind,
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
