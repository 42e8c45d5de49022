"""``gfins integrate``'s options and their parse-time checks (split from
:mod:`gfins_fmi.cli.parser` for its length; the same option types of
:mod:`gfins_fmi.cli.options`)."""
from __future__ import annotations

import argparse
import pathlib

from gfins_fmi.cli.options import GRADES, noise_values, real, vector

__all__ = ["integrate_parser", "check_integrate", "INITIAL_STD_DEFAULTS", "INITIAL_OPTION"]

#: ``--initial`` of integrate and align motion: LAT,LON,H,HEADING,PITCH,ROLL
INITIAL_OPTION = vector(6, "LAT,LON,H,HEADING,PITCH,ROLL in deg, deg, m, deg, deg, deg")
_INITIAL = INITIAL_OPTION


def check_integrate(args) -> str | None:
    """integrate's combinations of options (with --config: checked again once the file's
    values are in, by gfins_fmi.cli.integrate)."""
    if args.print_config or (args.config is not None and not getattr(args, "config_applied", False)):
        return None
    given = [x for x in (args.imu, args.gnss, args.output) if x is not None]
    if args.kfgins_config is not None:
        clash = [o for o, v in (("IMU GNSS OUT", given), ("--initial", args.initial), ("--static", args.static),
                                ("--noise", args.noise), ("--noise-file", args.noise_file),
                                ("--grade", args.grade != "tactical"), ("--imu-errors", args.imu_errors)) if v]
        if clash:
            return (f"--kfgins-config gives the files, the initial state and the noise: leave out "
                    f"{', '.join(clash)}")
    elif len(given) != 3:
        return "the following arguments are required: IMU GNSS OUT (or --kfgins-config KF-GINS.yaml)"
    if args.outages is not None:
        dur, per, first = args.outages
        if not (dur > 0 and per >= dur and first >= 0):
            return (f"--outages {dur:g},{per:g},{first:g}: DURATION must be > 0 s, PERIOD >= "
                    "DURATION and FIRST >= 0 s")
    if args.noise and args.noise_file:
        return "give the IMU noise once: --noise or --noise-file"
    if args.initial == "truth" and args.truth is None:
        return "--initial truth takes the initial state from the --truth file: give --truth"
    started = [o for o, v in (("--initial-velocity", args.initial_velocity), ("--position-std", args.position_std),
                              ("--velocity-std", args.velocity_std), ("--attitude-std", args.attitude_std))
               if v is not None]
    if started and args.initial is None:
        return (f"{', '.join(started)} describe the initial state of --initial; without --initial the "
                "static alignment (--static) gives the state and its 1-sigma")
    if args.initial == "truth" and args.initial_velocity is not None:
        return "--initial truth takes the velocity from the truth too: leave out --initial-velocity"
    return None


#: integrate's initial 1-sigma when --initial gives the state (FilterConfig's InitialState
#: blocks: position E,N,U m; velocity E,N,U m/s; attitude tilt E, tilt N, heading deg)
INITIAL_STD_DEFAULTS = {"position_std": (5.0, 5.0, 5.0), "velocity_std": (0.5, 0.5, 0.5),
                        "attitude_std": (2.0, 2.0, 10.0)}


def _initial_or_truth(text: str):
    """``--initial LAT,LON,H,HEADING,PITCH,ROLL`` or ``--initial truth``."""
    return "truth" if text.strip().lower() == "truth" else _INITIAL(text)


def _nonneg3(what: str):
    parse = vector(3, what)

    def check(text: str):
        v = parse(text)
        if not all(x > 0 for x in v):
            raise argparse.ArgumentTypeError(f"each of {what} must be > 0; got {text!r}")
        return v
    return check


def integrate_parser(sub, imu_errors_argument, command) -> argparse.ArgumentParser:
    """The ``integrate`` subcommand's parser (``imu_errors_argument``, ``command``: the
    parser module's helpers)."""
    p = sub.add_parser("integrate", help="integrated navigation (INS/GNSS EKF or UKF, optional RTS "
                       "smoother) of recorded IMU and GNSS files",
                       description="Integrated navigation of recorded files (docs/estimation.md).")
    p.add_argument("imu", type=pathlib.Path, nargs="?", default=None, help="IMU file")
    p.add_argument("gnss", type=pathlib.Path, nargs="?", default=None, help="GNSS file")
    p.add_argument("output", type=pathlib.Path, nargs="?", default=None, help="solution CSV to write")
    p.add_argument("--config", type=pathlib.Path, default=None, metavar="FILE.toml",
                   help="the run's settings from a file (TOML, YAML, or a run's OUT.config.json to repeat "
                        "it): options by name, a [filter] table of the settings table, the noise block "
                        "([imu]); options given here override it (docs/own_data.md)")
    p.add_argument("--print-config", action="store_true",
                   help="print a commented template of the configuration file and exit")
    p.add_argument("--kfgins-config", type=pathlib.Path, default=None, metavar="KF-GINS.yaml",
                   help="run a KF-GINS configuration file as it is (its IMU and GNSS paths, time span, initial "
                        "state and stds, IMU noise, bias and scale parameters, antenna lever arm) and write "
                        "KF-GINS's output files (KF_GINS_Navresult.nav, KF_GINS_IMU_ERR.txt, KF_GINS_STD.txt) "
                        "in its outputpath; no IMU GNSS OUT then")
    p.add_argument("--imu-format", choices=("csv", "kfgins", "rtk_walk"), default="csv",
                   help="csv: gfins_fmi.io ImuRecord CSV, or Parquet (.parquet, .pq) / npz (.npz) of its "
                        "columns (t_s s, gyro rad or rad/s, accel m/s or m/s^2, body right-front-up); kfgins: "
                        "KF-GINS IMU text/.bin (increments, front-right-down); rtk_walk: the rtk_walk CSV "
                        "(rates in g and rad/s). Every format is read in chunks (but with --plot)")
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
    p.add_argument("--grade", choices=GRADES, default="tactical",
                   help="IMU noise model (gfins_fmi.sim.scenarios); overridden by --noise")
    p.add_argument("--noise", type=noise_values,
                   default=None, metavar="ARW,VRW,GB,AB,TAU",
                   help="IMU noise, each value with an optional unit: ARW (deg/sqrt(h); or deg/h/sqrt(Hz)), "
                        "VRW (a bare number is the ONE-sided density in ug/sqrt(Hz), = sqrt(2) x the "
                        "Allan VRW; write the datasheet's as e.g. 0.03m/s/sqrt(h), = 72.1 ug/sqrt(Hz)), "
                        "GB gyro bias instability (deg/h), AB accelerometer bias instability (ug; or "
                        "mg, mGal, m/s^2), TAU their correlation time (s; or h). Example: "
                        "--noise 0.003,0.03m/s/sqrt(h),0.027,15mGal,1h")
    p.add_argument("--noise-file", type=pathlib.Path, default=None, metavar="FILE.toml",
                   help="IMU noise from a noise block (TOML; `gfins noise RECORD --output FILE.toml` "
                        "writes one; units in its keys); overrides --grade, excludes --noise")
    imu_errors_argument(p)
    p.add_argument("--filter", choices=("ekf", "ukf"), default="ekf")
    p.add_argument("--smooth", action="store_true", help="also run the RTS smoother (its solution is "
                   "written beside OUT in its format: OUT.smoothed.csv, .parquet, .npz; with --kfgins-config "
                   "KF_GINS_Navresult.smoothed.nav); in the runs in chunks (every run but --plot's) its epochs "
                   "and the rows go to a temporary folder beside OUT, removed "
                   "at the end: per hour of record at 200 Hz and the default --propagation-interval 0.1 s, "
                   "0.31 GB with 15 states, 0.44 GB with 21 (--kfgins-config), +10%% with 1 Hz GNSS fixes "
                   "between the propagation instants (4.1 or 7.7 kB per epoch, 224 B per row); memory flat")
    p.add_argument("--propagation-interval", type=real("s", at_least=0.0), default=0.1,
                   help="covariance propagation interval, s (0: every IMU sample)")
    p.add_argument("--subsamples", type=int, choices=(1, 2, 3, 4), default=1,
                   help="IMU increments per navigation update between measurement and propagation "
                        "instants (multi-sample coning/sculling; one output row per update; a rate "
                        "record is turned into increments by the trapezoid); 2 makes the filter ~1.5x "
                        "faster on a 200 Hz IMU")
    p.add_argument("--static", type=real("s", above=0.0), default=None, metavar="SECONDS",
                   help="the record starts at rest for SECONDS: level (and gyrocompass if the gyros "
                        "allow; otherwise heading from GNSS velocity); default when no --initial")
    p.add_argument("--initial", type=_initial_or_truth, default=None, metavar="LAT,LON,H,HEADING,PITCH,ROLL|truth",
                   help="initial state at the record's start (deg, deg, m, deg, deg, deg; at rest unless "
                        "--initial-velocity), or 'truth': the --truth file's state at that time")
    p.add_argument("--initial-velocity", type=vector(3, "E,N,U in m/s"), default=None, metavar="E,N,U",
                   help="with --initial: the initial velocity east, north, up, m/s (a record that starts "
                        "moving; default 0,0,0)")
    p.add_argument("--position-std", type=_nonneg3("E,N,U in m"), default=None, metavar="E,N,U",
                   help="with --initial: initial position 1-sigma east, north, up, m (default 5,5,5)")
    p.add_argument("--velocity-std", type=_nonneg3("E,N,U in m/s"), default=None, metavar="E,N,U",
                   help="with --initial: initial velocity 1-sigma east, north, up, m/s (default 0.5,0.5,0.5)")
    p.add_argument("--attitude-std", type=_nonneg3("TILT_E,TILT_N,HEADING in deg"), default=None,
                   metavar="TILT_E,TILT_N,HEADING",
                   help="with --initial: initial attitude 1-sigma, deg: the tilts about east and north "
                        "(roll/pitch for a level vehicle heading north) and the heading (default 2,2,10)")
    p.add_argument("--gyro-bias-std", type=_nonneg3("X,Y,Z in deg/h"), default=None, metavar="X,Y,Z",
                   help="initial gyro bias 1-sigma, deg/h (default: the noise model's bias instability)")
    p.add_argument("--accel-bias-std", type=_nonneg3("X,Y,Z in mGal"), default=None, metavar="X,Y,Z",
                   help="initial accelerometer bias 1-sigma, mGal (1e-5 m/s^2; default: the noise "
                        "model's bias instability)")
    p.add_argument("--lever-arm", type=vector(3, "X,Y,Z in m"), default=(0.0, 0.0, 0.0),
                   metavar="X,Y,Z", help="IMU -> GNSS antenna, body right, front, up, m (negative values as "
                   "typed: --lever-arm -0.3,0.1,1.2)")
    p.add_argument("--outages", type=vector(3, "DURATION,PERIOD,FIRST in s"), default=None,
                   metavar="DURATION,PERIOD,FIRST",
                   help="simulate GNSS outages of DURATION s every PERIOD s from FIRST s after the "
                        "first epoch, KF-GINS's and pyins's protocol: the fixes with t0 < t < t0 + "
                        "DURATION removed, every outage that starts inside the record scored by the "
                        "maximum horizontal error inside it (against --truth; without it, against the "
                        "removed fixes at the antenna)")
    p.add_argument("--zupt", action="store_true", help="zero-velocity updates at detected standstill")
    p.add_argument("--nhc", action="store_true", help="non-holonomic constraints (ground vehicles)")
    p.add_argument("--plot", type=pathlib.Path, default=None,
                   help="folder for figures; it reads the whole IMU record at once (memory grows with the "
                        "record's length; without --plot the run goes in chunks)")
    p.add_argument("--all-states", action="store_true",
                   help="write every sensor state's column (default: the biases and the states the "
                        "configuration enables; a disabled state's column is all zeros)")
    p.add_argument("--progress", action="store_true", help="progress bar over reading, filtering, "
                   "smoothing and writing")
    command(p, "integrate", check=check_integrate)
    return p


