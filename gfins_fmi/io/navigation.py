"""Navigation records as tables: the solutions our commands write (``gfins navigate``,
``gfins integrate``: their first columns are :data:`~gfins_fmi.io.columns.NAV_SOLUTION`,
degrees) or a :class:`~gfins_fmi.io.records.TruthRecord` CSV (radians), read into a
TruthRecord with, when the table has them, the body's angular rate (``omega_x_rad_s``,
``omega_y_rad_s``, ``omega_z_rad_s``: w_ib^b, body axes) — what a master INS reports for
transfer alignment. CSV with a header line, npz or Parquet (:class:`TableReader`).
"""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi.io.columns import NAV_SOLUTION, RATE_COLUMNS
from gfins_fmi.io.errors import FileFormatError
from gfins_fmi.io.records import TruthRecord
from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.tables import TableReader

__all__ = ["read_navigation", "write_navigation", "NAV_RATE_COLUMNS"]

#: the body's angular rate w_ib^b (rad/s, body axes) beside a navigation solution
NAV_RATE_COLUMNS = RATE_COLUMNS[:3]
_RAD_COLUMNS = ("t_s", "lat_rad", "lon_rad", "h_m", "v_e_m_s", "v_n_m_s", "v_u_m_s", "heading_rad",
                "pitch_rad", "roll_rad")


def read_navigation(path) -> tuple[TruthRecord, np.ndarray | None]:
    """A navigation table as (TruthRecord, rates (n, 3) rad/s or None).

    The table needs the columns of :data:`~gfins_fmi.io.columns.NAV_SOLUTION` (degrees:
    our commands' solutions) or of a TruthRecord CSV (radians), by name, in any order
    among others; the rate columns :data:`NAV_RATE_COLUMNS` are optional (all three or
    none). Raises FileFormatError naming what is missing."""
    path = pathlib.Path(path)
    with TableReader(path, header=True, what="navigation record",
                     header_hint="a navigation table starts with a line of column names") as rd:
        names = rd.names
        if not names:
            raise FileFormatError(path, None, "no column names: a navigation table starts with a line "
                                  f"of them ({', '.join(NAV_SOLUTION)})")
        blocks = [block for _, block in rd]
    table = np.vstack(blocks) if blocks else np.zeros((0, len(names)))
    col = {n: i for i, n in enumerate(names)}
    if all(n in col for n in NAV_SOLUTION):
        want, deg = NAV_SOLUTION, True
    elif all(n in col for n in _RAD_COLUMNS):
        want, deg = _RAD_COLUMNS, False
    else:
        missing = [n for n in NAV_SOLUTION if n not in col]
        raise FileFormatError(path, None, f"a navigation table needs the columns {', '.join(NAV_SOLUTION)} "
                              f"(degrees) or {', '.join(_RAD_COLUMNS)} (radians); missing "
                              f"{', '.join(missing)} (columns: {', '.join(names)})")
    x = table[:, [col[n] for n in want]]
    k = np.pi / 180.0 if deg else 1.0
    euler = x[:, 7:10] * k
    euler[:, 0] = np.mod(euler[:, 0], 2 * np.pi)
    rec = TruthRecord(x[:, 0], x[:, 1] * k, x[:, 2] * k, x[:, 3], x[:, 4:7], euler, f"navigation table {path.name}")
    have = [n in col for n in NAV_RATE_COLUMNS]
    if any(have) and not all(have):
        raise FileFormatError(path, None, f"the rate columns come together: {', '.join(NAV_RATE_COLUMNS)}")
    rates = table[:, [col[n] for n in NAV_RATE_COLUMNS]] if all(have) else None
    if rates is not None and not np.all(np.isfinite(rates)):
        raise FileFormatError(path, None, "the rate columns hold NaN or Inf")
    return rec, rates


def write_navigation(path, record: TruthRecord, rates=None) -> None:
    """A TruthRecord (and its rates) as our navigation table: NAV_SOLUTION (degrees) and
    the rate columns, written beside its name and renamed when complete."""
    deg = 180.0 / np.pi
    cols = [record.t_s, record.lat_rad * deg, record.lon_rad * deg, record.h_m,
            *record.v_enu_m_s.T, *(record.euler_rad * deg).T]
    names = list(NAV_SOLUTION)
    if rates is not None:
        cols += list(np.asarray(rates, float).T)
        names += list(NAV_RATE_COLUMNS)
    with TableWriter(path, names) as w:
        w.write(cols)
        w.commit()
