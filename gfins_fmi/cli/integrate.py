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
The IMU record (any format, any start) is read, filtered and written in chunks
(gfins_fmi.io.imu_stream, cli/integrate_stream.py), --smooth too (cli/integrate_smooth.py);
--plot reads it whole.
"""
from __future__ import annotations

import dataclasses
import itertools
import json
import pathlib
import sys
import time

import numpy as np

from gfins_fmi import io
from gfins_fmi._lib import GfinsError
from gfins_fmi._version import __version__
from gfins_fmi.cli import Failed
from gfins_fmi.cli.files import (cause, compensated, compensated_block, outputs, read_gnss, read_imu,
                                 read_optional, read_truth)
from gfins_fmi.cli.config_file import config_template, configured, input_file, option_units
from gfins_fmi.cli.initial import from_initial_option, record_start_s
from gfins_fmi.cli.kfgins_config import initial_state as kfgins_initial_state
from gfins_fmi.cli.kfgins_config import (kfgins_outputs, kfgins_tables, open_kfgins_writers, read_kfgins_config,
                                         write_kfgins_outputs)
from gfins_fmi.cli.integrate_stream import STREAM_CHUNK, Scores, grouped, solution_table, time_slice
from gfins_fmi.cli.integrate_smooth import open_smoother, smoothed_path, smoothed_table, write_smoothed
from gfins_fmi.cli.integrate_options import INITIAL_STD_DEFAULTS, check_integrate
from gfins_fmi.cli.parser import build_parser
from gfins_fmi.cli.noise import imu_noise
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.estimation.alignment import align_static_then_gnss, heading_from_gnss
from gfins_fmi.estimation.config import (MEAS_TYPES, SENSOR_NAMES, UPDATE_STATUS, FilterConfig,
                                         FilterError, InitialState)
from gfins_fmi.estimation.evaluation import (NavErrors, gnss_outage_drift, gnss_residuals, kfgins_outage_windows,
                                             navigation_errors, outage_drift, plot_errors, reference_at,
                                             without_outages)
from gfins_fmi.estimation.measurement_checks import unusable_measurements
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.io.columns import INNOVATION_COLUMNS
from gfins_fmi.io.imu_stream import ImuChunks
from gfins_fmi.io.output_set import signals_held
from gfins_fmi.nav.strapdown import NavState, quat_to_euler

__all__ = ["run"]


def _write(outs, path, sol, extra_note="", quiet=False, all_states=False):
    """The solution table: position, velocity and attitude in degrees, the 1-sigma (attitude
    in degrees), the estimates of the sensor states the filter has."""
    outs.write_table(path, *solution_table(sol, all_states))
    if not quiet:
        print(f"{len(sol)} samples{extra_note} -> {path}")


def _write_solution(args, outs, sol, quiet=False):
    """Our solution table, or with --kfgins-config KF-GINS's three files."""
    if args.kfgins is None:
        _write(outs, args.output, sol, quiet=quiet, all_states=args.all_states)
        return
    files = kfgins_outputs(args.kfgins.output)
    write_kfgins_outputs(outs, files, sol)
    if not quiet:
        print(f"{len(sol)} samples -> {files['nav']}, {files['imu_err'].name}, {files['std'].name}")


#: the innovation log's column types
_INNOVATION_DTYPES = [np.float64, str, str, np.int64, np.float64] + [np.float64] * 6


def _innovation_columns(sol) -> list:
    inn = sol.innovations
    kinds = np.array([MEAS_TYPES[int(x)] for x in inn["type"]], dtype=str)
    status = np.array([UPDATE_STATUS[int(x)] for x in inn["status"]], dtype=str)
    return [inn["t_s"], kinds, status, inn["m"], inn["nis"], *inn["r"].T, *inn["s_std"].T]


def _write_innovations(outs, path, sol):
    """The innovation log: one row per update, its kind and outcome by name; Python's
    notation for the numbers (the log's format since before TableWriter)."""
    outs.write_table(path, INNOVATION_COLUMNS, _innovation_columns(sol), _INNOVATION_DTYPES, float_format="repr")


def _effective_config(args, cfg, init, windows) -> str:
    """What the run used, to read back or rerun it: the inputs (path, size, time), every
    option, the filter's settings (FilterConfig, datasheet units), the initial state and
    its 1-sigma (as gf_ins_initial_std holds them), the simulated outages; the options'
    units; with --kfgins-config how its keys were mapped."""
    nav = init.nav
    doc = {
        "gfins_fmi": __version__, "command": "integrate",
        "inputs": {k: input_file(getattr(args, k)) for k in ("imu", "gnss", "baro", "odometer", "truth",
                                                                 "kfgins_config")},
        "options": {k: (str(v) if isinstance(v, pathlib.Path) else v) for k, v in sorted(vars(args).items())
                    if k not in ("check", "module", "function", "kfgins", "given_options", "config_applied", "argv")},
        "units": option_units(build_parser()[1]["integrate"]),
        "kfgins_notes": None if args.kfgins is None else args.kfgins.notes,
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


def _outage_windows(args, gnss, t_end_s):
    """The simulated outages of --outages, refused when none falls inside the record."""
    dur, per, first = args.outages
    t0, t1 = float(gnss.t_s[0]), float(min(gnss.t_s[-1], t_end_s))
    windows = kfgins_outage_windows(t0, t1, dur, per, first)
    # an outage with no fix strictly inside removes nothing and scores nothing
    tg = np.asarray(gnss.t_s)
    windows = windows[[bool(np.any((tg > a) & (tg < b))) for a, b in windows]] if len(windows) else windows
    if len(windows) == 0:
        raise ValueError(f"--outages {dur:g},{per:g},{first:g}: no outage starting {first:g} s after "
                         f"the first GNSS epoch removes a fix inside the aided span ({t0:.10g} to "
                         f"{t1:.10g} s, {t1 - t0:.6g} s long): give a FIRST below {t1 - t0:.6g} s")
    return windows


def _initial_from_options(args, imu, truth, cfg) -> InitialState:
    """The initial state of --initial (LAT,LON,H,HEADING,PITCH,ROLL, or 'truth') with
    --initial-velocity and the 1-sigma options (defaults: INITIAL_STD_DEFAULTS), printed."""
    t0 = record_start_s(imu)
    if args.initial == "truth":
        tr = np.asarray(truth.t_s)
        # a start one interval before the first increment can land a rounding off the truth's first row
        t_ref = min(max(t0, tr[0]), tr[-1]) if tr[0] - 1e-6 <= t0 <= tr[-1] + 1e-6 else t0
        ref = reference_at(truth, np.array([t_ref]))
        if not ref["inside"][0] or ref["v"] is None or ref["q"] is None:
            raise ValueError(f"--initial truth: the truth file {args.truth} does not cover the record's start "
                             f"{t0:.10g} s with a position, velocity and attitude: give --initial "
                             "LAT,LON,H,HEADING,PITCH,ROLL")
        nav0 = NavState(ref["q"][0], ref["v"][0], float(ref["lat"][0]), float(ref["lon"][0]),
                        float(ref["h"][0]), t0)
        how = f"from the truth {args.truth} at {t0:.10g} s"
    else:
        nav0 = from_initial_option(args.initial, t0, args.initial_velocity or (0.0, 0.0, 0.0))
        how = "from --initial" + (" and --initial-velocity" if args.initial_velocity else " (at rest)")
    std = {k: getattr(args, k) or v for k, v in INITIAL_STD_DEFAULTS.items()}
    init = InitialState(nav0, position_std_m=tuple(std["position_std"]),
                        velocity_std_m_s=tuple(std["velocity_std"]),
                        attitude_std_rad=tuple(np.radians(std["attitude_std"])), **_bias_stds(args))
    e = np.degrees(quat_to_euler(nav0.q_bn))
    print(f"initial state {how}: lat {np.degrees(nav0.lat_rad):.9f} deg, lon {np.degrees(nav0.lon_rad):.9f} deg, "
          f"h {nav0.h_m:.3f} m, v ENU {', '.join(f'{x:.3f}' for x in nav0.v_n_m_s)} m/s, heading/pitch/roll "
          f"{e[0]:.4f}, {e[1]:.4f}, {e[2]:.4f} deg; 1-sigma position {_csv(std['position_std'])} m, velocity "
          f"{_csv(std['velocity_std'])} m/s, attitude (tilt E, tilt N, heading) {_csv(std['attitude_std'])} deg")
    return init


def _csv(v) -> str:
    return ",".join(f"{x:g}" for x in v)


def _bias_stds(args) -> dict:
    """--gyro-bias-std (deg/h), --accel-bias-std (mGal) as InitialState's (SI)."""
    out = {}
    if args.gyro_bias_std is not None:
        out["gyro_bias_std_rad_s"] = tuple(np.radians(np.asarray(args.gyro_bias_std) / 3600.0))
    if args.accel_bias_std is not None:
        out["accel_bias_std_m_s2"] = tuple(np.asarray(args.accel_bias_std) * 1e-5)
    return out


def _configured(args) -> None:
    """--config: the file's values where the command line gave none, then the checks of
    the combinations (at parse time without a file) on the result."""
    configured(args, build_parser()[1]["integrate"], "integrate", check_integrate)


def run(args) -> int:
    if args.print_config:
        print(config_template(build_parser()[1]["integrate"]), end="")
        return 0
    _configured(args)
    kf = None
    if args.kfgins_config:
        # a KF-GINS configuration file as it is: its paths, settings and output files
        kf = read_kfgins_config(args.kfgins_config)
        args.imu, args.gnss, args.imu_format, args.gnss_format = kf.imu, kf.gnss, "kfgins", "kfgins"
        args.output = kfgins_outputs(kf.output)["nav"]
        args.lever_arm = kf.lever_arm_m
    inn_path = args.output.with_suffix(".innovations.csv")
    sm_path = smoothed_path(args.output)
    with outputs(args.imu, args.gnss, args.baro, args.odometer, args.truth, args.kfgins_config) as outs:
        # every file of the run claimed before it: inputs, folders, links refused now
        if kf is None:
            outs.claim(args.output)
            outs.claim(args.output.with_suffix(".config.json"))
        else:
            if not kf.output.is_dir():
                raise ValueError(f"{args.kfgins_config}: outputpath {kf.output} is not a folder")
            for f in kfgins_outputs(kf.output).values():
                outs.claim(f)
        args.kfgins = kf
        outs.claim(inn_path)
        outs.claim(sm_path, produced=args.smooth)
        figures = {}
        if args.plot:
            outs.claim_folder(args.plot)
            for name in ("filter", "smoother"):
                figures[name] = outs.claim(args.plot / f"integrate_{name}.png",
                                           produced=name == "filter" or args.smooth)
        return _run(args, outs, inn_path, sm_path, figures)


#: options -> the FilterConfig field they set
_OPTION_FIELDS = {"filter": "filter", "propagation_interval": "propagation_interval_s", "lever_arm": "gnss_lever_arm_m",
                  "zupt": "zupt", "nhc": "nhc", "odometer_mount": "odometer_mount", "subsamples": "subsamples"}


def _filter_settings(args, noise, kind, scale) -> dict:
    """FilterConfig's arguments: the options, the configuration file's [filter] table where
    the command line did not give the option that sets the same field."""
    given = set(getattr(args, "given_options", ()))
    kw = {f: getattr(args, o) for o, f in _OPTION_FIELDS.items()}
    kw["gnss_lever_arm_m"] = tuple(kw["gnss_lever_arm_m"])
    for k, v in (getattr(args, "filter_settings", None) or {}).items():
        opt = next((o for o, f in _OPTION_FIELDS.items() if f == k), None)
        if k in ("imu", "input"):
            raise ValueError(f"[filter] {k}: set by the noise options/block and the IMU record, not here")
        if opt is None or opt not in given:
            kw[k] = tuple(v) if isinstance(v, list) else v
    return dict(kw, imu=noise, input=kind, **scale)


def _kfgins_span(imu, kf):
    """KF-GINS's processing interval: the first sample at or after starttime gives the
    initial state's time; the run takes the samples after it, up to endtime."""
    t = imu.t_s
    i0 = int(np.searchsorted(t, kf.start_s, side="left"))
    if i0 >= len(t) - 1:
        raise ValueError(f"starttime {kf.start_s:.10g} s is not before the IMU record's end ({t[-1]:.10g} s)")
    sel = (t > t[i0]) & (t <= (kf.end_s if kf.end_s is not None else t[-1]))
    return float(t[i0]), io.ImuRecord(t_s=t[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind=imu.kind,
                                      source=imu.source)


class _Stage:
    """With --progress: what the run is doing and how long it took, one line each on
    stderr (reading and writing take most of a run's time; the filter has its bar)."""

    def __init__(self, on: bool, what: str):
        self.on, self.what = on, what

    def __enter__(self):
        if self.on:
            self.t0 = time.perf_counter()
            print(f"gfins integrate: {self.what} ...", file=sys.stderr, flush=True)
        return self

    def __exit__(self, *exc):
        if self.on and exc[0] is None:
            print(f"gfins integrate: {self.what}: {time.perf_counter() - self.t0:.2f} s", file=sys.stderr,
                  flush=True)


def _streamed(args) -> bool:
    """Whether the run goes in chunks (memory independent of the record's length): every
    IMU format and every start, --smooth included (integrate_smooth); only --plot, which
    needs the whole solution at once, reads the record whole."""
    return not args.plot


def _compensation(errors):
    """--imu-errors on a streamed chunk (the time before it: the first interval)."""
    def transform(t, gyro, accel, kind, t_before):
        return compensated_block(errors, t, gyro, accel, kind, t_before)
    return transform


def _run(args, outs, inn_path, sm_path, figures) -> int:
    kf = args.kfgins
    streamed = _streamed(args)
    chunks = None
    with _Stage(args.progress, f"reading {args.imu}" + (" (its first chunk)" if streamed else "")):
        if streamed:
            chunks = ImuChunks(args.imu, args.imu_format, args.gps_week, STREAM_CHUNK,
                               kf.imu_columns if kf else 7)
            imu, t_end = chunks.first, chunks.t_end
        else:
            imu = read_imu(args.imu, args.imu_format, args.gps_week, kf.imu_columns if kf else 7)
            t_end = float(imu.t_s[-1])
    with _Stage(args.progress, "reading the GNSS and the other records"):
        gnss = read_gnss(args.gnss, args.gnss_format, args.gps_week)
        baro = read_optional(io.BaroRecord, args.baro)
        odo = read_optional(io.OdometerRecord, args.odometer)
        truth = read_truth(args.truth, args.gps_week)
    # records the run could not use: refused before it (two time scales, most likely)
    problems = unusable_measurements(record_start_s(imu), t_end, gnss=gnss, barometer=baro,
                                     odometer=odo, truth=truth)
    if problems:
        raise ValueError(f"{problems[0]}; nothing was run")
    errors = read_imu_errors(args.imu_errors) if args.imu_errors else None
    if errors is not None:
        print(f"IMU record compensated with {args.imu_errors}")
    # the multi-sample coning/sculling corrections are formed from increments: rates by the
    # trapezoid over each interval (what the filter's rate input assumes too)
    to_increments = args.subsamples > 1 and imu.kind == "rates"
    if streamed:
        if errors is not None or to_increments:
            chunks.convert(None if errors is None else _compensation(errors), to_increments)
        if kf is not None:
            chunks.start_at(kf.start_s)
        imu = chunks.first
    else:
        if errors is not None:
            imu = compensated(imu, errors)
        if to_increments:
            imu = imu.to_increments()
    noise = imu_noise(args.grade, args.noise, args.noise_file) if kf is None else kf.noise
    scale = {} if kf is None else {"scale_factors": True, "gyro_scale_std": kf.scale_std[0],
                                   "accel_scale_std": kf.scale_std[1], "gyro_scale_tau_s": kf.correlation_s,
                                   "accel_scale_tau_s": kf.correlation_s}
    cfg = FilterConfig(**_filter_settings(args, noise, imu.kind, scale))
    if kf is not None:
        t0, rec = _kfgins_span(imu, kf)
        init = kfgins_initial_state(kf, t0, len(SENSOR_NAMES))
        if kf.end_s is not None:
            t_end = min(t_end, kf.end_s)
        print(f"KF-GINS configuration {args.kfgins_config}: IMU samples from {t0:.10g} s to {t_end:.10g} s, "
              f"GNSS {args.gnss}, outputs in {kf.output}")
        for note in kf.notes:
            print(f"KF-GINS configuration: {note}")
        if streamed:
            chunks.keep(t0, kf.end_s)
    elif args.initial:
        init = _initial_from_options(args, imu, truth, cfg)
        rec = imu
        if streamed:
            chunks.keep(init.nav.t_s, None)
    else:
        sp = _aligned(args, chunks, imu, gnss, cfg)
        for note in sp.notes:
            print("alignment:", note)
        init = InitialState(sp.nav, position_std_m=(0.5, 0.5, 1.0), velocity_std_m_s=0.05,
                            attitude_std_rad=np.maximum(sp.attitude_std_rad, 1e-3), sensors=sp.sensors,
                            **_bias_stds(args))
        if streamed:
            chunks.keep(sp.nav.t_s, None)
        else:
            sel = imu.t_s > sp.nav.t_s
            rec = io.ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind=imu.kind,
                               source=imu.source)
    windows = None
    g_used = gnss
    if args.outages:
        windows = _outage_windows(args, gnss, t_end if streamed else float(rec.t_s[-1]))
        g_used = without_outages(gnss, windows)
        print(f"{len(windows)} simulated GNSS outages of {args.outages[0]:g} s (KF-GINS's protocol: the "
              f"{len(gnss) - len(g_used)} fixes strictly inside them removed)")
    nav = IntegratedNavigator(cfg, init)
    config_path = args.output.with_suffix(".config.json") if kf is None else kfgins_outputs(kf.output)["config"]
    outs.write_text(config_path, _effective_config(args, cfg, init, windows))
    if streamed:
        scores = [Scores(gnss, g_used, truth, windows, cfg.gnss_lever_arm_m) for _ in range(1 + args.smooth)]
        return _stream(args, outs, nav, chunks, g_used, baro, odo, scores, inn_path, sm_path)
    try:
        # checked above, on the whole record ("warn": the alignment may have taken its start)
        sol = nav.run(rec, g_used, baro, odo, smoother=args.smooth, progress=args.progress, checks="warn",
                      state_std=kf is not None)     # KF-GINS's std file: every error state's 1-sigma
    except FilterError as exc:
        sol = exc.partial
        _write_solution(args, outs, sol, quiet=True)
        _write_innovations(outs, inn_path, sol)
        why = cause(exc)
        outs.keep_partial(f"the filter stopped at IMU sample {exc.index} of {args.imu}: {why}; the "
                          f"{len(sol)} rows here are the solution before it")
        print(_stopped(outs, why, len(sol)), file=sys.stderr)
        return 1
    with _Stage(args.progress, "writing the solution"):
        _write_solution(args, outs, sol)
        _write_innovations(outs, inn_path, sol)
    counts = {k: int(np.sum(sol.innovations["status"] == v)) for k, v in
              (("accepted", 0), ("gated", 1), ("singular", 2), ("stale", 3), ("forced", 4))}
    print(f"updates: {counts} -> {inn_path}")
    sm = None
    if args.smooth:
        try:
            sm = sol.smooth(progress=args.progress)
            with _Stage(args.progress, "writing the smoothed solution"):
                names, cols, kw = smoothed_table(sm, args.kfgins is not None, args.all_states)
                outs.write_table(sm_path, names, cols, **kw)
                print(f"{len(sm)} samples (smoothed) -> {sm_path}")
        except (ValueError, FilterError, OSError, GfinsError) as exc:   # GfinsError: refused in C
            _failed_after_solution(outs, "the smoother", exc)
    try:
        _summary(args, outs, figures, sol, sm, gnss, truth, windows, cfg)
    except (ValueError, TypeError, OSError, ImportError) as exc:
        _failed_after_solution(outs, "the summary", exc)
    outs.commit()
    return 0


def _aligned(args, chunks, imu, gnss, cfg):
    """The default start: static alignment over the first --static seconds (default 5),
    the heading from GNSS velocity when gyrocompassing refuses. In chunks the record's
    head is read up to the window's end (and, for the GNSS heading, up to its epoch).
    Increments: the window ends on a sample's time (an increment covers the interval that
    ends at its time; a window end a rounding before a sample's time left the next sample
    an interval of 1e-15 s, which the filter refused as an impossible rate)."""
    t0, end = imu.t_s[0], imu.t_s[0] + (args.static or 5.0)
    if chunks is not None and imu.t_s[-1] < end:
        imu = chunks.head(until_s=end)
    if imu.kind == "increments":
        end = imu.t_s[max(int(np.searchsorted(imu.t_s, end, side="right")) - 1, 0)]
    window = (t0, end)
    kw = dict(gyro_bias_std_rad_s=cfg.noise_si()["gyro_bias_std_rad_s"],
              accel_bias_std_m_s2=max(cfg.noise_si()["accel_bias_std_m_s2"], 1e-4))
    sp = align_static_then_gnss(imu, gnss, window, **kw)
    if chunks is not None and sp.alignment.heading_method != "gyrocompass":
        # the gyros carry the heading back from the first GNSS epoch in motion
        t_h = heading_from_gnss(gnss, 1.0, t_from_s=float(window[1]))[0]
        if imu.t_s[-1] < t_h:
            sp = align_static_then_gnss(chunks.head(until_s=t_h), gnss, window, **kw)
    return sp


def _stopped(outs, why: str, rows: int) -> str:
    """The message of a run that stopped: where the rows before it are (none: what was left)."""
    if outs.partial:
        return (f"error: {why}; the {rows} samples before it are in {', '.join(map(str, outs.partial))} "
                f"({outs.outcome().split('; ', 1)[-1]})")
    return f"error: {why}; no sample was filtered: {outs.outcome()}"


def _stream(args, outs, nav, chunks, gnss, baro, odo, scores, inn_path, sm_path) -> int:
    """The run a chunk at a time: each chunk with the measurements of its own span
    (lo, hi], written and scored as it passes; the memory does not grow with the record.
    With --smooth the smoother's epochs and rows go to a temporary folder beside the
    smoothed output (integrate_smooth), removed whatever happens."""
    smoother, remove = open_smoother(outs, nav, sm_path, args.progress) if args.smooth else (None, None)
    try:
        return _stream_run(args, outs, nav, smoother, chunks, gnss, baro, odo, scores, inn_path, sm_path)
    finally:
        if smoother is not None:
            # a Ctrl-C here would stop the removal half way (the interrupt study found the
            # folder left): held until it is done, then raised
            with signals_held():
                smoother.close()
                remove()


def _stream_run(args, outs, nav, smoother, chunks, gnss, baro, odo, scores, inn_path, sm_path) -> int:
    kf = args.kfgins
    if kf is None:
        writers = {"ours": None}      # opened with the first chunk: its columns follow the configuration
    else:
        writers = open_kfgins_writers(outs, kfgins_outputs(kf.output))
    inn = outs.table(inn_path, INNOVATION_COLUMNS, _INNOVATION_DTYPES, float_format="repr")
    counts = dict.fromkeys(("accepted", "gated", "singular", "stale", "forced"), 0)
    rows, lo = 0, nav.t_s
    step = nav.run if smoother is None else smoother.run

    def write(sol):
        nonlocal rows
        if kf is None:
            names, cols = solution_table(sol, args.all_states)
            if writers["ours"] is None:
                writers["ours"] = outs.table(args.output, names)
            writers["ours"].write(cols)
        else:
            for k, cols in kfgins_tables(sol).items():
                writers[k].write(cols)
        inn.write(_innovation_columns(sol))
        rows += len(sol)
        for k, v in zip(counts, range(5)):
            counts[k] += int(np.sum(sol.innovations["status"] == v))

    bar = None
    if args.progress:
        from tqdm import tqdm   # lazy: tqdm only with a progress bar
        bar = tqdm(total=round(max(chunks.t_end - lo, 0.0), 3), unit="s", desc="read, filter, write (record seconds)")
    def stopped(why, what):
        outs.keep_partial(f"{what}: {why}; the {rows} rows here are the solution before it")
        print(_stopped(outs, why, rows), file=sys.stderr)
        return 1

    records = grouped(chunks, nav.config.subsamples)
    try:
        for k in itertools.count():
            try:
                rec = next(records, None)
            except ValueError as exc:
                # a line or sample past the first chunk the record refuses: the rows before it kept
                return stopped(str(exc), f"reading {args.imu} stopped after {rows} samples of the solution")
            if rec is None:
                break
            hi = float(rec.t_s[-1]) + 1e-9      # the navigator's own cut: measurements up to the last sample
            # the first chunk takes the epochs before the start too: the filter logs them as stale
            parts = [time_slice(r, lo if k else -np.inf, hi) for r in (gnss, baro, odo)]
            try:
                sol = step(rec, *parts, checks="warn" if k == 0 else "off", state_std=kf is not None)
            except FilterError as exc:
                write(exc.partial)
                where = rows - len(exc.partial) + exc.index
                return stopped(cause(exc), f"the filter stopped at IMU sample {where} of {args.imu}")
            write(sol)
            scores[0].add(sol)
            # not held while the next chunk is read and filtered: one chunk's solution at a time
            del sol, rec, parts
            if bar:
                bar.update(min(round(hi - lo, 3), bar.total - bar.n))
            lo = hi
    finally:
        if bar:
            bar.close()
    for w in [*writers.values(), inn]:
        if w is not None:
            w.commit()
    if kf is None:
        print(f"{rows} samples -> {args.output}")
    else:
        files = kfgins_outputs(kf.output)
        print(f"{rows} samples -> {files['nav']}, {files['imu_err'].name}, {files['std'].name}")
    if args.progress:
        print(f"gfins integrate: read, filtered and written in chunks of {STREAM_CHUNK} samples", file=sys.stderr)
    print(f"updates: {counts} -> {inn_path}")
    if smoother is not None:
        try:
            n = write_smoothed(outs, smoother, sm_path, scores[1], args.all_states, STREAM_CHUNK, args.progress,
                               kfgins=kf is not None)
            print(f"{n} samples (smoothed) -> {sm_path} ({smoother.n_epochs} epochs smoothed in blocks of "
                  f"{smoother.block_epochs}; {smoother.bytes_on_disk / 1e6:.0f} MB of temporary files, removed)")
        except (ValueError, FilterError, OSError, GfinsError) as exc:   # GfinsError: a block refused in C
            _failed_after_solution(outs, "the smoother", exc)
    try:
        for line in [line for s, name in zip(scores, ("filter", "smoother")) for line in s.lines(name)]:
            print(line)
    except (ValueError, TypeError) as exc:
        _failed_after_solution(outs, "the summary", exc)
    outs.commit()
    return 0


def _failed_after_solution(outs, what: str, exc: Exception):
    """A failure once the solution is written: the solution kept (the set committed
    without the rest), exit status 1, the message says so."""
    outs.commit()
    raise Failed(f"{what}: {exc}; the solution was kept ({outs.outcome()})") from exc


def _summary(args, outs, figures, sol, sm, gnss, truth, windows, cfg) -> None:
    """Errors against --truth, or the residuals to GNSS at the antenna (lever arm
    applied) at the fixes the filter used; the outage protocol's drift; the figures."""
    arm = cfg.gnss_lever_arm_m
    used = gnss if windows is None else without_outages(gnss, windows)
    for name, s in (("filter", sol), ("smoother", sm)):
        if s is None or len(s) == 0:
            continue
        if truth is not None:
            e = navigation_errors(s, truth)
            r = e.rms()
            att = "" if r["heading_rad"] is None else f", heading RMS {np.degrees(r['heading_rad']):.4f} deg"
            print(f"{name}: error to the truth: horizontal RMS {r['horizontal_m']:.3f} m, vertical RMS "
                  f"{r['pos_enu_m'][2]:.3f} m{att}")
        else:
            res = gnss_residuals(s, used, arm)
            r = res.rms()
            print(f"{name}: residuals to the GNSS fixes used ({len(res.t_s)}, at the antenna: lever arm "
                  f"{_csv(arm)} m): horizontal RMS {r['horizontal_m']:.3f} m, vertical RMS {r['up_m']:.3f} m "
                  "(residuals, not errors: the fixes carry their own noise)")
        if windows is not None:
            if truth is not None:
                drift, against = outage_drift(s, truth, windows)["max_m"], "the truth"
            else:
                drift, against = gnss_outage_drift(s, gnss, windows, arm), "the removed fixes at the antenna"
            ok = drift[np.isfinite(drift)]
            print(f"{name}: outage protocol ({len(windows)} outages, against {against}): RMS of the maximum "
                  f"horizontal drift per outage {np.sqrt(np.mean(ok ** 2)):.3f} m (max {ok.max():.3f} m)")
        if args.plot:
            if truth is not None:
                plot_errors(navigation_errors(s, truth), outs.file(figures[name]), std=s.std,
                            title=f"{name} vs truth", windows=windows)
            else:
                res = gnss_residuals(s, gnss, arm)
                plot_errors(NavErrors(res.t_s, res.enu_m, None, None, None), outs.file(figures[name]), std=None,
                            title=f"{name}: residuals to GNSS at the antenna (at the fixes)", windows=windows)
            print("figure:", figures[name])
