"""The ``gfins`` command line: every subcommand's options in one place, with the option
types of :mod:`gfins_fmi.cli.options` (units and bounds), and the checks of option
combinations made at parse time. A subcommand names the module that runs it
(``gfins_fmi.cli.<module>``, its ``run`` or the function given): :func:`gfins_fmi.cli.main`
imports only that one, so ``gfins --help`` and a command's refusal of its options stay as
fast as before the package had one module per command (the parser imports nothing heavy).
"""
from __future__ import annotations

import argparse
import pathlib

from gfins_fmi.cli.integrate_options import INITIAL_OPTION, integrate_parser
from gfins_fmi.cli.options import GRADES, count, prior_setting, real, vector
from gfins_fmi.cli.transfer_options import transfer_arguments
from gfins_fmi.gyrofree.array import MIN_LEVER_ARM_M
from gfins_fmi.nav.earth import WGS84

__all__ = ["build_parser", "executor_arguments", "record_arguments", "state_arguments", "imu_errors_argument",
           "config_arguments", "check_align", "check_calibrate", "ANALYZE_CONFIGS"]

#: ``gfins analyze --config``: the scenarios of gfins_fmi.analysis.error_report.CONFIGS (named
#: here so that the parser does not import the analysis; a test checks that they agree)
ANALYZE_CONFIGS = ("sins", "cube6", "qin9", "12", "qin9-sqrt", "12-sqrt", "qin9-fused", "12-fused")

#: ``gfins calibrate --help``
CALIBRATE_DESCRIPTION = """``gfins calibrate``: system-level calibration of a recorded multi-position run,
or (``gfins calibrate poses RECORD``) calibration at unknown static poses of a hand-turned IMU.

    gfins calibrate poses RECORD [--lat DEG --height M | --gravity M_S2] [--format csv|kfgins|rtk_walk]
                    [--counts GYRO_LSB_PER_DPS,ACCEL_LSB_PER_G] [--initial-still S] [--still-window S]
                    [--still-accel F] [--still-gyro F] [--min-still S] [--k2] [--gyro-bias still|fit]
                    [--output CAL.toml] [--table PREFIX] [--report REPORT.md] [--plot DIR]

RECORD starts at rest (--initial-still s), then the IMU is turned by hand to >= 20 orientations
and held still at each for a few seconds (docs/characterise_imu.md). Prints the poses found and
every parameter with its 1-sigma; --output writes [imu_errors] for `gfins integrate --imu-errors`.

    gfins calibrate IMU --lat DEG --height M [--lon DEG] [--gravity M_S2]
                    [--format csv|kfgins|bin64|bin32|text7 [--raw-kind increments|rates]
                     [--gyro-unit U] [--accel-unit U] [--time-scale S]]
                    [--grade auto|navigation|tactical|mems] [--model full|seed] [--delay|--no-delay]
                    [--arw DEG_SQRT_H] [--vrw UG_SQRT_HZ] [--vel-std M_S] [--passes N]
                    [--prior NAME=VALUE ...] [--prior-mean CLBT] [--widen-priors [--max-rounds N]]
                    [--heading DEG] [--report REPORT.md] [--json PARAMS.json]
                    [--compensation CLBT.json|.toml|.bin|.txt] [--plot DIR] [--progress]
                    [--simulate seed001|turntable19 [--sim-errors seed|lab] [--sim-seed N]]

The full lever-arm model (the x and y accelerometers' positions relative to the z
accelerometer, and the accelerometer delay: 40 states) with the defaults of the IMU's
grade (read from the first static interval unless --grade names it); --model seed runs
seed 001's 36 states. Prints the static intervals and turns found, every parameter with
its 1-sigma, its prior and its shift against the prior, the checks (NIS, prior blocks,
model terms the chosen model lacks) with warnings that name the parameters and the fix,
and the result in the compensation form (PSINS clbt fields); --json writes both
conventions and the SINS/vehicle FMU start values, --compensation the compensation form
alone (JSON, TOML, PSINS's 37-value .bin or text). --prior-mean centres the prior on a
compensation form (a previous calibration, another tool's). --simulate first writes a
simulated raw record of that path to IMU (its true errors beside it, IMU.truth.json).

    gfins calibrate [poses] [IMU|RECORD] --config run.toml [--save-config FILE.json] [options]
    gfins calibrate --print-config

--config takes every option from a TOML or YAML file (the record too; options typed here
override it), --print-config prints its commented template with units and defaults. A run
writes its effective configuration (every option with its value and unit, the grade and
filter settings it chose, the input) beside the first of --report, --json,
--compensation (poses: --output, --report), as R.config.json (with --plot DIR only:
DIR/calibrate.config.json), or at --save-config; --config R.config.json repeats the run.
"""


def _command(p, module: str, function: str = "run", check=None) -> None:
    """The subcommand of parser ``p`` runs ``gfins_fmi.cli.<module>.<function>(args)``."""
    p.set_defaults(module=module, function=function, check=check)


def _check_demo(args) -> str | None:
    n = int(round(args.duration / args.dt))
    if n < 2:
        return (f"--duration {args.duration:g} s at --dt {args.dt:g} s gives {n} sample"
                f"{'' if n == 1 else 's'}; the demo needs at least 2")
    return None


def _check_cosim(args) -> str | None:
    if args.seconds < args.step:
        return f"--seconds {args.seconds:g} s is shorter than one --step ({args.step:g} s)"
    # the FMUs refuse a step past their stop time (to 1e-9 relative, the glue's tolerance on
    # communication points): before, a step that does not divide the run failed at its
    # last step, deep inside the run
    n = args.seconds / args.step
    k = round(n)
    if abs(k * args.step - args.seconds) > 1e-9 * max(1.0, args.seconds):
        lo, hi = int(n), int(n) + 1
        return (f"--seconds {args.seconds:.10g} s is not a whole number of --step {args.step:.10g} s "
                f"({n:.6g} steps): give a step that divides it, or --seconds {lo * args.step:.10g} or "
                f"{hi * args.step:.10g} ({lo} or {hi} steps)")
    return None


def check_align(args) -> str | None:
    """``gfins align``'s combinations of options (with --config: checked once the file is read)."""
    if _deferred(args):
        return None
    if args.mode is None or args.imu is None:
        return ("the following arguments are required: mode (static, motion or transfer) and IMU (or --config "
                "FILE giving them)")
    if args.mode == "static" and args.position is None:
        return "static alignment needs --position LAT,LON,H"
    if args.mode == "motion" and (args.speed is None or args.initial is None):
        return "motion alignment needs a SPEED record and --initial LAT,LON,H,HEADING,PITCH,ROLL"
    if args.mode == "transfer" and args.speed is None:
        return "transfer alignment needs the master's navigation record: gfins align transfer SLAVE_IMU MASTER_NAV"
    if args.mode != "transfer" and (args.simulate is not None or args.truth or args.truth_json or args.plot):
        return "--simulate, --truth, --truth-json and --plot belong to transfer alignment"
    if args.disturbed and args.mode != "static":
        return "--disturbed is a static coarse alignment (on a swaying base)"
    if args.fine_end is not None and not args.fine:
        return "--fine-end is the end of the fine alignment: give --fine"
    if args.heading is not None and args.mode != "static":
        return "--heading is for the static alignment (motion: --initial holds the heading)"
    if args.position is not None and not abs(args.position[0]) < 90:
        return f"--position: latitude must be in (-90, 90) deg; got {args.position[0]}"
    if args.initial is not None and not abs(args.initial[0]) < 90:
        return f"--initial: latitude must be in (-90, 90) deg; got {args.initial[0]}"
    return None


def executor_arguments(p) -> None:
    """--scheduler and --workers: where a Monte Carlo runs (gfins_fmi.analysis.montecarlo.
    executor); shared by the commands and the bench studies."""
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the Monte-Carlo runs on a dask.distributed cluster: its "
                        "scheduler's address, e.g. tcp://10.0.0.5:8786 (needs "
                        "'gfins_fmi[dask]'; results equal a local run with the same seed)")
    p.add_argument("--workers", type=count(1), default=None,
                   help="without --scheduler: threads on this machine (default: one per "
                        "CPU); with it: wait for this many cluster workers")


def record_arguments(p, what: str) -> None:
    """Input, output and streaming options, shared by the record commands."""
    p.add_argument("input", type=pathlib.Path,
                   help=f"{what}: CSV text (comma-separated, '#' comments), .parquet or .npz")
    p.add_argument("output", type=pathlib.Path,
                   help="solution file: CSV text unless it ends in .parquet or .npz; written "
                        "beside its name and renamed into place when complete")
    p.add_argument("--header", action="store_true",
                   help="the CSV's first line (after '#' comments) is a line of column names")
    p.add_argument("--chunk", type=count(2), default=1 << 18, metavar="SAMPLES",
                   help="samples read, solved and written at a time (default 262144); memory "
                        "grows with it")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar over reading, solving and writing (default: on for "
                        "inputs of 10^6 samples, or 64 MiB of text, or more)")


def config_arguments(p, command: str, written: str) -> None:
    """``--config FILE``, ``--print-config`` and ``--save-config FILE`` of ``gfins align``
    and ``gfins calibrate`` (gfins_fmi.cli.config_file; ``written``: where the effective
    configuration goes by default)."""
    p.add_argument("--config", type=pathlib.Path, default=None, metavar="FILE.toml",
                   help="the run's settings from a file (TOML, YAML, or a run's .config.json to repeat it): "
                        "the options by name (positionals too); options given here override it "
                        f"(gfins {command} --print-config prints a template)")
    p.add_argument("--print-config", action="store_true",
                   help="print a commented template of the configuration file (every option, its units and "
                        "default) and exit")
    p.add_argument("--save-config", type=pathlib.Path, default=None, metavar="FILE.json",
                   help="write the effective configuration (every option with its value and unit, the values "
                        "the run chose, the inputs) here; by default it goes " + written +
                        "; --config FILE.json repeats the run")


def _deferred(args) -> bool:
    """The combinations are checked once the --config file is read (gfins_fmi.cli.config_file.configured)."""
    return bool(args.print_config) or (args.config is not None and not getattr(args, "config_applied", False))


def imu_errors_argument(p) -> None:
    """``--imu-errors CAL.toml``, shared by the commands that read IMU records."""
    p.add_argument("--imu-errors", type=pathlib.Path, default=None, metavar="CAL.toml",
                   help="compensate the IMU record with these errors first ([imu_errors] of a file "
                        "`gfins calibrate poses` writes)")


def state_arguments(p) -> None:
    """Initial state and vertical channel, shared by the navigation commands (the state:
    :func:`gfins_fmi.cli.initial.from_state_options`)."""
    p.add_argument("--lat0", type=real("deg", above=-90.0, below=90.0), required=True,
                   help="initial latitude, deg")
    p.add_argument("--lon0", type=real("deg"), required=True, help="initial longitude, deg")
    p.add_argument("--h0", type=real("m", above=-0.5 * WGS84.a, below=WGS84.a / 3.0), default=0.0,
                   help="initial height above the ellipsoid, m, in (-a/2, a/3) (also the held "
                        "height)")
    p.add_argument("--heading0", type=real("deg"), default=0.0,
                   help="initial heading, deg clockwise from north")
    p.add_argument("--pitch0", type=real("deg"), default=0.0, help="initial pitch, deg")
    p.add_argument("--roll0", type=real("deg"), default=0.0, help="initial roll, deg")
    p.add_argument("--v0", type=vector(3, "E,N,U in m/s"), default=[0.0, 0.0, 0.0],
                   help="initial velocity E,N,U in m/s (e.g. --v0 -1,2,0)")
    p.add_argument("--vertical", choices=["free", "hold", "baro"], default="free",
                   help="vertical channel (baro needs the external height as the last column)")
    p.add_argument("--baro-tau", type=real("s", above=0.0), default=10.0,
                   help="baro loop time constant, s")


#: ``--initial`` of integrate and align motion (cli/integrate_options.py)
_INITIAL = INITIAL_OPTION

def _noise(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("noise", help="noise identification of a static IMU record: Allan deviation "
                       "per axis with confidence intervals, fitted terms, the filter's noise block",
                       description="Overlapping Allan deviation of a static record (streamed), the IEEE "
                       "952 terms fitted per axis (quantisation, ARW/VRW, bias instability or a "
                       "Gauss-Markov bump, rate random walk, rate ramp) with their 1-sigma, written "
                       "as the noise block `gfins integrate --noise-file` reads (docs/characterise_imu.md).")
    p.add_argument("record", type=pathlib.Path, help="static IMU record: ImuRecord CSV, npz or Parquet "
                   "(rates or increments, read in chunks), or --format kfgins/rtk_walk")
    p.add_argument("--format", choices=("record", "kfgins", "rtk_walk"), default="record",
                   help="record: our ImuRecord columns (default); kfgins, rtk_walk: those readers")
    p.add_argument("--output", type=pathlib.Path, default=None, metavar="NOISE.toml",
                   help="write the noise block here (for gfins integrate --noise-file)")
    p.add_argument("--table", type=pathlib.Path, default=None, metavar="ADEV.csv",
                   help="write tau, the deviation of every axis and its 68%% interval")
    p.add_argument("--plot", type=pathlib.Path, default=None, help="folder for the log-log figure")
    p.add_argument("--per-decade", type=count(1), default=10, help="taus per decade (default 10)")
    p.add_argument("--tau-max", type=real("s", above=0.0), default=None,
                   help="largest tau, s (default a quarter of the record; memory is 2.5 tau-max "
                        "of samples per axis)")
    p.add_argument("--progress", action="store_true", help="progress bar while reading")
    _command(p, "noise_id")
    return p


#: ``gfins calibrate --format``: the raw 7-column layouts (gfins_fmi.io.raw_imu) by name
RAW_FORMATS = {"bin64": "float64", "bin32": "float32", "text7": "text"}


def _calibrate(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("calibrate", help="system-level calibration (the full lever-arm model or seed "
                       "001's 36 states) of a raw multi-position record", description=CALIBRATE_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("imu", type=pathlib.Path, nargs="?", default=None,
                   help="raw IMU record (IMU frame), starting at rest; or the word poses followed by RECORD for "
                        "the calibration at unknown poses (may come from --config)")
    p.add_argument("record", type=pathlib.Path, nargs="?", default=None,
                   help="(gfins calibrate poses RECORD) the hand-turned record")
    p.add_argument("--format", choices=("csv", "kfgins", "rtk_walk") + tuple(RAW_FORMATS), default="csv",
                   help="csv: gfins_fmi.io ImuRecord CSV (increments or rates); kfgins: KF-GINS IMU file; "
                        "bin64, bin32, text7: seven columns [wx wy wz ax ay az t] (PSINS's imu array), "
                        "float64 / float32 binary or text (docs/io.md); rtk_walk (poses only)")
    p.add_argument("--raw-kind", choices=("increments", "rates"), default="increments",
                   help="raw formats: increments over the interval ending at t (default) or rates at t")
    p.add_argument("--gyro-unit", choices=("rad", "deg", "arcsec", "deg/h"), default="rad",
                   help="raw formats: gyro column unit (per second for rates; deg/h for rates only; default rad)")
    p.add_argument("--accel-unit", choices=("m", "g", "mg", "ug"), default="m",
                   help="raw formats: accelerometer column unit, m (m/s or m/s^2), g, mg, ug (default m)")
    p.add_argument("--time-scale", type=real("s", above=0.0), default=1.0,
                   help="raw formats: seconds per unit of the time column (default 1; 0.001 for ms)")
    p.add_argument("--lat", type=real("deg", above=-89.0, below=89.0), default=None,
                   help="site latitude, deg (required for the system-level calibration)")
    p.add_argument("--lon", type=real("deg"), default=0.0, help="site longitude, deg (default 0)")
    p.add_argument("--height", type=real("m"), default=None,
                   help="site ellipsoidal height, m (required for the system-level calibration)")
    p.add_argument("--gravity", type=real("m/s^2", above=9.7, below=9.9), default=None,
                   help="the site's gravity, m/s^2 (e.g. surveyed; both modes); default WGS-84 "
                        "normal gravity at --lat, --height")
    p.add_argument("--grade", choices=("auto", "navigation", "tactical", "mems"), default="auto",
                   help="IMU grade whose priors and noise are the defaults (calibration.grades); "
                        "auto: read from the first static interval (default)")
    p.add_argument("--model", choices=("full", "seed"), default="full",
                   help="full: lever arms in all directions (default); seed: seed 001's 36 states")
    p.add_argument("--delay", action=argparse.BooleanOptionalAction, default=None,
                   help="estimate the accelerometer sample delay (default: yes with --model full, "
                        "no with --model seed)")
    p.add_argument("--arw", type=real("deg/sqrt(h)", at_least=0.0), default=None,
                   help="gyro angle random walk, deg/sqrt(h) (default: the grade's)")
    p.add_argument("--vrw", type=real("ug/sqrt(Hz)", at_least=0.0), default=None,
                   help="accelerometer white noise, ug/sqrt(Hz) (default: the grade's)")
    p.add_argument("--vel-std", type=real("m/s", at_least=0.0), default=None,
                   help="std of the zero-velocity measurement (base sway), m/s (default: the grade's, "
                        "1e-5; 0: 1e-6)")
    p.add_argument("--passes", type=int, default=2, choices=range(1, 11), metavar="N",
                   help="filter passes, each linearised about the previous estimates, the prior kept (default 2)")
    p.add_argument("--prior", type=prior_setting, action="append", default=[], metavar="NAME=VALUE",
                   help="prior 1-sigma (calibration.syscal_filter.Prior field, its unit), e.g. "
                        "gyro_bias_deg_h=0.05")
    p.add_argument("--prior-mean", type=pathlib.Path, default=None, metavar="CLBT",
                   help="centre the prior on this compensation form (.json, .toml, PSINS .bin or text)")
    p.add_argument("--widen-priors", action="store_true",
                   help="when estimates fight their prior, widen those priors and run again")
    p.add_argument("--max-rounds", type=int, default=4, choices=range(1, 11), metavar="N",
                   help="with --widen-priors: at most N runs (default 4)")
    p.add_argument("--heading", type=real("deg"), default=None,
                   help="heading of the IMU's y axis at the start, deg (gyros that cannot see the "
                        "Earth rate: MEMS); default: gyrocompassing")
    p.add_argument("--report", type=pathlib.Path, help="write the report (markdown) here")
    p.add_argument("--json", type=pathlib.Path,
                   help="write estimates, stds, checks, both conventions and FMU parameters here")
    p.add_argument("--compensation", type=pathlib.Path, metavar="CLBT",
                   help="write the compensation form here (.json, .toml, .bin: PSINS's 37 float64, else text)")
    p.add_argument("--plot", type=pathlib.Path, help="folder for the convergence and residual figures")
    p.add_argument("--progress", action="store_true", help="progress bar over the filter passes")
    p.add_argument("--simulate", choices=("seed001", "turntable19"),
                   help="first write a simulated record of this path to IMU (see --sim-errors; the "
                        "noise of --arw/--vrw, default 0.002 deg/sqrt(h) and 10 ug/sqrt(Hz))")
    p.add_argument("--sim-errors", choices=("seed", "lab"), default="seed",
                   help="--simulate's errors: seed (random at seed 001's prior, lever arms along the "
                        "axes; default) or lab (random at a laboratory tool's defaults: lever arms "
                        "across the axes, 1 ms delay; calibration.compensation.random_compensation)")
    p.add_argument("--sim-seed", type=int, default=0, help="seed of --simulate (default 0)")
    q = p.add_argument_group("calibration at unknown poses (gfins calibrate poses RECORD)")
    q.add_argument("--counts", type=vector(2, "GYRO_LSB_PER_DPS,ACCEL_LSB_PER_G"), default=None,
                   metavar="GYRO_LSB_PER_DPS,ACCEL_LSB_PER_G",
                   help="the record holds raw counts (t in s): their nominal sensitivities, LSB per deg/s "
                        "and LSB per g")
    q.add_argument("--initial-still", type=real("s", above=0.0), default=20.0,
                   help="the record's still start, s (default 20): the sensor's noise and gyro bias")
    q.add_argument("--still-window", type=real("s", above=0.0), default=1.0,
                   help="window of the still detector, s (default 1)")
    q.add_argument("--still-accel", type=real("", above=0.0), default=6.0,
                   help="still when the accelerometer variance is below this many times the initial one (default 6)")
    q.add_argument("--still-gyro", type=real("", above=0.0), default=6.0,
                   help="... and the gyro window mean below this many times its noise + 0.5 deg/s (default 6)")
    q.add_argument("--min-still", type=real("s", above=0.0), default=2.0,
                   help="shortest pose, s (default 2)")
    q.add_argument("--k2", action="store_true", help="also fit the accelerometers' K2 (needs >= 15 poses)")
    q.add_argument("--gyro-bias", choices=("still", "fit"), default="still",
                   help="gyro bias from the initial still period (default) or from the turns")
    q.add_argument("--output", type=pathlib.Path, default=None, metavar="CAL.toml",
                   help="write [imu_errors] (for gfins integrate --imu-errors)")
    q.add_argument("--table", type=pathlib.Path, default=None, metavar="PREFIX",
                   help="write PREFIX.poses.csv and PREFIX.turns.csv (residuals before and after)")
    config_arguments(p, "calibrate", "beside the first of --report, --json, --compensation (R.config.json), "
                     "else in --plot DIR (calibrate.config.json)")
    _command(p, "calibrate", check=check_calibrate)
    return p


def check_calibrate(args) -> str | None:
    """``gfins calibrate poses RECORD`` runs cli/calibrate_poses.py; ``gfins calibrate IMU``
    the system-level calibration, which needs the site (with --config: checked once the
    file is read)."""
    if _deferred(args):
        return None
    if args.imu is None:
        return "the following arguments are required: IMU (or --config FILE giving it)"
    if args.record is not None:
        if str(args.imu) != "poses":
            return f"one record: gfins calibrate IMU ..., or gfins calibrate poses RECORD (got {args.imu} {args.record})"
        if args.gravity is None and (args.lat is None or args.height is None):
            return "the calibration at poses needs the gravity: --lat and --height (normal gravity), or --gravity"
        if args.format in RAW_FORMATS:
            return f"--format {args.format} is for the system-level calibration (gfins calibrate IMU); poses reads csv, kfgins, rtk_walk"
        args.module = "calibrate_poses"
        return None
    if args.lat is None or args.height is None:
        return "the following arguments are required: --lat, --height"
    if args.format == "rtk_walk":
        return "--format rtk_walk is for gfins calibrate poses"
    if args.format in RAW_FORMATS and args.raw_kind == "increments" and args.gyro_unit == "deg/h":
        return "--gyro-unit deg/h is a rate: use it with --raw-kind rates"
    if args.max_rounds != 4 and not args.widen_priors:
        return "--max-rounds needs --widen-priors"
    return None


def _align(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("align", help="initial alignment: static (levelling + gyrocompassing, fine "
                       "alignment), in motion with a speed sensor and forward-backward passes, or "
                       "transfer alignment of a slave IMU against a master INS",
                       description="Initial alignment of recorded files (docs/alignment.md). --config FILE "
                       "(TOML or YAML) gives every option, the mode and files too (options typed here override "
                       "it); --print-config prints its template; a run writes its effective configuration "
                       "beside --output (OUT.config.json) or at --save-config, and --config of it repeats the run.")
    p.add_argument("mode", choices=("static", "motion", "transfer"), nargs="?", default=None,
                   help="static, motion or transfer (may come from --config)")
    p.add_argument("imu", type=pathlib.Path, nargs="?", default=None,
                   help="IMU file (ImuRecord CSV / npz / parquet); transfer: the slave's (may come from --config)")
    imu_errors_argument(p)
    p.add_argument("speed", type=pathlib.Path, nargs="?", default=None, metavar="SPEED|MASTER_NAV",
                   help="motion: speed record (OdometerRecord: t_s, speed_m_s, std_m_s); transfer: the "
                        "master's navigation record (KF-GINS .nav, our navigation CSV with NAV_SOLUTION "
                        "columns and optionally omega_x_rad_s.. its rate, or a TruthRecord CSV)")
    p.add_argument("--position", type=vector(3, "LAT,LON,H in deg, deg, m"), default=None,
                   metavar="LAT,LON,H", help="static: position (deg, deg, m)")
    p.add_argument("--window", type=vector(2, "T0,T1 in s"), default=None, metavar="T0,T1",
                   help="static: the window at rest for the coarse alignment, s (default: the first 60 s)")
    p.add_argument("--fine", action="store_true", help="static: fine alignment (zero-velocity updates) from "
                   "the window's end to --fine-end; after --disturbed with a 0.1 m/s velocity 1-sigma")
    p.add_argument("--fine-end", type=real("s"), default=None, metavar="T1",
                   help="static: the fine alignment's end time, s, on the record's scale (default: its end)")
    p.add_argument("--heading", type=real("deg"), default=None, metavar="DEG",
                   help="static: the heading, deg clockwise from north, when gyrocompassing cannot give one "
                        "(a MEMS IMU) or to replace it; its 1-sigma is --heading-std")
    p.add_argument("--disturbed", action="store_true",
                   help="static on a swaying base (a moored ship, an idling vehicle): the inertial-frame "
                        "coarse alignment; the attitude is that at the window's end (default window: the "
                        "first 300 s)")
    p.add_argument("--initial", type=_INITIAL, default=None, metavar="LAT,LON,H,HEADING,PITCH,ROLL",
                   help="motion: coarse start at the record's start (deg, deg, m, deg, deg, deg); the "
                        "velocity is the first speed along the heading")
    p.add_argument("--depth", type=pathlib.Path, default=None,
                   help="motion: height record (BaroRecord CSV, h_m = -depth)")
    p.add_argument("--passes", type=count(0), default=5, help="motion: forward-backward passes (default 5)")
    p.add_argument("--heading-std", type=real("deg", above=0.0), default=5.0,
                   help="motion, and static with --heading: 1-sigma of the coarse heading, deg (default 5)")
    p.add_argument("--tilt-std", type=real("deg", above=0.0), default=0.5,
                   help="motion: 1-sigma of the coarse pitch/roll, deg (default 0.5)")
    p.add_argument("--gyro-bias", type=real("deg/h", at_least=0.0), default=None,
                   help="1-sigma turn-on gyro bias, deg/h (default: the grade's bias instability)")
    p.add_argument("--accel-bias", type=real("ug", at_least=0.0), default=None,
                   help="1-sigma turn-on accelerometer bias, ug (default: the grade's)")
    p.add_argument("--grade", choices=GRADES, default=None,
                   help="IMU noise model (default navigation; transfer: consumer, the slave's)")
    p.add_argument("--output", type=pathlib.Path, default=None,
                   help="motion: CSV of the state after each pass; transfer: CSV of the estimates and "
                        "their 1-sigma over time")
    p.add_argument("--progress", action="store_true", help="report the passes as they run")
    transfer_arguments(p)
    config_arguments(p, "align", "beside --output (OUT.config.json; with --plot only: FIG.config.json)")
    _command(p, "align", check=check_align)
    return p


def build_parser() -> tuple[argparse.ArgumentParser, dict]:
    """The ``gfins`` parser and its subcommands' parsers by name."""
    seconds = real("s", above=0.0)
    lever_arm = real("m", at_least=MIN_LEVER_ARM_M)
    parser = argparse.ArgumentParser(
        prog="gfins",
        description="gfins_fmi: gyro-free and strapdown inertial navigation — C core, "
                    "cffi, FMI co-simulation FMUs, error analysis.")
    sub = parser.add_subparsers(dest="command", required=True)
    parsers = {}

    p = parsers["demo"] = sub.add_parser(
        "demo", help="the main job: motion -> accelerometer array -> solve via cffi and via the "
        "FMUs (fmpy) -> agreement, errors, analysis, plot")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_demo"),
                   help="folder for the figure (default: ./gfins_demo)")
    p.add_argument("--duration", type=seconds, default=60.0, help="record length, s (default 60)")
    p.add_argument("--dt", type=seconds, default=0.01, help="sampling interval, s (default 0.01)")
    p.add_argument("--lever-arm", type=lever_arm, default=0.1, help="lever arm l, m (default 0.1)")
    p.add_argument("--noise", type=real("m/s^2", at_least=0.0), default=1e-4,
                   help="white noise per accelerometer, m/s^2 (default 1e-4)")
    _command(p, "demo", check=_check_demo)

    p = parsers["solve9"] = sub.add_parser(
        "solve9", help="solve a record of 9 accelerometer outputs (m/s^2; optional "
        "leading time column) and write the solution (CSV, Parquet or npz)")
    record_arguments(p, "accelerometer outputs A1..A9 (m/s^2), optionally after a time column (s)")
    p.add_argument("--dt", type=seconds, default=None,
                   help="sampling interval, s (default: from the time column, which it must "
                        "agree with when both are given)")
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--omega-init", type=vector(3, "x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, as x,y,z: the first signs and the start "
                        "of the omega_dot integral that gives the later signs")
    _command(p, "solve9")

    p = parsers["navigate"] = sub.add_parser(
        "navigate", help="strapdown navigation of a record (t, gyro x y z, accel x y z "
        "[, h_ext]) -> solution (CSV, Parquet or npz)")
    record_arguments(p, "t (s), gyro x y z, accel x y z [, h_ext (m)]")
    p.add_argument("--input-kind", choices=["increments", "rates"], default="increments",
                   help="increments: rad and m/s over (t_(k-1), t_k]; rates: rad/s and m/s^2 at t_k")
    imu_errors_argument(p)
    state_arguments(p)
    p.add_argument("--t0", type=real("s"), default=None,
                   help="time of the initial state, s (default: one interval before the first "
                        "increment, or the first rate sample)")
    p.add_argument("--no-coning", action="store_true", help="one-sample algorithm")
    p.add_argument("--subsamples", type=int, choices=[1, 2, 3, 4], default=1, metavar="N",
                   help="increments per navigation update, 1..4 (default 1); N > 1 writes one "
                        "row per update (every N-th increment's time; the last row takes the "
                        "increments left)")
    _command(p, "navigate")

    p = parsers["gfnav"] = sub.add_parser(
        "gfnav", help="gyro-free navigation of a record of accelerometer-array outputs "
        "(t, A1..AN [, h_ext]) at a fixed interval -> solution (CSV, Parquet or npz)")
    record_arguments(p, "t (s), A1..AN (m/s^2) [, h_ext (m)]")
    p.add_argument("--layout", choices=["cube6", "qin9", "12"], required=True)
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--strategy", choices=["integrate", "sqrt", "eigen", "fused"],
                   default="integrate", help="angular-rate strategy (default integrate)")
    p.add_argument("--accel-noise", type=real("m/s^2", above=0.0, at_most=1000.0), default=1e-4,
                   help="accelerometer white-noise std, m/s^2, at most 1000 (fused strategy)")
    p.add_argument("--omega-init", type=vector(3, "x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, x,y,z (e.g. --omega-init -1,0,0)")
    state_arguments(p)
    _command(p, "gfnav")

    p = parsers["reproduce"] = sub.add_parser(
        "reproduce", help="reproduce a published experiment (qin: the 6- vs 9-accelerometer "
        "comparison of seed 000, as a Monte Carlo)")
    p.add_argument("experiment", choices=["qin", "seed001"],
                   help="qin: seed 000; seed001: the vehicle test of seed 001 (rotating INS, "
                        "calibration with and without K_a2 and lever arms)")
    p.add_argument("--runs", type=count(1), default=None,
                   help="Monte-Carlo runs (default: qin 100, seed001 3 calibrations)")
    p.add_argument("--seed", type=count(0), default=2008, help="random seed (default 2008)")
    p.add_argument("--drift-signs", choices=["random", "equal"], default="random",
                   help="signs of the 1.5e-5 m/s^2 drifts (default: random per sensor and run)")
    p.add_argument("--gravity", type=real("m/s^2", at_least=0.0), default=9.8,
                   help="gravity of the fixed frame, m/s^2 (default 9.8; 0: gravity-free)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_reproduce"),
                   help="folder for the figure and the table")
    executor_arguments(p)
    _command(p, "reproduce")

    p = parsers["analyze"] = sub.add_parser(
        "analyze", help="error growth: python-control predictions against a Monte Carlo of "
        "the C core, as a markdown report with figures")
    p.add_argument("--config", action="append", choices=list(ANALYZE_CONFIGS),
                   help="configuration (repeatable; default: all); see gfins_fmi.analysis.error_report")
    p.add_argument("--runs", type=count(2), default=1000,
                   help="Monte-Carlo runs per configuration (default 1000; a standard deviation "
                        "needs 2)")
    p.add_argument("--seed", type=count(0), default=0, help="random seed (default 0)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_analysis"),
                   help="folder for report.md and the figures")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    executor_arguments(p)
    _command(p, "analyze")

    p = parsers["cosim"] = sub.add_parser(
        "cosim", help="vehicle FMU + navigator FMU co-simulation (seed 001's run): Python "
        "master, SSP file and container FMU, each checked against cffi (ins_gnss: against "
        "the batch API, with GNSS, barometer and odometer)")
    p.add_argument("--navigator", choices=["gfnav_qin9", "gfnav_cube6", "gfnav_12", "sins",
                                           "ins_gnss"], default="gfnav_qin9")
    p.add_argument("--seconds", type=seconds, default=600.0, help="stop time, s (default 600)")
    p.add_argument("--step", type=seconds, default=0.01, help="communication step, s (default 0.01)")
    p.add_argument("--align", type=seconds, default=60.0, help="rest before the run, s (default 60)")
    p.add_argument("--fmi", type=int, choices=[2, 3], default=3, help="FMI version of the master run")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_cosim"),
                   help="folder for the SSP, the container FMU and the error CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _command(p, "cosim", check=_check_cosim)

    parsers["integrate"] = integrate_parser(sub, imu_errors_argument, _command)
    parsers["noise"] = _noise(sub)
    parsers["calibrate"] = _calibrate(sub)
    parsers["align"] = _align(sub)

    p = parsers["validate"] = sub.add_parser("validate", help="run fmpy's validation on every shipped FMU")
    _command(p, "validate")
    p = parsers["info"] = sub.add_parser("info", help="version and paths of the shipped FMUs")
    _command(p, "validate", "info")
    return parser, parsers
