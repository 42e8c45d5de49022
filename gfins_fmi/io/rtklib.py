"""Reader of RTKLIB solution files (``*.pos``, rnx2rtkp / RTKPOST / RTKNAVI output).

The header's column line (``%  GPST  latitude(deg) longitude(deg) height(m) Q ns sdn(m)
sde(m) sdu(m) sdne(m) sdeu(m) sdun(m) age(s) ratio [vn(m/s) ve(m/s) vu(m/s) sdvn sdve
sdvu sdvne sdveu sdvun]``) names the columns; without it RTKLIB's standard order is
assumed. Times are either a GPST calendar date and time (``2025/08/28 17:30:39.749``)
or a GPS week and seconds of week (``2381 63039.749``); the first epoch line tells
which. Both become GPS seconds since 1980-01-06 00:00:00 GPST.
"""
from __future__ import annotations

import pathlib
import re

import numpy as np

from gfins_fmi.io._text import read_table, record_errors_at_lines
from gfins_fmi.io.conventions import SECONDS_PER_WEEK, gps_seconds_from_calendar
from gfins_fmi.io.errors import FileFormatError, not_a_file
from gfins_fmi.io.records import GnssRecord

__all__ = ["read_rtklib_pos"]

_TIME_SYSTEMS = ("GPST", "UTC", "JST", "BJT")
_POSITION = ["latitude(deg)", "longitude(deg)", "height(m)", "Q", "ns", "sdn(m)", "sde(m)",
             "sdu(m)", "sdne(m)", "sdeu(m)", "sdun(m)", "age(s)", "ratio"]
_VELOCITY = ["vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu", "sdvne", "sdveu", "sdvun"]
_OTHER_FORMS = {"latitude(d'\")": "latitude/longitude in degrees, minutes, seconds",
                "x-ecef(m)": "ECEF x/y/z", "e-baseline(m)": "an east/north/up baseline"}


def _header(path: pathlib.Path, lines: list[str]) -> tuple[str | None, list[str] | None]:
    """(time system, column names after the time) from the '%' lines, or (None, None)."""
    for i, line in enumerate(lines):
        if not line.startswith("%"):
            continue
        if "lat/lon/height=" in line:
            datum = line.split("lat/lon/height=", 1)[1].split(",", 1)[0]
            if "geodetic" in datum or "Tokyo" in datum:
                raise FileFormatError(path, i + 1, f"positions are {datum}: export WGS84 with "
                                      "ellipsoidal heights (RTKLIB: Datum WGS84, Height Ellipsoidal)")
        tokens = line[1:].replace(",", " ").split()
        if tokens and tokens[0] in _TIME_SYSTEMS and len(tokens) > 1:
            for name, form in _OTHER_FORMS.items():
                if name in tokens:
                    raise FileFormatError(path, i + 1, f"the solution is written as {form}: export "
                                          "latitude/longitude/height in degrees (RTKLIB: Solution "
                                          "Format Lat/Lon/Height, ddd.ddddddd)")
            return tokens[0], tokens[1:]
    return None, None


def read_rtklib_pos(path, velocity: bool | None = None) -> GnssRecord:
    """Read an RTKLIB solution file in the latitude/longitude/height form.

    Parameters
    ----------
    path : str or path-like
    velocity : bool, optional
        Read the velocity columns (``vn ve vu`` with ``sdvn sdve sdvu``): None (default)
        when the file has them, True to require them, False to ignore them.

    Returns
    -------
    GnssRecord
        Times in GPS seconds since 1980-01-06 00:00:00 GPST; latitude, longitude in rad
        (from deg), ellipsoidal height (m); standard deviations east, north, up (m) from
        ``sde sdn sdu``; velocity east, north, up (m/s) from ``ve vn vu`` (RTKLIB writes
        north, east, up) with ``sdve sdvn sdvu``; ``quality`` = Q (1 fix, 2 float,
        3 SBAS, 4 DGPS, 5 single, 6 PPP). The covariances (``sdne`` ... , signed square
        roots) and ``ns``, ``age``, ``ratio`` are not kept.

    Raises
    ------
    FileFormatError
        Times not in GPST (UTC or JST need leap seconds: export GPST), positions not in
        WGS-84 latitude/longitude/ellipsoidal height in degrees, an empty file, a line
        that is not an epoch of the header's columns, or a record that breaks
        :class:`GnssRecord`'s contract (NaN, zero standard deviation, times not
        increasing), with the line at fault.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise not_a_file(path, "RTKLIB .pos file")
    raw = path.read_text(encoding="utf-8", errors="replace").splitlines()
    system, names = _header(path, raw)
    if system is not None and system != "GPST":
        raise FileFormatError(path, None, f"times are in {system}: the records need GPS time, "
                              "export the solution with the time system GPST")
    first = next((line for line in raw if line.strip() and not line.startswith("%")), None)
    if first is None:
        raise FileFormatError(path, None, "no epoch lines: the file holds only a header or nothing")
    calendar = "/" in first.split()[0]
    # one numeric table: the calendar date and time become six numbers, separators spaces
    sub = re.compile(r"[/:,;]" if calendar else r"[,;]")
    lines = ["" if line.startswith("%") else sub.sub(" ", line) for line in raw]
    n_time = 6 if calendar else 2
    if names is None:
        widths = [n_time + len(_POSITION), n_time + len(_POSITION) + len(_VELOCITY)]
    else:
        widths = [n_time + len(names)]
    what = "RTKLIB .pos" + (" (date and time counted as 6 fields)" if calendar else "")
    table, line_of = read_table(path, widths, what, lines=lines)
    if names is None:
        names = _POSITION + (_VELOCITY if table.shape[1] == widths[1] else [])
    col = {name: n_time + i for i, name in enumerate(names)}
    missing = [n for n in ("latitude(deg)", "longitude(deg)", "height(m)", "Q", "sdn(m)", "sde(m)",
                           "sdu(m)") if n not in col]
    if missing:
        raise FileFormatError(path, None, f"the header has no column {', '.join(missing)}: not a "
                              "latitude/longitude/height solution of RTKLIB")
    has_vel = all(n in col for n in ("vn(m/s)", "ve(m/s)", "vu(m/s)", "sdvn", "sdve", "sdvu"))
    if velocity and not has_vel:
        raise FileFormatError(path, None, "velocity=True but the file has no velocity columns "
                              "(RTKLIB: Output Velocity On)")
    if calendar:
        t = gps_seconds_from_calendar(*(table[:, k] for k in range(6)))
    else:
        t = table[:, 0] * SECONDS_PER_WEEK + table[:, 1]
    c = [col[n] for n in ("sde(m)", "sdn(m)", "sdu(m)")]
    vel = vstd = None
    if has_vel and velocity is not False:
        vel = table[:, [col["ve(m/s)"], col["vn(m/s)"], col["vu(m/s)"]]]
        vstd = table[:, [col["sdve"], col["sdvn"], col["sdvu"]]]
    form = "GPST calendar" if calendar else "GPST week/seconds"
    with record_errors_at_lines(path, line_of):
        return GnssRecord(t, np.radians(table[:, col["latitude(deg)"]]),
                          np.radians(table[:, col["longitude(deg)"]]), table[:, col["height(m)"]],
                          table[:, c], vel, vstd, table[:, col["Q"]],
                          f"RTKLIB pos file {path.name}: {form} -> GPS seconds since 1980-01-06, "
                          "NEU -> ENU, deg -> rad")
