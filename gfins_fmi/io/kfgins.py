"""Readers of the KF-GINS file formats (i2Nav-WHU/KF-GINS, its README "Data format";
the same formats as i2Nav-WHU/awesome-gins-datasets).

KF-GINS's frames: IMU (body) forward-right-down, navigation north-east-down, attitude
roll, pitch, yaw with C_b^n = Rz(yaw) Ry(pitch) Rx(roll) (ZYX). Its times are GPS
seconds of week. The readers convert to ours (body right-front-up, navigation
east-north-up, radians; :mod:`gfins_fmi.io.conventions`) and keep the times as seconds
of week unless ``gps_week`` is given, which makes them GPS seconds since 1980-01-06
(``week * 604800 + seconds of week``, the scale of :func:`~gfins_fmi.io.read_rtklib_pos`).

Fields may be separated by spaces, tabs or commas, as KF-GINS's own loader accepts.
"""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi.io._text import read_table, record_errors_at_lines
from gfins_fmi.io.conventions import SECONDS_PER_WEEK, frd_to_rfu, ned_to_enu, rpy_frd_ned_to_euler_rfu_enu
from gfins_fmi.io.errors import FileFormatError, not_a_file
from gfins_fmi.io.records import GnssRecord, ImuRecord, TruthRecord

__all__ = ["read_kfgins_imu", "check_kfgins_imu", "read_kfgins_gnss", "read_kfgins_nav", "kfgins_imu_table",
           "kfgins_gnss_table", "kfgins_nav_table", "KFGINS_NAV_FORMAT", "KFGINS_IMU_FORMAT",
           "KFGINS_GNSS_FORMAT"]

#: the fixed decimals of KF-GINS's own writers (src/kf-gins.cpp, writeNavResult): week,
#: seconds of week, lat/lon deg, h m, velocity NED m/s, roll/pitch/yaw deg
KFGINS_NAV_FORMAT = ("%.0f", "%.9f", "%.12f", "%.12f", "%.6f", "%.6f", "%.6f", "%.6f", "%.9f", "%.9f", "%.9f")
#: an IMU file: seconds of week, angle increments FRD rad, velocity increments FRD m/s
KFGINS_IMU_FORMAT = ("%.9f",) + ("%.15e",) * 6
#: a GNSS file: seconds of week, lat/lon deg, h m, std north, east, down m
KFGINS_GNSS_FORMAT = ("%.9f", "%.12f", "%.12f", "%.6f", "%.6f", "%.6f", "%.6f")


def _table(path, n_columns, what):
    """The numeric table; fields split at any run of spaces, tabs and commas, as KF-GINS's
    own loader does."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise not_a_file(path, f"{what} file")
    with open(path, encoding="utf-8", errors="replace") as f:
        first = next((line for line in f if line.strip()), "")
    if "," not in first:
        return read_table(path, n_columns, what)
    lines = path.read_text(encoding="utf-8", errors="replace").replace(",", " ").splitlines()
    return read_table(path, n_columns, what, lines=lines)


def _time(sow: np.ndarray, gps_week: int | None) -> np.ndarray:
    if gps_week is None:
        return sow
    if isinstance(gps_week, bool) or not isinstance(gps_week, (int, np.integer)) or gps_week < 0:
        raise ValueError(f"gps_week must be a non-negative integer (GPS week number); got {gps_week!r}")
    return int(gps_week) * SECONDS_PER_WEEK + sow


def check_kfgins_imu(path: pathlib.Path, n_columns) -> None:
    """The checks of a KF-GINS IMU file before it is read (whole or in chunks):
    ``n_columns`` an integer >= 7; a ``.bin`` file a whole number of 56-byte samples."""
    if isinstance(n_columns, bool) or not isinstance(n_columns, (int, np.integer)) or n_columns < 7:
        raise ValueError(f"n_columns must be an integer >= 7 (time, 3 angle and 3 velocity "
                         f"increments, then any extra columns); got {n_columns!r}")
    if path.suffix.lower() == ".bin":
        if not path.is_file():
            raise not_a_file(path, "KF-GINS binary IMU file")
        size = path.stat().st_size
        if size == 0 or size % 56:
            raise FileFormatError(path, None, f"{size} bytes is not a whole number of 56-byte "
                                  "samples (seven float64: time, 3 angle and 3 velocity increments)")


def read_kfgins_imu(path, n_columns: int = 7, gps_week: int | None = None) -> ImuRecord:
    """Read a KF-GINS IMU file: text (``*.txt``) or the binary form (``*.bin``, seven
    little-endian float64 per sample, as in awesome-gins-datasets).

    Columns: 1 GPS seconds of week (s, the end of the sample's interval), 2-4 angle
    increments x, y, z (rad), 5-7 velocity increments x, y, z (m/s), axes
    forward-right-down. Text files may have more columns (KF-GINS's ``imudatalen``;
    an 8th is an odometer speed): give their number as ``n_columns``; only the first
    seven are read.

    Conversion: increments to right-front-up, (x, y, z)_RFU = (y, x, -z)_FRD.

    Returns
    -------
    ImuRecord
        ``kind="increments"``, gyro (rad), accel (m/s), body RFU; times in seconds of
        week (or GPS seconds with ``gps_week``).
    """
    path = pathlib.Path(path)
    check_kfgins_imu(path, n_columns)
    line_of = None
    if path.suffix.lower() == ".bin":
        table = np.fromfile(path, dtype="<f8").reshape(-1, 7)
        fmt = "KF-GINS binary IMU"
    else:
        table, line_of = _table(path, [int(n_columns)], "KF-GINS IMU")
        fmt = "KF-GINS IMU"
    with record_errors_at_lines(path, line_of):
        return ImuRecord(_time(table[:, 0], gps_week), frd_to_rfu(table[:, 1:4]),
                         frd_to_rfu(table[:, 4:7]), "increments",
                         f"{fmt} file {path.name}: increments, FRD -> RFU")


def read_kfgins_gnss(path, gps_week: int | None = None, angles: str = "deg") -> GnssRecord:
    """Read a KF-GINS GNSS position file (7 columns) or position/velocity file (13).

    Columns: 1 GPS seconds of week (s), 2 latitude (deg), 3 longitude (deg),
    4 ellipsoidal height (m), 5-7 position standard deviations north, east, down (m);
    in the 13-column form (KF-GINS-Matlab's "GNSS position/velocity file") also
    8-10 velocity north, east, down (m/s) and 11-13 its standard deviations (m/s).
    KF-GINS-Matlab's README lists latitude and longitude of the 13-column form in rad,
    its KF-GINS README (7 columns) in deg: ``angles`` says which the file holds
    ("deg", the default, or "rad"). (The C++ KF-GINS reads a 13-column file's position
    std from columns 8-10, which KF-GINS-Matlab's layout gives to the velocity; this
    reader follows KF-GINS-Matlab's layout.)

    Conversion: latitude and longitude to radians; standard deviations reordered to
    east, north, up (a standard deviation has no sign: down = up); velocity to east,
    north, up. The quality flag is unknown (0): the format has none.
    """
    path = pathlib.Path(path)
    if angles not in ("deg", "rad"):
        raise ValueError(f'angles must be "deg" or "rad" (the unit of latitude and longitude '
                         f"in the file); got {angles!r}")
    to_rad = np.radians if angles == "deg" else np.asarray
    table, line_of = _table(path, [7, 13], "KF-GINS GNSS")
    std_ned = table[:, 4:7]
    vel = vstd = None
    if table.shape[1] == 13:
        vel = ned_to_enu(table[:, 7:10])
        vstd = table[:, [11, 10, 12]]
    with record_errors_at_lines(path, line_of):
        return GnssRecord(_time(table[:, 0], gps_week), to_rad(table[:, 1]), to_rad(table[:, 2]),
                          table[:, 3], std_ned[:, [1, 0, 2]], vel, vstd, None,
                          f"KF-GINS GNSS file {path.name}: NED -> ENU, {angles} -> rad")


def read_kfgins_nav(path, gps_week: int | None = None) -> TruthRecord:
    """Read a KF-GINS navigation result or ground-truth file (``*.nav``, 11 columns).

    Columns: 1 GPS week, 2 GPS seconds of week (s), 3 latitude (deg), 4 longitude
    (deg), 5 ellipsoidal height (m), 6-8 velocity north, east, down (m/s), 9-11 roll,
    pitch, yaw (deg) of the forward-right-down body in north-east-down
    (C_b^n = Rz(yaw) Ry(pitch) Rx(roll)).

    Conversion: degrees to radians; velocity to east, north, up; attitude to ours,
    [heading, pitch, roll] = [yaw wrapped to [0, 2 pi), pitch, roll] of the
    right-front-up body in east-north-up (the same angles: see
    :func:`~gfins_fmi.io.conventions.rpy_frd_ned_to_euler_rfu_enu`). Times are the
    seconds of week of column 2 (KF-GINS's own results write week 0); a file whose
    week changes is refused (its seconds of week restart).
    """
    path = pathlib.Path(path)
    table, line_of = _table(path, [11], "KF-GINS nav")
    week = table[:, 0]
    changed = np.flatnonzero(week != week[0])
    if changed.size:
        raise FileFormatError(path, line_of(int(changed[0])), f"the GPS week changes from "
                              f"{week[0]:.0f} to {week[changed[0]]:.0f}: seconds of week restart "
                              "there; split the file at the week boundary")
    rad = np.radians(table[:, 8:11])
    with record_errors_at_lines(path, line_of):
        return TruthRecord(_time(table[:, 1], gps_week), np.radians(table[:, 2]),
                           np.radians(table[:, 3]), table[:, 4], ned_to_enu(table[:, 5:8]),
                           rpy_frd_ned_to_euler_rfu_enu(rad[:, 0], rad[:, 1], rad[:, 2]),
                           f"KF-GINS nav file {path.name} (GPS week {week[0]:.0f}): "
                           "NED/FRD -> ENU/RFU, deg -> rad")


def kfgins_imu_table(imu) -> np.ndarray:
    """An ImuRecord of increments as KF-GINS's IMU file's rows (n, 7): time, angle and
    velocity increments forward-right-down (the inverse of :func:`read_kfgins_imu`; the
    time as it is: seconds of week for a record read from KF-GINS)."""
    if imu.kind != "increments":
        raise ValueError("a KF-GINS IMU file holds increments: convert the record with to_increments()")
    return np.column_stack([imu.t_s, frd_to_rfu(imu.gyro), frd_to_rfu(imu.accel)])


def kfgins_gnss_table(gnss) -> np.ndarray:
    """A GnssRecord as KF-GINS's 7-column GNSS file's rows: time, latitude and longitude
    (deg), height (m), position std north, east, down (m)."""
    std = np.asarray(gnss.pos_std_m)
    return np.column_stack([gnss.t_s, np.degrees(gnss.lat_rad), np.degrees(gnss.lon_rad), gnss.h_m,
                            std[:, 1], std[:, 0], std[:, 2]])


def kfgins_nav_table(t_s, lat_rad, lon_rad, h_m, v_enu_m_s, euler_rad, gps_week: int = 0) -> np.ndarray:
    """A navigation solution or truth as the rows of KF-GINS's ``.nav`` (n, 11): week,
    seconds of week, latitude and longitude (deg), height (m), velocity north, east,
    down (m/s), roll, pitch, yaw (deg) of the FRD body in NED. ``euler_rad`` is ours
    ([heading, pitch, roll] of the RFU body in ENU): the same angles
    (:func:`~gfins_fmi.io.conventions.rpy_frd_ned_to_euler_rfu_enu`), yaw = heading.
    ``t_s`` on a GPS-seconds scale (above one week) is written as week and seconds of
    week; otherwise as given, after ``gps_week``."""
    t = np.asarray(t_s, float)
    week = np.full(len(t), float(gps_week))
    if len(t) and t[0] >= SECONDS_PER_WEEK:
        week = np.floor(t / SECONDS_PER_WEEK)
        t = t - week * SECONDS_PER_WEEK
    e = np.degrees(np.asarray(euler_rad, float))
    return np.column_stack([week, t, np.degrees(lat_rad), np.degrees(lon_rad), h_m,
                            ned_to_enu(v_enu_m_s), e[:, 2], e[:, 1], e[:, 0]])
