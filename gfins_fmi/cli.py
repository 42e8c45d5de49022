"""The ``gfins`` command."""
from __future__ import annotations

import argparse
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


def _navigate(args) -> int:
    import numpy as np
    from gfins_fmi import NavState, SinsConfig, Strapdown
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    data = np.loadtxt(args.input, delimiter=",", ndmin=2, comments="#",
                      skiprows=1 if args.header else 0)
    if data.shape[1] not in (7, 8):
        raise ValueError(f"{args.input}: expected 7 or 8 columns (t, gyro x y z, accel x y z "
                         f"[, h_ext]); found {data.shape[1]}")
    t, gyro, accel = data[:, 0], data[:, 1:4], data[:, 4:7]
    h_ext = data[:, 7] if data.shape[1] == 8 else None
    if args.vertical == "baro" and h_ext is None:
        raise ValueError("--vertical baro needs the external height as an 8th column (h_ext, m)")
    if args.input_kind == "increments" and len(t) < 2 and args.t0 is None:
        raise ValueError("a record of one increment needs --t0 (the time its interval starts)")
    if args.input_kind == "increments":
        # row k is the increment over (t_(k-1), t_k]; the navigator starts one interval
        # before the first row unless --t0 says otherwise
        t0 = args.t0 if args.t0 is not None else (t[0] - (t[1] - t[0]) if len(t) > 1 else t[0])
    else:
        t0 = args.t0 if args.t0 is not None else t[0]
    deg = np.pi / 180
    v0 = [float(x) for x in args.v0.split(",")]
    x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg], v0,
                             args.lat0 * deg, args.lon0 * deg, args.h0, t0)
    cfg = SinsConfig(input=args.input_kind, coning=not args.no_coning, vertical=args.vertical,
                     hold_height_m=args.h0, baro_tau_s=args.baro_tau)
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
    """Navigation solution CSV: time, position (deg, m; or m in a fixed frame), ENU
    velocity, Euler angles (deg), quaternion [, extra columns]."""
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
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.12g")
    print(f"{len(sol)} samples navigated -> {path}")


def _gfnav(args) -> int:
    import numpy as np
    from gfins_fmi import GyroFreeNavigator, NavState, SinsConfig, layout
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    g = layout(args.layout, args.lever_arm)
    n = g.n_sensors
    data = np.loadtxt(args.input, delimiter=",", ndmin=2, comments="#",
                      skiprows=1 if args.header else 0)
    if data.shape[1] not in (n + 1, n + 2):
        raise ValueError(f"{args.input}: layout {args.layout} needs {n + 1} or {n + 2} columns "
                         f"(t, A1..A{n} [, h_ext]); found {data.shape[1]}")
    t, A = data[:, 0], data[:, 1:n + 1]
    h_ext = data[:, n + 1] if data.shape[1] == n + 2 else None
    if args.vertical == "baro" and h_ext is None:
        raise ValueError(f"--vertical baro needs the external height as column {n + 2}")
    if len(t) < 2:
        raise ValueError("the record needs at least two samples (the interval comes from t)")
    dt = float(np.median(np.diff(t)))
    if not np.allclose(np.diff(t), dt, rtol=1e-6, atol=1e-9):
        raise ValueError("the gyro-free navigator needs a fixed sampling interval; the time "
                         "column is not uniform")
    deg = np.pi / 180
    v0 = [float(x) for x in args.v0.split(",")]
    w0 = [float(x) for x in args.omega_init.split(",")]
    x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg], v0,
                             args.lat0 * deg, args.lon0 * deg, args.h0, float(t[0]))
    nav = GyroFreeNavigator(g, x0, args.strategy, w0, accel_noise_m_s2=args.accel_noise,
                            sins=SinsConfig(vertical=args.vertical, hold_height_m=args.h0,
                                            baro_tau_s=args.baro_tau))
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
    from gfins_fmi import reproduce as R
    args.out.mkdir(parents=True, exist_ok=True)
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
    from gfins_fmi._lib import NonFiniteInputError
    A = np.loadtxt(args.input, delimiter=",", ndmin=2, comments="#")
    if A.shape[1] == 10:  # a leading time column
        A = A[:, 1:]
    w0 = [float(x) for x in args.omega_init.split(",")]
    try:
        sol = solve_accel9(A, args.dt, args.lever_arm, w0)
        status = 0
    except NonFiniteInputError as exc:
        print(f"error: {exc}; writing the {exc.index} solved samples", file=sys.stderr)
        sol, status = exc.partial, 1
    t = np.arange(len(sol)) * args.dt
    table = np.column_stack([t, sol.f_m_s2, sol.omega_rad_s, sol.omega_dot_rad_s2,
                             sol.omega_sq_rad2_s2, sol.flags])
    header = ("t_s,f_x_m_s2,f_y_m_s2,f_z_m_s2,omega_x_rad_s,omega_y_rad_s,omega_z_rad_s,"
              "omega_dot_x_rad_s2,omega_dot_y_rad_s2,omega_dot_z_rad_s2,omega_sq_x_rad2_s2,"
              "omega_sq_y_rad2_s2,omega_sq_z_rad2_s2,flags")
    fmt = ["%.6f"] + ["%.17g"] * 12 + ["%d"]
    np.savetxt(args.output, table, delimiter=",", header=header, comments="", fmt=fmt)
    print(f"{len(sol)} samples solved -> {args.output}; flags: {sol.flag_counts()}")
    return status


def _initial_state_args(p) -> None:
    """Initial state and vertical channel, shared by the navigation commands."""
    p.add_argument("--lat0", type=float, required=True, help="initial latitude, deg")
    p.add_argument("--lon0", type=float, required=True, help="initial longitude, deg")
    p.add_argument("--h0", type=float, default=0.0, help="initial height, m (also the held height)")
    p.add_argument("--heading0", type=float, default=0.0, help="initial heading, deg clockwise from north")
    p.add_argument("--pitch0", type=float, default=0.0, help="initial pitch, deg")
    p.add_argument("--roll0", type=float, default=0.0, help="initial roll, deg")
    p.add_argument("--v0", default="0,0,0",
                   help="initial velocity E,N,U in m/s (write --v0=-1,2,0 when it starts with -)")
    p.add_argument("--vertical", choices=["free", "hold", "baro"], default="free",
                   help="vertical channel (baro needs the external height as the last column)")
    p.add_argument("--baro-tau", type=float, default=10.0, help="baro loop time constant, s")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="gfins",
        description="gfins_fmi: gyro-free and strapdown inertial navigation — C core, "
                    "cffi, FMI co-simulation FMUs, error analysis.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("demo", help="the main job: motion -> accelerometer array -> solve "
                       "via cffi and via the FMUs (fmpy) -> agreement, errors, analysis, plot")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_demo"),
                   help="folder for the figure (default: ./gfins_demo)")
    p.add_argument("--duration", type=float, default=60.0, help="record length, s (default 60)")
    p.add_argument("--dt", type=float, default=0.01, help="sampling interval, s (default 0.01)")
    p.add_argument("--lever-arm", type=float, default=0.1, help="lever arm l, m (default 0.1)")
    p.add_argument("--noise", type=float, default=1e-4,
                   help="white noise per accelerometer, m/s^2 (default 1e-4)")
    p.set_defaults(func=_demo)

    p = sub.add_parser("solve9", help="solve a CSV record of 9 accelerometer outputs "
                       "(m/s^2; optional leading time column) and write the solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--dt", type=float, required=True, help="sampling interval, s")
    p.add_argument("--lever-arm", type=float, required=True, help="lever arm l, m")
    p.add_argument("--omega-init", default="0,0,0",
                   help="rate at the first sample, rad/s, as x,y,z: the first signs and the start "
                        "of the omega_dot integral that gives the later signs")
    p.set_defaults(func=_solve9)

    p = sub.add_parser("navigate", help="strapdown navigation of a CSV record "
                       "(t, gyro x y z, accel x y z [, h_ext]) -> solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--input-kind", choices=["increments", "rates"], default="increments",
                   help="increments: rad and m/s over (t_(k-1), t_k]; rates: rad/s and m/s^2 at t_k")
    p.add_argument("--header", action="store_true", help="the CSV's first line is a header")
    _initial_state_args(p)
    p.add_argument("--t0", type=float, default=None,
                   help="time of the initial state, s (default: one interval before the first "
                        "increment, or the first rate sample)")
    p.add_argument("--no-coning", action="store_true", help="one-sample algorithm")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar (default: on for records of 10^6 samples or more)")
    p.set_defaults(func=_navigate)

    p = sub.add_parser("gfnav", help="gyro-free navigation of a CSV record of accelerometer-array "
                       "outputs (t, A1..AN [, h_ext]) -> solution CSV")
    p.add_argument("input", type=pathlib.Path)
    p.add_argument("output", type=pathlib.Path)
    p.add_argument("--layout", choices=["cube6", "qin9", "12"], required=True)
    p.add_argument("--lever-arm", type=float, required=True, help="lever arm l, m")
    p.add_argument("--strategy", choices=["integrate", "sqrt", "eigen", "fused"],
                   default="integrate", help="angular-rate strategy (default integrate)")
    p.add_argument("--accel-noise", type=float, default=1e-4,
                   help="accelerometer white-noise std, m/s^2 (fused strategy)")
    p.add_argument("--omega-init", default="0,0,0",
                   help="rate at the first sample, rad/s, x,y,z (write --omega-init=-1,0,0 "
                        "when it starts with -)")
    p.add_argument("--header", action="store_true", help="the CSV's first line is a header")
    _initial_state_args(p)
    p.set_defaults(func=_gfnav)

    p = sub.add_parser("reproduce", help="reproduce a published experiment (qin: the 6- vs "
                       "9-accelerometer comparison of seed 000, as a Monte Carlo)")
    p.add_argument("experiment", choices=["qin"])
    p.add_argument("--runs", type=int, default=100, help="Monte-Carlo runs (default 100)")
    p.add_argument("--seed", type=int, default=2008, help="random seed (default 2008)")
    p.add_argument("--drift-signs", choices=["random", "equal"], default="random",
                   help="signs of the 1.5e-5 m/s^2 drifts (default: random per sensor and run)")
    p.add_argument("--gravity", type=float, default=9.8,
                   help="gravity of the fixed frame, m/s^2 (default 9.8; 0: gravity-free)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_reproduce"),
                   help="folder for the figure and the table")
    p.set_defaults(func=_reproduce)

    p = sub.add_parser("analyze", help="error growth: python-control predictions against a "
                       "Monte Carlo of the C core, as a markdown report with figures")
    p.add_argument("--config", action="append",
                   choices=["sins", "cube6", "qin9", "12", "qin9-sqrt", "12-sqrt", "qin9-fused", "12-fused"],
                   help="configuration (repeatable; default: all); see gfins_fmi.error_report")
    p.add_argument("--runs", type=int, default=1000, help="Monte-Carlo runs per configuration (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_analysis"),
                   help="folder for report.md and the figures")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_analyze)

    p = sub.add_parser("cosim", help="vehicle FMU + navigator FMU co-simulation (seed 001's run): "
                       "Python master, SSP file and container FMU, each checked against cffi")
    p.add_argument("--navigator", choices=["gfnav_qin9", "gfnav_cube6", "gfnav_12", "sins"],
                   default="gfnav_qin9")
    p.add_argument("--seconds", type=float, default=600.0, help="stop time, s (default 600)")
    p.add_argument("--step", type=float, default=0.01, help="communication step, s (default 0.01)")
    p.add_argument("--align", type=float, default=60.0, help="rest before the run, s (default 60)")
    p.add_argument("--fmi", type=int, choices=[2, 3], default=3, help="FMI version of the master run")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("gfins_cosim"),
                   help="folder for the SSP, the container FMU and the error CSV")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cosim)

    from gfins_fmi.estimation import cli as estimation_cli
    estimation_cli.add_parser(sub)

    p = sub.add_parser("validate", help="run fmpy's validation on every shipped FMU")
    p.set_defaults(func=_validate)
    p = sub.add_parser("info", help="version and paths of the shipped FMUs")
    p.set_defaults(func=_info)

    args = parser.parse_args(argv)
    from gfins_fmi._lib import GfinsError
    try:
        return args.func(args)
    except (ValueError, TypeError, OSError, GfinsError) as exc:
        print(f"gfins {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
