"""``gfins navigate``: strapdown navigation of a record (t, gyro x y z, accel x y z
[, h_ext]) of increments or rates, streamed chunk by chunk -> the solution table."""
from __future__ import annotations

import sys

import numpy as np

from gfins_fmi._lib import NonFiniteInputError, SampleError
from gfins_fmi.cli.files import Refused, TimeColumn, compensated_block, nav_columns, outputs, record_reader, stream
from gfins_fmi.cli.initial import from_state_options
from gfins_fmi.estimation.noise_file import read_imu_errors
from gfins_fmi.io.columns import NAV_COLUMNS
from gfins_fmi.nav.plausibility import report, specific_force_problem
from gfins_fmi.nav.strapdown import SinsConfig, Strapdown

__all__ = ["run"]


def run(args) -> int:
    with outputs(args.input) as outs:
        outs.claim(args.output)
        return _run(args, outs)


def _run(args, outs) -> int:
    N = args.subsamples
    if N > 1:   # chunks of a multiple of N keep the groups of the whole record
        args.chunk = -(-args.chunk // N) * N
    reader = record_reader(args, "strapdown record")
    if reader.n_columns not in (7, 8):
        raise ValueError(f"{args.input}: expected 7 or 8 columns (t, gyro x y z, accel x y z "
                         f"[, h_ext]); found {reader.n_columns}")
    has_h = reader.n_columns == 8
    if args.vertical == "baro" and not has_h:
        raise ValueError("--vertical baro needs the external height as an 8th column (h_ext, m)")
    times = TimeColumn(args.input, fixed=False)
    cfg = SinsConfig(input=args.input_kind, coning=not args.no_coning, vertical=args.vertical,
                     baro_tau_s=args.baro_tau, subsamples=args.subsamples)
    if args.subsamples > 1 and args.input_kind != "increments":
        raise ValueError(f"--subsamples {args.subsamples} needs --input-kind increments (rate "
                         "samples are navigated one update per sample)")
    nav = None
    errors = read_imu_errors(args.imu_errors) if args.imu_errors else None
    t_prev = None

    def solve(start, block):
        nonlocal nav, t_prev
        t = block[:, 0]
        times.check(t, start)
        if errors is not None:   # --imu-errors: the chunk compensated before the navigator
            block = block.copy()
            block[:, 1:4], block[:, 4:7] = compensated_block(errors, t, block[:, 1:4], block[:, 4:7],
                                                             args.input_kind, t_prev)
            t_prev = t[-1]
        if nav is None:
            if args.input_kind == "increments":
                if len(t) < 2 and args.t0 is None:
                    raise ValueError("a record of one increment needs --t0 (the time its "
                                     "interval starts)")
                # row k is the increment over (t_(k-1), t_k]; the navigator starts one
                # interval before the first row unless --t0 says otherwise
                t0 = args.t0 if args.t0 is not None else t[0] - (t[1] - t[0])
                if not t0 < t[0]:
                    raise ValueError(f"--t0 {t0!r} s is not before the record's first time "
                                     f"{float(t[0])!r} s: the first increment covers the interval "
                                     "from --t0 to it; give an earlier --t0 (or leave it out)")
            else:
                t0 = args.t0 if args.t0 is not None else t[0]
                if not t0 <= t[0]:
                    raise ValueError(f"--t0 {t0!r} s is after the record's first time "
                                     f"{float(t[0])!r} s: give --t0 at or before it (or leave "
                                     "it out)")
            nav = Strapdown(from_state_options(args, t0), cfg)
            # the specific force of the first chunk: units, increments against rates, ms
            f = block[:, 4:7] if args.input_kind == "rates" else \
                block[:, 4:7] / np.diff(np.r_[t0, t])[:, None]
            report([specific_force_problem(np.linalg.norm(f, axis=1), str(args.input))], "warn")
        try:
            sol = nav.run(block[:, 1:4], block[:, 4:7], t_s=t,
                          h_ext_m=block[:, 7] if has_h else None, start_index=start)
        except (NonFiniteInputError, SampleError) as exc:
            raise Refused(exc, nav_columns(exc.partial), len(exc.partial)) from None
        return nav_columns(sol)

    status, rows = stream(args, outs, reader, NAV_COLUMNS, None, solve, "navigated", group=N)
    for note in times.notes():   # the navigator takes any intervals; a gap is worth knowing about
        print(f"note: {note}", file=sys.stderr)
    if status == 0:
        what = f"{rows} samples" if N == 1 else f"{rows} updates of {N} samples"
        print(f"{what} navigated -> {args.output}")
    return status
