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


class _TimeColumn:
    """Checks a record's time column (s) as the record streams, chunk by chunk: finite
    and strictly increasing (across chunks too); intervals longer than 1.5 times the
    typical one are gaps. The typical interval is the median of the first chunk's
    intervals (the whole record when it fits in one chunk). ``fixed``: the solver needs
    one sampling interval, so gaps and intervals off the typical one by more than
    ``_UNIFORM_RTOL`` are errors; the interval :attr:`dt` is the first chunk's mean
    interval, or ``dt_option`` (``--dt``), which must agree with it.

    :meth:`check` raises ValueError naming the row (data rows counted from 0); the gaps
    of a record that may have them are reported by :meth:`notes`.
    """

    def __init__(self, source, fixed: bool, dt_option: float | None = None):
        self.source, self.fixed, self.dt_option = source, fixed, dt_option
        self.dt = dt_option
        self.typical = None
        self._last = None
        self._gaps: list[str] = []
        self._n_gaps = 0

    def _gap_text(self, n: int, listed: list[str]) -> str:
        more = f"; and {n - len(listed)} more" if n > len(listed) else ""
        return f"{n} gap{'s' if n > 1 else ''} in the time column: {'; '.join(listed)}{more}"

    def check(self, t, start: int) -> None:
        """Check the times ``t`` of the rows from ``start`` on."""
        import numpy as np
        source = self.source
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            k = int(bad[0])
            raise ValueError(f"{source}: row {start + k}: time {t[k]:g} s is not finite")
        # the interval from the previous chunk's last time is checked with this chunk's
        tt, first = (t, start) if self._last is None else (np.r_[self._last, t], start - 1)
        d = np.diff(tt)
        bad = np.flatnonzero(~(d > 0))
        if bad.size:
            k = int(bad[0]) + 1
            raise ValueError(f"{source}: row {first + k}: time {tt[k]:.10g} s does not increase "
                             f"(previous {tt[k - 1]:.10g} s); the time column must increase strictly")
        self._last = float(t[-1])
        if self.typical is None:
            if d.size == 0:       # a record of one sample
                if self.dt_option is None and self.fixed:
                    raise ValueError(f"{source}: one sample: give --dt, the sampling interval")
                return
            self.typical = float(np.median(d))
        typical = self.typical
        gaps = np.flatnonzero(d > 1.5 * typical) + 1
        if gaps.size:
            listed = [f"row {first + k} (t = {tt[k - 1]:.10g} -> {tt[k]:.10g} s, "
                      f"{round((tt[k] - tt[k - 1]) / typical)} intervals of {typical:g} s)"
                      for k in gaps[:3]]
            if self.fixed:
                raise ValueError(f"{source}: {self._gap_text(int(gaps.size), listed)}: a "
                                 f"fixed-interval solver cannot bridge "
                                 f"{'it' if gaps.size == 1 else 'them'}; split the record there")
            self._gaps += listed[:3 - len(self._gaps)]
            self._n_gaps += int(gaps.size)
        if not self.fixed:
            return
        off = np.flatnonzero(np.abs(d - typical) > _UNIFORM_RTOL * typical)
        if off.size:
            k = int(off[0]) + 1
            raise ValueError(f"{source}: the time column is not uniform: row {first + k} "
                             f"(interval {d[k - 1]:.6g} s against {typical:.6g} s); the solver needs "
                             "a fixed sampling interval")
        if start == 0:
            dt = float((t[-1] - t[0]) / (t.size - 1))
            if self.dt_option is not None:
                if abs(self.dt_option - dt) > _UNIFORM_RTOL * dt:
                    raise ValueError(f"{source}: --dt {self.dt_option:g} s disagrees with the time "
                                     f"column (interval {dt:.6g} s)")
                dt = self.dt_option
            self.dt = dt

    def notes(self) -> list[str]:
        """The gaps found (a record that may have them), as one line."""
        return [self._gap_text(self._n_gaps, self._gaps)] if self._n_gaps else []


#: what a CSV whose first line is a header is told
_HEADER_HINT = "if it is a line of column names, give --header"
#: the navigation solution's columns (position geodetic: the commands navigate on WGS-84)
_NAV_COLUMNS = ("t_s", "lat_deg", "lon_deg", "h_m", "v_e_m_s", "v_n_m_s", "v_u_m_s",
                "heading_deg", "pitch_deg", "roll_deg", "q0", "q1", "q2", "q3")
#: progress bars by default from this input size on: 10^6 samples (binary), or about as
#: many lines of text
_PROGRESS_ROWS, _PROGRESS_BYTES = 1_000_000, 64 << 20


class _Refused(Exception):
    """The solver refused a sample: ``error`` (with ``.partial``) and the output
    columns of the ``rows`` before it in the chunk."""

    def __init__(self, error: Exception, columns: list, rows: int):
        super().__init__(str(error))
        self.error, self.columns, self.rows = error, columns, rows


def _reader(args, what: str):
    from gfins_fmi.io.tables import TableReader
    return TableReader(args.input, header=args.header, chunk_rows=args.chunk, what=what,
                       header_hint=_HEADER_HINT)


def _stream(args, reader, names, dtypes, solve, verb: str, group: int = 1) -> tuple[int, int]:
    """Read, solve and write a record chunk by chunk: ``solve(start, block)`` gives the
    output columns of the rows of ``block`` (the first is row ``start``) or raises
    :class:`_Refused`. The output is written beside ``args.output`` and renamed into
    place at the end; after a refused sample it holds the rows before it, and when
    there is none, it is not written (an existing file stays as it was).

    Returns (status, rows written): status 0, or 1 after a refused sample. ``group``:
    input rows per output row (the last output row takes the rows left).
    """
    from gfins_fmi.io.tables import TableWriter
    status, error = 0, None
    with reader, TableWriter(args.output, names, dtypes,
                             rows=None if reader.n_rows is None else -(-reader.n_rows // group)) as writer, \
            _progress(args, reader, verb) as bar:
        for start, block in reader:
            try:
                cols = solve(start, block)
            except _Refused as refused:
                if refused.rows:
                    writer.write(refused.columns)
                status, error = 1, refused.error
                break
            writer.write(cols)
            bar.update(reader.position - bar.n)
            bar.set_postfix_str(f"{writer.rows} samples")
        else:
            bar.update(reader.size - bar.n)     # trailing comment lines, if any
        if status and writer.rows == 0:
            kept = "left as it was" if args.output.exists() else "not written"
            print(f"error: {error}; no sample was {verb}: {args.output} {kept}", file=sys.stderr)
            writer.discard()
            return status, 0
        if status:
            print(f"error: {error}; writing the {writer.rows} samples {verb} before it",
                  file=sys.stderr)
        writer.commit()
    return status, writer.rows


class _NoBar:
    n = 0

    def update(self, n) -> None:
        pass

    def set_postfix_str(self, text) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass


def _progress(args, reader, verb: str):
    """One bar over the input (bytes of text, rows of a binary table): it advances when
    a chunk has been read, solved and written."""
    big = reader.size >= (_PROGRESS_BYTES if reader.unit == "B" else _PROGRESS_ROWS)
    if not (args.progress if args.progress is not None else big):
        return _NoBar()
    from tqdm import tqdm
    text = reader.unit == "B"
    return tqdm(total=reader.size, unit="B" if text else " samples", unit_scale=True,
                unit_divisor=1024 if text else 1000, desc=f"read, {verb[:-1]}, write")


def _nav_columns(sol) -> list:
    """The columns of :data:`_NAV_COLUMNS` from a NavSolution: time, latitude and
    longitude (deg), height (m), ENU velocity (m/s), Euler angles (deg), quaternion."""
    import numpy as np
    deg = 180.0 / np.pi
    e = sol.euler_rad * deg if len(sol) else np.empty((0, 3))
    return ([sol.t_s, sol.lat_rad * deg, sol.lon_rad * deg, sol.h_m]
            + [sol.v_n_m_s[:, j] for j in range(3)] + [e[:, j] for j in range(3)]
            + [sol.q_bn[:, j] for j in range(4)])


def _navigate(args) -> int:
    import numpy as np
    from gfins_fmi import NavState, SinsConfig, Strapdown
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    N = args.subsamples
    if N > 1:   # chunks of a multiple of N keep the groups of the whole record
        args.chunk = -(-args.chunk // N) * N
    reader = _reader(args, "strapdown record")
    if reader.n_columns not in (7, 8):
        raise ValueError(f"{args.input}: expected 7 or 8 columns (t, gyro x y z, accel x y z "
                         f"[, h_ext]); found {reader.n_columns}")
    has_h = reader.n_columns == 8
    if args.vertical == "baro" and not has_h:
        raise ValueError("--vertical baro needs the external height as an 8th column (h_ext, m)")
    times = _TimeColumn(args.input, fixed=False)
    deg = np.pi / 180
    cfg = SinsConfig(input=args.input_kind, coning=not args.no_coning, vertical=args.vertical,
                     baro_tau_s=args.baro_tau, subsamples=args.subsamples)
    if args.subsamples > 1 and args.input_kind != "increments":
        raise ValueError(f"--subsamples {args.subsamples} needs --input-kind increments (rate "
                         "samples are navigated one update per sample)")
    nav = None

    def solve(start, block):
        nonlocal nav
        t = block[:, 0]
        times.check(t, start)
        if nav is None:
            if args.input_kind == "increments":
                if len(t) < 2 and args.t0 is None:
                    raise ValueError("a record of one increment needs --t0 (the time its "
                                     "interval starts)")
                # row k is the increment over (t_(k-1), t_k]; the navigator starts one
                # interval before the first row unless --t0 says otherwise
                t0 = args.t0 if args.t0 is not None else t[0] - (t[1] - t[0])
            else:
                t0 = args.t0 if args.t0 is not None else t[0]
            x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg],
                                     args.v0, args.lat0 * deg, args.lon0 * deg, args.h0, t0)
            nav = Strapdown(x0, cfg)
        try:
            sol = nav.run(block[:, 1:4], block[:, 4:7], t_s=t,
                          h_ext_m=block[:, 7] if has_h else None, start_index=start)
        except (NonFiniteInputError, SampleError) as exc:
            raise _Refused(exc, _nav_columns(exc.partial), len(exc.partial)) from None
        return _nav_columns(sol)

    status, rows = _stream(args, reader, _NAV_COLUMNS, None, solve, "navigated", group=N)
    for note in times.notes():   # the navigator takes any intervals; a gap is worth knowing about
        print(f"note: {note}", file=sys.stderr)
    if rows:
        what = f"{rows} samples" if N == 1 else f"{rows} updates of {N} samples"
        print(f"{what} navigated -> {args.output}")
    return status


_RATE_COLUMNS = ("omega_x_rad_s", "omega_y_rad_s", "omega_z_rad_s", "f_x_m_s2", "f_y_m_s2",
                 "f_z_m_s2", "flags")


def _gfnav(args) -> int:
    import numpy as np
    from gfins_fmi import GyroFreeNavigator, NavState, SinsConfig, layout
    from gfins_fmi._lib import NonFiniteInputError
    from gfins_fmi.sins import SampleError
    g = layout(args.layout, args.lever_arm)
    n = g.n_sensors
    reader = _reader(args, "accelerometer-array record")
    if reader.n_columns not in (n + 1, n + 2):
        raise ValueError(f"{args.input}: layout {args.layout} needs {n + 1} or {n + 2} columns "
                         f"(t, A1..A{n} [, h_ext]); found {reader.n_columns}")
    has_h = reader.n_columns == n + 2
    if args.vertical == "baro" and not has_h:
        raise ValueError(f"--vertical baro needs the external height as column {n + 2}")
    times = _TimeColumn(args.input, fixed=True)
    deg = np.pi / 180
    nav = None

    def columns(t, sol, rates):
        # the record's own times (the navigator's clock is t0 + k dt, which differs from
        # them in the last digits): an output row joins its input row on t
        cols = _nav_columns(sol)
        cols[0] = t[:len(sol)]
        return (cols + [rates.omega_rad_s[:, j] for j in range(3)]
                + [rates.f_m_s2[:, j] for j in range(3)] + [rates.flags])

    def solve(start, block):
        nonlocal nav
        t = block[:, 0]
        if start == 0 and len(t) < 2:
            raise ValueError(f"{args.input}: the record needs at least two samples (the "
                             "interval comes from its time column)")
        times.check(t, start)
        if nav is None:
            x0 = NavState.from_euler([args.heading0 * deg, args.pitch0 * deg, args.roll0 * deg],
                                     args.v0, args.lat0 * deg, args.lon0 * deg, args.h0, float(t[0]))
            nav = GyroFreeNavigator(g, x0, args.strategy, args.omega_init,
                                    accel_noise_m_s2=args.accel_noise,
                                    sins=SinsConfig(vertical=args.vertical, baro_tau_s=args.baro_tau))
        try:
            sol, rates = nav.run(block[:, 1:n + 1], times.dt,
                                 h_ext_m=block[:, n + 1] if has_h else None, start_index=start)
        except (NonFiniteInputError, SampleError) as exc:
            raise _Refused(exc, columns(t, exc.partial, exc.partial_rates), len(exc.partial)) from None
        return columns(t, sol, rates)

    status, rows = _stream(args, reader, _NAV_COLUMNS + _RATE_COLUMNS,
                           [np.float64] * (len(_NAV_COLUMNS) + 6) + [np.uint8], solve, "navigated")
    if rows:
        print(f"{rows} samples navigated -> {args.output}")
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
    from gfins_fmi.montecarlo import executor
    with executor(args.scheduler, args.workers) as ex:
        res = R.run_qin(runs=args.runs, seed=args.seed, progress=True,
                        drift_signs=args.drift_signs,
                        scenario=R.QinScenario(gravity_m_s2=args.gravity), executor=ex)
    table = R.qin_table(res)
    print("\nErrors at t = 60 s\n" + table)
    mech = R.mechanization_table(R.mechanization_error(R.QinScenario(gravity_m_s2=args.gravity)))
    print("\nthe navigator's own part (exact outputs, no noise or drift), at 60 s:\n" + mech)
    imp = R.improvement(res)
    print(f"\nimprovement of 9 over 6 (median |error|): attitude "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["att"]) + "; position "
          + ", ".join(f"{100 * v:.2f}%" for v in imp["pos"]))
    rates = R.rate_strategy_table(progress=False)
    print("\nangular-rate RMS error of the 9-accelerometer strategies (rad/s, median of 20 runs):")
    for case, row in rates.items():
        print(f"  {case:40s} " + "  ".join(f"{k} {v:.3g}" for k, v in row.items()))
    png = R.qin_plot(res, args.out / "qin_errors.png")
    (args.out / "qin_table.md").write_text(table + "\n\n" + mech + "\n", encoding="utf-8")
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
    from gfins_fmi.montecarlo import executor
    configs = args.config or list(CONFIGS)
    with executor(args.scheduler, args.workers) as ex:
        path = write_report(args.out, configs, runs=args.runs, seed=args.seed, executor=ex,
                            progress=not args.quiet)
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
    integrated = args.navigator == "ins_gnss"
    print(f"vehicle + {args.navigator}, {args.seconds:g} s at {1 / args.step:g} Hz"
          + (" (GNSS 1 Hz 0.37 s off the grid, 0.1 s latency, out 300-360 s; barometer, "
             "odometer; tactical IMU)" if integrated else ""))
    print(f"  navigation error: horizontal max {e['horizontal_m'].max():.4g} m (final "
          f"{e['horizontal_m'][-1]:.4g} m), velocity max {e['velocity_m_s'].max():.3g} m/s, "
          f"attitude max {np.degrees(np.linalg.norm(e['attitude_rad'], axis=1).max()):.3g} deg")
    names = {"master": f"Python master (FMI {args.fmi}.0)", "ssp": "fmpy SSP simulator",
             "container": "fmpy container FMU (FMI 2.0)"}
    reference = "the batch API (IntegratedNavigator.run)" if integrated else "the cffi navigator"
    for runner, r in res.items():
        where = f" {r['path']}" if r["path"] else ""
        print(f"  {names[runner]}{where}: {r['wall_s']:.1f} s; vs {reference} on the "
              f"same sensor data |dlat| {r['diff']['lat_rad']:.3g} rad, |dv| "
              f"{r['diff']['v_m_s']:.3g} m/s"
              + (f", |dq| {r['diff']['q']:.3g}, |dstd| {r['diff']['std']:.3g}" if integrated else ""))
    np.savetxt(out / "cosim_errors.csv", np.c_[e["t_s"], e["horizontal_m"], e["velocity_m_s"],
                                               np.linalg.norm(e["attitude_rad"], axis=1)],
               delimiter=",",
               header="t_s,horizontal_error_m,velocity_error_m_s,attitude_error_rad", comments="")
    print(f"  errors -> {out / 'cosim_errors.csv'}")
    ok = all(max(r["diff"].values()) == 0.0 for r in res.values())
    print("cosim " + (f"passed: every co-simulation equals {reference} bit for bit"
                      if ok else f"FAILED: a co-simulation differs from {reference}"))
    return 0 if ok else 1


def _info(args) -> int:
    import gfins_fmi
    from gfins_fmi.fmu import MODELS, fmu_path
    print(f"gfins_fmi {gfins_fmi.__version__}")
    for model in MODELS:
        for version in (2, 3):
            print(f"  FMU {model} (FMI {version}.0): {fmu_path(model, version)}")
    return 0


_ACCEL9_COLUMNS = ("t_s", "f_x_m_s2", "f_y_m_s2", "f_z_m_s2", "omega_x_rad_s", "omega_y_rad_s",
                   "omega_z_rad_s", "omega_dot_x_rad_s2", "omega_dot_y_rad_s2", "omega_dot_z_rad_s2",
                   "omega_sq_x_rad2_s2", "omega_sq_y_rad2_s2", "omega_sq_z_rad2_s2", "flags")


def _solve9(args) -> int:
    import numpy as np
    from gfins_fmi import Accel9Solver
    from gfins_fmi._lib import NonFiniteInputError, SampleError
    reader = _reader(args, "9-accelerometer record")
    if reader.n_columns not in (9, 10):
        raise ValueError(f"{args.input}: expected 9 columns (A1..A9, m/s^2) or 10 (t, A1..A9); "
                         f"found {reader.n_columns}")
    timed = reader.n_columns == 10   # a leading time column: the interval and the output times
    if not timed and args.dt is None:
        raise ValueError(f"{args.input} has no time column: give --dt, the sampling interval")
    times = _TimeColumn(args.input, fixed=True, dt_option=args.dt)
    solver = Accel9Solver(args.lever_arm, args.omega_init)
    flags: dict[str, int] = {}

    def columns(t, sol):
        for name, count in sol.flag_counts().items():
            flags[name] = flags.get(name, 0) + count
        return ([t[:len(sol)]] + [a[:, j] for a in (sol.f_m_s2, sol.omega_rad_s,
                                                    sol.omega_dot_rad_s2, sol.omega_sq_rad2_s2)
                                  for j in range(3)] + [sol.flags])

    def solve(start, block):
        if timed:
            t, A = block[:, 0], block[:, 1:]
            times.check(t, start)
        else:
            A = block
            t = (start + np.arange(len(A))) * times.dt
        try:
            sol = solver.solve(A, times.dt, start_index=start)
        except (NonFiniteInputError, SampleError) as exc:
            raise _Refused(exc, columns(t, exc.partial), len(exc.partial)) from None
        return columns(t, sol)

    status, rows = _stream(args, reader, _ACCEL9_COLUMNS, [np.float64] * 13 + [np.uint8], solve,
                           "solved")
    if rows:
        print(f"{rows} samples solved -> {args.output}; flags: {flags}")
    return status


def executor_arguments(p) -> None:
    """--scheduler and --workers: where a Monte Carlo runs (gfins_fmi.montecarlo.executor);
    shared by the commands and the bench studies."""
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the Monte-Carlo runs on a dask.distributed cluster: its "
                        "scheduler's address, e.g. tcp://10.0.0.5:8786 (needs "
                        "'gfins_fmi[dask]'; results equal a local run with the same seed)")
    p.add_argument("--workers", type=_option_count(1), default=None,
                   help="without --scheduler: threads on this machine (default: one per "
                        "CPU); with it: wait for this many cluster workers")


def _record_args(p, what: str) -> None:
    """Input, output and streaming options, shared by the record commands."""
    p.add_argument("input", type=pathlib.Path,
                   help=f"{what}: CSV text (comma-separated, '#' comments), .parquet or .npz")
    p.add_argument("output", type=pathlib.Path,
                   help="solution file: CSV text unless it ends in .parquet or .npz; written "
                        "beside its name and renamed into place when complete")
    p.add_argument("--header", action="store_true",
                   help="the CSV's first line (after '#' comments) is a line of column names")
    p.add_argument("--chunk", type=_option_count(2), default=1 << 18, metavar="SAMPLES",
                   help="samples read, solved and written at a time (default 262144); memory "
                        "grows with it")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="progress bar over reading, solving and writing (default: on for "
                        "inputs of 10^6 samples, or 64 MiB of text, or more)")


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
        "solve9", help="solve a record of 9 accelerometer outputs (m/s^2; optional "
        "leading time column) and write the solution (CSV, Parquet or npz)")
    _record_args(p, "accelerometer outputs A1..A9 (m/s^2), optionally after a time column (s)")
    p.add_argument("--dt", type=seconds, default=None,
                   help="sampling interval, s (default: from the time column, which it must "
                        "agree with when both are given)")
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--omega-init", type=_option_vector3("x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, as x,y,z: the first signs and the start "
                        "of the omega_dot integral that gives the later signs")
    p.set_defaults(func=_solve9)

    p = parsers["navigate"] = sub.add_parser(
        "navigate", help="strapdown navigation of a record (t, gyro x y z, accel x y z "
        "[, h_ext]) -> solution (CSV, Parquet or npz)")
    _record_args(p, "t (s), gyro x y z, accel x y z [, h_ext (m)]")
    p.add_argument("--input-kind", choices=["increments", "rates"], default="increments",
                   help="increments: rad and m/s over (t_(k-1), t_k]; rates: rad/s and m/s^2 at t_k")
    _initial_state_args(p)
    p.add_argument("--t0", type=_option_real("s"), default=None,
                   help="time of the initial state, s (default: one interval before the first "
                        "increment, or the first rate sample)")
    p.add_argument("--no-coning", action="store_true", help="one-sample algorithm")
    p.add_argument("--subsamples", type=int, choices=[1, 2, 3, 4], default=1, metavar="N",
                   help="increments per navigation update, 1..4 (default 1); N > 1 writes one "
                        "row per update (every N-th increment's time; the last row takes the "
                        "increments left)")
    p.set_defaults(func=_navigate)

    p = parsers["gfnav"] = sub.add_parser(
        "gfnav", help="gyro-free navigation of a record of accelerometer-array outputs "
        "(t, A1..AN [, h_ext]) at a fixed interval -> solution (CSV, Parquet or npz)")
    _record_args(p, "t (s), A1..AN (m/s^2) [, h_ext (m)]")
    p.add_argument("--layout", choices=["cube6", "qin9", "12"], required=True)
    p.add_argument("--lever-arm", type=lever_arm, required=True, help="lever arm l, m")
    p.add_argument("--strategy", choices=["integrate", "sqrt", "eigen", "fused"],
                   default="integrate", help="angular-rate strategy (default integrate)")
    p.add_argument("--accel-noise", type=_option_real("m/s^2", above=0.0), default=1e-4,
                   help="accelerometer white-noise std, m/s^2 (fused strategy)")
    p.add_argument("--omega-init", type=_option_vector3("x,y,z in rad/s"), default=[0.0, 0.0, 0.0],
                   help="rate at the first sample, rad/s, x,y,z (write --omega-init=-1,0,0 "
                        "when it starts with -)")
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
    executor_arguments(p)
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
    executor_arguments(p)
    p.set_defaults(func=_analyze)

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
    p.set_defaults(func=_cosim, check=_check_cosim)

    from gfins_fmi.estimation import cli as estimation_cli
    parsers["integrate"] = estimation_cli.add_parser(sub)
    from gfins_fmi.estimation import calibrate_cli
    parsers["calibrate"] = calibrate_cli.add_parser(sub)
    from gfins_fmi.estimation import align_cli
    parsers["align"] = align_cli.add_parser(sub)

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
    except (ValueError, TypeError, OSError, ImportError, GfinsError) as exc:
        print(f"gfins {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # the record commands write beside the output's name and rename when complete
        kept = f"; {args.output} left as it was" if getattr(args, "output", None) else ""
        print(f"gfins {args.command}: interrupted{kept}", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
