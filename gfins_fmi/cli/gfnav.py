"""``gfins gfnav``: gyro-free navigation of a record of accelerometer-array outputs
(t, A1..AN [, h_ext]) at a fixed interval, streamed chunk by chunk -> the solution table
with the solved rates."""
from __future__ import annotations

import numpy as np

from gfins_fmi._lib import NonFiniteInputError, SampleError
from gfins_fmi.cli.files import Refused, TimeColumn, nav_columns, outputs, record_reader, stream
from gfins_fmi.cli.initial import from_state_options
from gfins_fmi.gyrofree.geometry import layout
from gfins_fmi.gyrofree.navigator import GyroFreeNavigator
from gfins_fmi.io.columns import NAV_COLUMNS, RATE_COLUMNS
from gfins_fmi.nav.strapdown import SinsConfig

__all__ = ["run"]


def run(args) -> int:
    with outputs(args.input) as outs:
        outs.claim(args.output)
        return _run(args, outs)


def _run(args, outs) -> int:
    g = layout(args.layout, args.lever_arm)
    n = g.n_sensors
    reader = record_reader(args, "accelerometer-array record")
    if reader.n_columns not in (n + 1, n + 2):
        raise ValueError(f"{args.input}: layout {args.layout} needs {n + 1} or {n + 2} columns "
                         f"(t, A1..A{n} [, h_ext]); found {reader.n_columns}")
    has_h = reader.n_columns == n + 2
    if args.vertical == "baro" and not has_h:
        raise ValueError(f"--vertical baro needs the external height as column {n + 2}")
    times = TimeColumn(args.input, fixed=True)
    nav = None

    def columns(t, sol, rates):
        # the record's own times (the navigator's clock is t0 + k dt, which differs from
        # them in the last digits): an output row joins its input row on t
        cols = nav_columns(sol)
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
            nav = GyroFreeNavigator(g, from_state_options(args, float(t[0])), args.strategy, args.omega_init,
                                    accel_noise_m_s2=args.accel_noise,
                                    sins=SinsConfig(vertical=args.vertical, baro_tau_s=args.baro_tau))
        try:
            sol, rates = nav.run(block[:, 1:n + 1], times.dt,
                                 h_ext_m=block[:, n + 1] if has_h else None, start_index=start)
        except (NonFiniteInputError, SampleError) as exc:
            raise Refused(exc, columns(t, exc.partial, exc.partial_rates), len(exc.partial)) from None
        return columns(t, sol, rates)

    status, rows = stream(args, outs, reader, NAV_COLUMNS + RATE_COLUMNS,
                          [np.float64] * (len(NAV_COLUMNS) + 6) + [np.uint8], solve, "navigated")
    if status == 0:
        print(f"{rows} samples navigated -> {args.output}")
    return status
