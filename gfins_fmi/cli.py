"""The ``gfins`` command."""
from __future__ import annotations

import argparse
import math
import pathlib
import sys


def _demo(args) -> int:
    from gfins_fmi import demo
    res = demo.run(out_dir=args.out, duration_s=args.duration, dt_s=args.dt, l_m=args.lever_arm,
                   noise_m_s2=args.noise)
    ok = all(res[f"fmi{v}"]["problems"] == [] and res[f"fmi{v}"]["max_rel_diff"] <= 1e-12
             for v in (2, 3)) and res["sins"]["fmu_max_rel_diff"] <= 1e-12 \
        and res["cosim"]["master_diff"] == 0.0 and res["cosim"]["ssp_diff"] == 0.0
    print("\ndemo " + ("passed: C core, FMUs and analysis agree" if ok else "FAILED"))
    return 0 if ok else 1


def _option_real(unit: str, **bounds):
    """An argparse type: a finite number in ``unit`` within ``bounds`` (as
    :func:`gfins_fmi._lib.as_scalar`), refused at parse time in the option's terms."""
    def parse(text: str) -> float:
        from gfins_fmi._lib import as_scalar
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number in {unit}; got {text!r}") from None
        try:
            return as_scalar("value", x, unit, **bounds)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("value ")) from None
    return parse


def _option_count(at_least: int):
    """An argparse type: an integer >= ``at_least``."""
    def parse(text: str) -> int:
        try:
            k = int(text)
        except ValueError:
            k = None
        if k is None or k < at_least:
            raise argparse.ArgumentTypeError(f"must be an integer >= {at_least}; got {text!r}")
        return k
    return parse


def _option_vector3(what: str):
    """An argparse type: three comma-separated finite numbers."""
    def parse(text: str) -> list[float]:
        try:
            v = [float(x) for x in text.split(",")]
        except ValueError:
            v = []
        if len(v) != 3 or not all(math.isfinite(x) for x in v):
            raise argparse.ArgumentTypeError(f"expected 3 comma-separated finite numbers ({what}); "
                                             f"got {text!r}")
        return v
    return parse


#: relative tolerance of a fixed sampling interval in a time column: timestamps rounded
#: to microseconds at 1 kHz, or written with 6 decimals at 100 Hz, stay well inside it
_UNIFORM_RTOL = 1e-3


def _time_column(t, source, fixed: bool, dt_option: float | None = None):
    """Checks a record's time column (s): finite and strictly increasing; intervals
    longer than 1.5 times the typical (median) one are gaps. ``fixed``: the solver
    needs one sampling interval, so gaps and intervals off the typical one by more than
    ``_UNIFORM_RTOL`` are errors, and ``dt_option`` (``--dt``) must agree with the column.

    Returns (dt_s, notes): the interval (``--dt`` if given, else from the column) and
    the gaps to report (only when not ``fixed``). Raises ValueError naming the row
    (data rows counted from 0).
    """
    import numpy as np
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"{source}: row {k}: time {t[k]:g} s is not finite")
    d = np.diff(t)
    bad = np.flatnonzero(~(d > 0))
    if bad.size:
        k = int(bad[0]) + 1
        raise ValueError(f"{source}: row {k}: time {t[k]:.10g} s does not increase "
                         f"(previous {t[k - 1]:.10g} s); the time column must increase strictly")
    if d.size == 0:
        if dt_option is None and fixed:
            raise ValueError(f"{source}: one sample: give --dt, the sampling interval")
        return dt_option, []
    typical = float(np.median(d))
    gaps = np.flatnonzero(d > 1.5 * typical) + 1
    notes = []
    if gaps.size:
        listed = "; ".join(f"row {k} (t = {t[k - 1]:.10g} -> {t[k]:.10g} s, "
                           f"{round((t[k] - t[k - 1]) / typical)} intervals of {typical:g} s)"
                           for k in gaps[:3])
        more = f"; and {gaps.size - 3} more" if gaps.size > 3 else ""
        text = (f"{gaps.size} gap{'s' if gaps.size > 1 else ''} in the time column: "
                f"{listed}{more}")
        if fixed:
            raise ValueError(f"{source}: {text}: a fixed-interval solver cannot bridge "
                             f"{'it' if gaps.size == 1 else 'them'}; split the record there")
        notes.append(text)
    if fixed:
        off = np.flatnonzero(np.abs(d - typical) > _UNIFORM_RTOL * typical)
        if off.size:
            k = int(off[0]) + 1
            raise ValueError(f"{source}: the time column is not uniform: row {k} (interval "
                             f"{d[k - 1]:.6g} s against {typical:.6g} s); the solver needs a fixed "
                             "sampling interval")
        dt = float((t[-1] - t[0]) / (t.size - 1))
        if dt_option is not None:
            if abs(dt_option - dt) > _UNIFORM_RTOL * dt:
                raise ValueError(f"{source}: --dt {dt_option:g} s disagrees with the time column "
                                 f"(interval {dt:.6g} s)")
            dt = dt_option
        return dt, notes
    return typical, notes


def _read_csv(path, header: bool = False):
    import numpy as np
    return np.loadtxt(path, delimiter=",", ndmin=2, comments="#", skiprows=1 if header else 0)


def _navigate(args) -> int:
    import numpy as np
    from gfins_fmi import NavState, SinsConfig, Strapdown
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    data = _read_csv(args.input, args.header)
    if data.shape[1] not in (7, 8):
        raise ValueError(f"{args.input}: expected 7 or 8 columns (t, gyro x y z, accel x y z "
                         f"[, h_ext]); found {data.shape[1]}")
    t, gyro, accel = data[:, 0], data[:, 1:4], data[:, 4:7]
    h_ext = data[:, 7] if data.shape[1] == 8 else None
    if args.vertical == "baro" and h_ext is None:
        raise ValueError("--vertical baro needs the external height as an 8th column (h_ext, m)")
    if args.input_kind == "increments" and len(t) < 2 and args.t0 is None:
        raise ValueError("a record of one increment needs --t0 (the time its interval starts)")
    _, notes = _time_column(t, args.input, fixed=False)
    for note in notes:   # the navigator takes any intervals; a gap is worth knowing about
        print(f"note: {note}", file=sys.stderr)
    if args.input_kind == "increments":
        # row k is the increment over (t_(k-1), t_k]; the navigator starts one interval
        # before the first row unless --t0 says otherwise
        t0 = args.t0 if args.t0 is not None else (t[0] - (t[1] - t[0]) if len(t) > 1 else t[0])
    else:
        t0 = args.t0 if args.t0 is not None else t[0]
    deg = np.pi / 180
    x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg], args.v0,
                             args.lat0 * deg, args.lon0 * deg, args.h0, t0)
    cfg = SinsConfig(input=args.input_kind, coning=not args.no_coning, vertical=args.vertical,
                     baro_tau_s=args.baro_tau)
    nav = Strapdown(x0, cfg)
    status = 0
    progress = args.progress if args.progress is not None else len(t) >= 1_000_000
    try:
        sol = nav.run(gyro, accel, t_s=t, h_ext_m=h_ext, progress=progress)
    except (NonFiniteInputError, SampleError) as exc:
        print(f"error: {exc}; writing the {len(exc.partial)} samples navigated before it",
              file=sys.stderr)
        sol, status = exc.partial, 1
    _write_solution(args.output, sol)
    return status


def _write_solution(path, sol, extra=None, extra_header=""):
    """Navigation solution CSV at full precision (17 significant digits, every double
    round-trips): time, position (deg, m; or m in a fixed frame), ENU velocity, Euler
    angles (deg), quaternion [, extra columns]."""
    import numpy as np
    deg = np.pi / 180
    e = sol.euler_rad / deg if len(sol) else np.empty((0, 3))
    if sol.pos_m is not None:
        pos, pos_header = sol.pos_m, "x_m,y_m,z_m"
    else:
        pos, pos_header = np.c_[sol.lat_rad / deg, sol.lon_rad / deg, sol.h_m], "lat_deg,lon_deg,h_m"
    cols = [sol.t_s, pos, sol.v_n_m_s, e, sol.q_bn] + ([extra] if extra is not None else [])
    table = np.column_stack(cols) if len(sol) else np.empty((0, 14 + (0 if extra is None else extra.shape[1])))
    header = (f"t_s,{pos_header},v_e_m_s,v_n_m_s,v_u_m_s,heading_deg,pitch_deg,roll_deg,"
              "q0,q1,q2,q3" + extra_header)
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.17g")
    print(f"{len(sol)} samples navigated -> {path}")


def _gfnav(args) -> int:
    import numpy as np
    from gfins_fmi import GyroFreeNavigator, NavState, SinsConfig, layout
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    g = layout(args.layout, args.lever_arm)
    n = g.n_sensors
    data = _read_csv(args.input, args.header)
    if data.shape[1] not in (n + 1, n + 2):
        raise ValueError(f"{args.input}: layout {args.layout} needs {n + 1} or {n + 2} columns "
                         f"(t, A1..A{n} [, h_ext]); found {data.shape[1]}")
    t, A = data[:, 0], data[:, 1:n + 1]
    h_ext = data[:, n + 1] if data.shape[1] == n + 2 else None
    if args.vertical == "baro" and h_ext is None:
        raise ValueError(f"--vertical baro needs the external height as column {n + 2}")
    if len(t) < 2:
        raise ValueError(f"{args.input}: the record needs at least two samples (the interval "
                         "comes from its time column)")
    dt, _ = _time_column(t, args.input, fixed=True)
    deg = np.pi / 180
    x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg], args.v0,
                             args.lat0 * deg, args.lon0 * deg, args.h0, float(t[0]))
    nav = GyroFreeNavigator(g, x0, args.strategy, args.omega_init, accel_noise_m_s2=args.accel_noise,
                            sins=SinsConfig(vertical=args.vertical, baro_tau_s=args.baro_tau))
    status = 0
    try:
        sol, rates = nav.run(A, dt, h_ext_m=h_ext)
        extra = np.c_[rates.omega_rad_s, rates.f_m_s2, rates.flags]
    except (NonFiniteInputError, SampleError) as exc:
        print(f"error: {exc}; writing the {len(exc.partial)} samples navigated before it",
              file=sys.stderr)
        sol, status, extra = exc.partial, 1, None
    _write_solution(args.output, sol, extra,
                    ",omega_x_rad_s,omega_y_rad_s,omega_z_rad_s,f_x_m_s2,f_y_m_s2,f_z_m_s2,flags"
                    if extra is not None else "")
    return status


def _reproduce(args) -> int:
    args.out.mkdir(parents=True, exist_ok=True)
    if args.experiment == "seed001":
        from gfins_fmi import reproduce_seed001 as S
        runs = args.runs or 3
        print(f"Reproduction of seed 001's vehicle test: {runs} calibrations with and without K_a2 "
              "and lever arms, each driven (assumptions: gfins_fmi/reproduce_seed001.py, "
              "docs/reproductions/seed001_vehicle.md)")
        res = S.run_seed001(runs=runs, seed=args.seed, progress=True)
        table = S.seed001_table(res)
        print("\n" + table)
        png = S.seed001_plot(res, args.out / "seed001_vehicle.png")
        (args.out / "seed001_table.md").write_text(table + "\n", encoding="utf-8")
        print(f"\nfigure: {png}\ntable: {args.out / 'seed001_table.md'}")
        return 0
    from gfins_fmi import reproduce as R
    args.runs = args.runs or 100
    print("Reproduction of Qin, Xu, Li (seed 000), section 2: Monte Carlo of "
          f"{args.runs} runs (assumptions: gfins_fmi/reproduce.py, docs/reproductions/qin.md)")
    res = R.run_qin(runs=args.runs, seed=args.seed, progress=True,
                    drift_signs=args.drift_signs,
                    scenario=R.QinScenario(gravity_m_s2=args.gravity))
    table = R.qin_table(res)
    print("\nErrors at t = 60 s\n" + table)
    imp = R.improvement(res)
    print(f"\nimprovement of 9 over 6 (median |error|): attitude "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["att"]) + "; position "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["pos"]))
    rates = R.rate_strategy_table(progress=False)
    print("\nangular-rate RMS error of the 9-accelerometer strategies (rad/s, median of 20 runs):")
    for case, row in rates.items():
        print(f"  {case:40s} " + "  ".join(f"{k} {v:.3g}" for k, v in row.items()))
    png = R.qin_plot(res, args.out / "qin_errors.png")
    (args.out / "qin_table.md").write_text(table + "\n", encoding="utf-8")
    print(f"\nfigure: {png}\ntable: {args.out / 'qin_table.md'}")
    return 0


def _validate(args) -> int:
    from gfins_fmi.fmu import MODELS, fmu_path, validate
    bad = 0
    for model in MODELS:
        for version in (2, 3):
            path = fmu_path(model, version)
            problems = validate(path)
            bad += len(problems)
            print(f"{path}: {len(problems)} problems")
            for p in problems:
                print(f"    {p}")
    return 1 if bad else 0


def _analyze(args) -> int:
    import time
    from gfins_fmi.error_report import write_report
    t0 = time.perf_counter()
    from gfins_fmi.error_report import CONFIGS
    configs = args.config or list(CONFIGS)
    path = write_report(args.out, configs, runs=args.runs, seed=args.seed, progress=not args.quiet)
    print(f"report -> {path} ({time.perf_counter() - t0:.1f} s)")
    return 0


def _cosim(args) -> int:
    import numpy as np

    from gfins_fmi import cosim
    from gfins_fmi.vehicle import VehicleProfile
    out = pathlib.Path(args.out)
    res = cosim.compare_runners(args.navigator, VehicleProfile.seed001(align_s=args.align),
                                args.seconds, out, step_s=args.step, fmi_version=args.fmi,
                                progress=not args.quiet)
    e = res["master"]["errors"]
    print(f"vehicle + {args.navigator}, {args.seconds:g} s at {1 / args.step:g} Hz")
    print(f"  navigation error: horizontal max {e['horizontal_m'].max():.4g} m (final "
          f"{e['horizontal_m'][-1]:.4g} m), velocity max {e['velocity_m_s'].max():.3g} m/s, "
          f"attitude max {np.degrees(e['attitude_rad'].max()):.3g} deg")
    names = {"master": f"Python master (FMI {args.fmi}.0)", "ssp": "fmpy SSP simulator",
             "container": "fmpy container FMU (FMI 2.0)"}
    for runner, r in res.items():
        where = f" {r['path']}" if r["path"] else ""
        print(f"  {names[runner]}{where}: {r['wall_s']:.1f} s; vs the cffi navigator on the "
              f"same sensor data |dlat| {r['diff']['lat_rad']:.3g} rad, |dv| "
              f"{r['diff']['v_m_s']:.3g} m/s")
    np.savetxt(out / "cosim_errors.csv", np.c_[e["t_s"], e["horizontal_m"], e["velocity_m_s"],
                                               e["attitude_rad"]], delimiter=",",
               header="t_s,horizontal_error_m,velocity_error_m_s,attitude_error_rad", comments="")
    print(f"  errors -> {out / 'cosim_errors.csv'}")
    ok = all(max(r["diff"].values()) == 0.0 for r in res.values())
    print("cosim " + ("passed: every co-simulation equals the cffi pipeline bit for bit"
                      if ok else "FAILED: a co-simulation differs from the cffi pipeline"))
    return 0 if ok else 1


def _info(args) -> int:
    import gfins_fmi
    from gfins_fmi.fmu import MODELS, fmu_path
    print(f"gfins_fmi {gfins_fmi.__version__}")
    for model in MODELS:
        for version in (2, 3):
            print(f"  FMU {model} (FMI {version}.0): {fmu_path(model, version)}")
    return 0


def _solve9(args) -> int:
    import numpy as np
    from gfins_fmi import solve_accel9
    from gfins_fmi._lib import NonFiniteInputError, SampleError
    data = _read_csv(args.input)
    if data.shape[1] not in (9, 10):
        raise ValueError(f"{args.input}: expected 9 columns (A1..A9, m/s^2) or 10 (t, A1..A9); "
                         f"found {data.shape[1]}")
    if data.shape[1] == 10:   # a leading time column: the interval and the output times
        t, A = data[:, 0], data[:, 1:]
        dt, _ = _time_column(t, args.input, fixed=True, dt_option=args.dt)
    else:
        if args.dt is None:
            raise ValueError(f"{args.input} has no time column: give --dt, the sampling interval")
        A, dt = data, args.dt
        t = np.arange(len(A)) * dt
    try:
        sol = solve_accel9(A, dt, args.lever_arm, args.omega_init)
        status = 0
    except (NonFiniteInputError, SampleError) as exc:
        print(f"error: {exc}; writing the {exc.index} solved samples", file=sys.stderr)
        sol, status = exc.partial, 1
    table = np.column_stack([t[:len(sol)], sol.f_m_s2, sol.omega_rad_s, sol.omega_dot_rad_s2,
                             sol.omega_sq_rad2_s2, sol.flags])
    header = ("t_s,f_x_m_s2,f_y_m_s2,f_z_m_s2,omega_x_rad_s,omega_y_rad_s,omega_z_rad_s,"
              "omega_dot_x_rad_s2,omega_dot_y_rad_s2,omega_dot_z_rad_s2,omega_sq_x_rad2_s2,"
              "omega_sq_y_rad2_s2,omega_sq_z_rad2_s2,flags")
    fmt = ["%.17g"] * 13 + ["%d"]
    np.savetxt(args.output, table, delimiter=",", header=header, comments="", fmt=fmt)
    print(f"{len(sol)} samples solved -> {args.output}; flags: {sol.flag_counts()}")
    return status


def _initial_state_args(p) -> None:
    """Initial state and vertical channel, shared by the navigation commands."""
    p.add_argument("--lat0", type=_option_real("deg", above=-90.0, below=90.0), required=True,
                   help="initial latitude, deg")
    p.add_argument("--lon0", type=_option_real("deg"), required=True, help="initial longitude, deg")
    p.add_argument("--h0", type=_option_real("m", above=-0.5 * 6378137.0), default=0.0,
                   help="initial height, m (also the held height)")
    p.add_argument("--heading0", type=_option_real("deg"), default=0.0,
                   help="initial heading, deg clockwise from north")
    p.add_argument("--pitch0", type=_option_real("deg"), default=0.0, help="initial pitch, deg")
    p.add_argument("--roll0", type=_option_real("deg"), default=0.0, help="initial roll, deg")
    p.add_argument("--v0", type=_option_vector3("E,N,U in m/s"), default=[0.0, 0.0, 0.0],
                   help="initial velocity E,N,U in m/s (write --v0=-1,2,0 when it starts with -)")
    p.add_argument("--vertical", choices=["free", "hold", "baro"], default="free",
                   help="vertical channel (baro needs the external height as the last column)")
    p.add_argument("--baro-tau", type=_option_real("s", above=0.0), default=10.0,
                   help="baro loop time constant, s")


def _check_demo(args) -> str | None:
    n = int(round(args.duration / args.dt))
    if n < 2:
        return (f"--duration {args.duration:g} s at --dt {args.dt:g} s gives {n} sample"
                f"{'' if n == 1 else 's'}; the demo needs at least 2")
    return None


def _check_cosim(args) -> str | None:
    if args.seconds < args.step:
        return f"--seconds {args.seconds:g} s is shorter than one --step ({args.step:g} s)"
    return None


def main(argv: list[str] | None = None) -> int:
    from gfins_fmi.accel_array import MIN_LEVER_ARM_M
    seconds = _option_real("s", above=0.0)
    lever_arm = _option_real("m", at_least=MIN_LEVER_ARM_M)
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
    p.add_argument("--noise", type=_option_real("m/s^2", at_least=0.0), default=1e-4,
                   help="white noise per accelerometer, m/s^2 (default 1e-4)")
    p.set_defaults(func=_demo, check=_check_demo)

    p = parsers["solve9"] = sub.add_parser(
        "solve9", help="solve a CSV record of 9 accelerometer outputs (m/s^2; optional "
        "leading time column) and write the solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--dt", type=seconds, default=None,
                   help="sampling interval, s (default: from the time column, which it must "
                        "agree with when both are given)")
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--omega-init", type=_option_vector3("x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, as x,y,z: the first signs and the start "
                        "of the omega_dot integral that gives the later signs")
    p.set_defaults(func=_solve9)

    p = parsers["navigate"] = sub.add_parser(
        "navigate", help="strapdown navigation of a CSV record (t, gyro x y z, accel x y z "
        "[, h_ext]) -> solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--input-kind", choices=["increments", "rates"], default="increments",
                   help="increments: rad and m/s over (t_(k-1), t_k]; rates: rad/s and m/s^2 at t_k")
    p.add_argument("--header", action="store_true", help="the CSV's first line is a header")
    _initial_state_args(p)
    p.add_argument("--t0", type=_option_real("s"), default=None,
                   help="time of the initial state, s (default: one interval before the first "
                        "increment, or the first rate sample)")
    p.add_argument("--no-coning", action="store_true", help="one-sample algorithm")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar (default: on for records of 10^6 samples or more)")
    p.set_defaults(func=_navigate)

    p = parsers["gfnav"] = sub.add_parser(
        "gfnav", help="gyro-free navigation of a CSV record of accelerometer-array outputs "
        "(t, A1..AN [, h_ext]) at a fixed interval -> solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--layout", choices=["cube6", "qin9", "12"], required=True)
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--strategy", choices=["integrate", "sqrt", "eigen", "fused"],
                   default="integrate", help="angular-rate strategy (default integrate)")
    p.add_argument("--accel-noise", type=_option_real("m/s^2", above=0.0), default=1e-4,
                   help="accelerometer white-noise std, m/s^2 (fused strategy)")
    p.add_argument("--omega-init", type=_option_vector3("x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, x,y,z (write --omega-init=-1,0,0 "
                        "when it starts with -)")
    p.add_argument("--header", action="store_true", help="the CSV's first line is a header")
    _initial_state_args(p)
    p.set_defaults(func=_gfnav)

    p = parsers["reproduce"] = sub.add_parser(
        "reproduce", help="reproduce a published experiment (qin: the 6- vs 9-accelerometer "
        "comparison of seed 000, as a Monte Carlo)")
    p.add_argument("experiment", choices=["qin", "seed001"],
                   help="qin: seed 000; seed001: the vehicle test of seed 001 (rotating INS, "
                        "calibration with and without K_a2 and lever arms)")
    p.add_argument("--runs", type=_option_count(1), default=None,
                   help="Monte-Carlo runs (default: qin 100, seed001 3 calibrations)")
    p.add_argument("--seed", type=_option_count(0), default=2008, help="random seed (default 2008)")
    p.add_argument("--drift-signs", choices=["random", "equal"], default="random",
                   help="signs of the 1.5e-5 m/s^2 drifts (default: random per sensor and run)")
    p.add_argument("--gravity", type=_option_real("m/s^2", at_least=0.0), default=9.8,
                   help="gravity of the fixed frame, m/s^2 (default 9.8; 0: gravity-free)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_reproduce"),
                   help="folder for the figure and the table")
    p.set_defaults(func=_reproduce)

    p = parsers["analyze"] = sub.add_parser(
        "analyze", help="error growth: python-control predictions against a Monte Carlo of "
        "the C core, as a markdown report with figures")
    p.add_argument("--config", action="append",
                   choices=["sins", "cube6", "qin9", "12", "qin9-sqrt", "12-sqrt", "qin9-fused", "12-fused"],
                   help="configuration (repeatable; default: all); see gfins_fmi.error_report")
    p.add_argument("--runs", type=_option_count(2), default=1000,
                   help="Monte-Carlo runs per configuration (default 1000; a standard deviation "
                        "needs 2)")
    p.add_argument("--seed", type=_option_count(0), default=0, help="random seed (default 0)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_analysis"),
                   help="folder for report.md and the figures")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_analyze)

    p = parsers["cosim"] = sub.add_parser(
        "cosim", help="vehicle FMU + navigator FMU co-simulation (seed 001's run): Python "
        "master, SSP file and container FMU, each checked against cffi")
    p.add_argument("--navigator", choices=["gfnav_qin9", "gfnav_cube6", "gfnav_12", "sins"],
                   default="gfnav_qin9")
    p.add_argument("--seconds", type=seconds, default=600.0, help="stop time, s (default 600)")
    p.add_argument("--step", type=seconds, default=0.01, help="communication step, s (default 0.01)")
    p.add_argument("--align", type=seconds, default=60.0, help="rest before the run, s (default 60)")
    p.add_argument("--fmi", type=int, choices=[2, 3], default=3, help="FMI version of the master run")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_cosim"),
                   help="folder for the SSP, the container FMU and the error CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cosim, check=_check_cosim)

    from gfins_fmi.estimation import cli as estimation_cli
    parsers["integrate"] = estimation_cli.add_parser(sub)
    from gfins_fmi.estimation import calibrate_cli
    parsers["calibrate"] = calibrate_cli.add_parser(sub)

    p = parsers["validate"] = sub.add_parser("validate", help="run fmpy's validation on every shipped FMU")
    p.set_defaults(func=_validate)
    p = parsers["info"] = sub.add_parser("info", help="version and paths of the shipped FMUs")
    p.set_defaults(func=_info)

    args = parser.parse_args(argv)
    problem = args.check(args) if getattr(args, "check", None) else None
    if problem:   # a combination of options: refused at parse time too
        parsers[args.command].error(problem)
    from gfins_fmi._lib import GfinsError
    try:
        return args.func(args)
    except (ValueError, TypeError, OSError, GfinsError) as exc:
        print(f"gfins {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
