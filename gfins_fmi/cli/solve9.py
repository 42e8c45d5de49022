"""``gfins solve9``: a record of 9 accelerometer outputs (m/s^2; optional leading time
column) through the 9-accelerometer solver of seed 000, streamed -> the solution table."""
from __future__ import annotations

import numpy as np

from gfins_fmi._lib import NonFiniteInputError, SampleError
from gfins_fmi.cli.files import Refused, TimeColumn, outputs, record_reader, stream
from gfins_fmi.gyrofree.array import Accel9Solver
from gfins_fmi.io.columns import ACCEL9_COLUMNS

__all__ = ["run"]


def run(args) -> int:
    with outputs(args.input) as outs:
        outs.claim(args.output)
        return _run(args, outs)


def _run(args, outs) -> int:
    reader = record_reader(args, "9-accelerometer record")
    if reader.n_columns not in (9, 10):
        raise ValueError(f"{args.input}: expected 9 columns (A1..A9, m/s^2) or 10 (t, A1..A9); "
                         f"found {reader.n_columns}")
    timed = reader.n_columns == 10   # a leading time column: the interval and the output times
    if not timed and args.dt is None:
        raise ValueError(f"{args.input} has no time column: give --dt, the sampling interval")
    times = TimeColumn(args.input, fixed=True, dt_option=args.dt)
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
            raise Refused(exc, columns(t, exc.partial), len(exc.partial)) from None
        return columns(t, sol)

    status, rows = stream(args, outs, reader, ACCEL9_COLUMNS, [np.float64] * 13 + [np.uint8], solve,
                          "solved")
    if status == 0:
        print(f"{rows} samples solved -> {args.output}; flags: {flags}")
    return status
