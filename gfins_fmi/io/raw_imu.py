"""Readers of the raw formats laboratory calibration records come in: seven columns per
sample, ``[wx wy wz ax ay az t]`` (PSINS's ``imu`` array: increments in rad and m/s, the
time at the end of the interval), as little-endian float32 or float64 binary, or as text
(spaces, tabs or commas). The IMU frame is the record's own (a calibration works in the
IMU frame: no axis change). Units and the kind (increments or rates) are arguments;
docs/io.md lists them.
"""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi.io._text import read_table, record_errors_at_lines
from gfins_fmi.io.errors import FileFormatError
from gfins_fmi.io.records import ImuRecord

__all__ = ["read_raw_imu", "RAW_LAYOUTS", "GYRO_UNITS", "ACCEL_UNITS"]

#: the layouts: binary float32, binary float64, text
RAW_LAYOUTS = ("float32", "float64", "text")
#: gyro column units: an angle (increments) or that angle per second (rates); deg/h for rates
GYRO_UNITS = {"rad": 1.0, "deg": np.pi / 180.0, "arcsec": np.pi / 648000.0, "deg/h": np.pi / 180.0 / 3600.0}
#: accelerometer column units: m/s (increments) or m/s^2 (rates) ("m"), or g, mg, ug of
#: standard gravity (times s for increments)
ACCEL_UNITS = {"m": 1.0, "g": 9.80665, "mg": 9.80665e-3, "ug": 9.80665e-6}


def read_raw_imu(path, layout: str | None = None, kind: str = "increments", gyro_unit: str = "rad",
                 accel_unit: str = "m", time_scale_s: float = 1.0,
                 columns: tuple = ("wx", "wy", "wz", "ax", "ay", "az", "t")) -> ImuRecord:
    """Read a raw 7-column IMU record.

    Parameters
    ----------
    path : the file.
    layout : "float32", "float64" (binary, little-endian, 7 values a sample) or "text";
        default by suffix: ``.bin`` float64, ``.f32``/``.bin32`` float32, else text (comments
        after ``#`` or ``%``; fields split at spaces, tabs or commas).
    kind : "increments" (PSINS's convention: angle and velocity increments over the
        interval that ends at t) or "rates" (rates and specific force at t).
    gyro_unit : rad (default), deg, arcsec (per second for rates), or deg/h (rates).
    accel_unit : m (m/s increments or m/s^2 rates; default), g, mg, ug (of 9.80665 m/s^2).
    time_scale_s : seconds per unit of the time column (1e-3 for ms).
    columns : the order of the seven columns by name (wx wy wz ax ay az t).

    Returns
    -------
    ImuRecord (SI: rad, m/s or rad/s, m/s^2; the IMU frame of the file).

    Raises
    ------
    FileFormatError
        A binary size that is not a whole number of samples (the other float width, or a
        header), a text line of another column count or with text in a number column, and
        any broken record contract (NaN, times not increasing), naming the line.
    """
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file (a raw 7-column IMU record was expected)")
    suffix = path.suffix.lower()
    layout = layout or ("float64" if suffix == ".bin" else "float32" if suffix in (".f32", ".bin32")
                        else "text")
    if layout not in RAW_LAYOUTS:
        raise ValueError(f"layout must be one of {RAW_LAYOUTS}; got {layout!r}")
    if gyro_unit not in GYRO_UNITS or accel_unit not in ACCEL_UNITS:
        raise ValueError(f"gyro_unit one of {list(GYRO_UNITS)}, accel_unit one of {list(ACCEL_UNITS)}; "
                         f"got {gyro_unit!r}, {accel_unit!r}")
    if gyro_unit == "deg/h" and kind != "rates":
        raise ValueError("gyro_unit deg/h is a rate: use it with kind='rates'")
    names = ("wx", "wy", "wz", "ax", "ay", "az", "t")
    if sorted(columns) != sorted(names):
        raise ValueError(f"columns must order the seven names {names}; got {columns!r}")
    if not (np.isfinite(time_scale_s) and time_scale_s > 0):
        raise ValueError(f"time_scale_s must be finite and > 0; got {time_scale_s!r}")
    line_of = None
    if layout == "text":
        # comments after # or % (Matlab), fields split at spaces, tabs or commas
        lines = [ln.split("#", 1)[0].split("%", 1)[0].replace(",", " ")
                 for ln in path.read_text(encoding="utf-8", errors="replace").splitlines()]
        table, line_of = read_table(path, [7], "raw 7-column IMU", lines=lines)
    else:
        width = 4 if layout == "float32" else 8
        size = path.stat().st_size
        if size == 0 or size % (7 * width):
            other = 8 if width == 4 else 4
            hint = (f" (it is a whole number of {7 * other}-byte samples: layout float{8 * other}?)"
                    if size and size % (7 * other) == 0 else " (a header, or another column count?)")
            raise FileFormatError(path, None, f"{size} bytes is not a whole number of {7 * width}-byte "
                                  f"samples (seven {layout}){hint}")
        table = np.fromfile(path, dtype="<f4" if width == 4 else "<f8").astype(float).reshape(-1, 7)
    col = {n: table[:, columns.index(n)] for n in names}
    t = col["t"] * time_scale_s
    if t.size > 1:
        dt = float(np.median(np.diff(t)))
        if not (1e-6 <= dt <= 100.0):
            hint = {"float64": " (a float32 file read as float64?)", "float32": " (a float64 file read "
                    "as float32?)"}.get(layout, "")
            raise FileFormatError(path, None, f"the median sample interval is {dt:.3g} s, not a sampling "
                                  f"interval (1 us to 100 s): the layout{hint}, the column order or "
                                  "--time-scale is wrong")
    g = np.c_[col["wx"], col["wy"], col["wz"]] * GYRO_UNITS[gyro_unit]
    a = np.c_[col["ax"], col["ay"], col["az"]] * ACCEL_UNITS[accel_unit]
    with record_errors_at_lines(path, line_of):
        return ImuRecord(t, g, a, kind,
                         f"raw 7-column IMU {layout} file {path.name}: {kind}, gyro {gyro_unit}, "
                         f"accel {accel_unit}")
