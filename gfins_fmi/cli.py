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
             for v in (2, 3))
    print("\ndemo " + ("passed: C core, FMUs and analysis agree" if ok else "FAILED"))
    return 0 if ok else 1


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
                   help="rate before the first sample, rad/s, as x,y,z (gives the first signs)")
    p.set_defaults(func=_solve9)

    p = sub.add_parser("validate", help="run fmpy's validation on every shipped FMU")
    p.set_defaults(func=_validate)
    p = sub.add_parser("info", help="version and paths of the shipped FMUs")
    p.set_defaults(func=_info)

    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, TypeError, OSError) as exc:
        print(f"gfins {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
