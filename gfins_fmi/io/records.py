"""Records of sensor and reference data: what the integrated-navigation filters and
smoothers consume (docs/io.md).

Frames and units (as in ``csrc/nav/gf_sins.h``): body b = right-front-up (x right, y
forward, z up), navigation n = East-North-Up, positions geodetic WGS-84 (latitude and
longitude in rad, ellipsoidal height in m), Euler angles [heading, pitch, roll] in rad
(heading clockwise from north in [0, 2 pi), pitch nose-up +, roll right-wing-down +,
C_b^n = Rz(-heading) Rx(pitch) Ry(roll)). Times in seconds, on one time scale per record
(the readers say which).

Each record is a frozen dataclass whose arrays are float64, C-contiguous and read-only,
validated once when the record is built: shapes, finiteness, strictly increasing times,
standard deviations > 0, angle ranges. The arrays are copied on construction, so a
record never changes under its user (nor its user's arrays under the record), and a C
function can take a pointer to them as they are.
"""
from __future__ import annotations

import dataclasses
import itertools
import math
import pathlib
import re
from dataclasses import dataclass
from typing import ClassVar, Iterable, NamedTuple, Sequence

import numpy as np

from gfins_fmi.io._text import data_lines, record_errors_at_lines
from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.tables import TableReader
from gfins_fmi.io.errors import FileFormatError, RecordError, not_a_file

__all__ = ["ImuRecord", "GnssRecord", "BaroRecord", "OdometerRecord", "TruthRecord",
           "SamplingStats", "Gap", "QUALITY_NAMES", "IMU_KINDS", "csv_line_of"]

#: RTKLIB's solution quality flag Q, kept in GnssRecord.quality
QUALITY_NAMES = {0: "unknown", 1: "fix", 2: "float", 3: "SBAS", 4: "DGPS", 5: "single", 6: "PPP"}
#: ImuRecord.kind: increments (gyro rad, accel m/s over the interval that ends at t_s)
#: or rates (gyro rad/s, accel m/s^2 at t_s)
IMU_KINDS = ("increments", "rates")

_TWO_PI = 2.0 * math.pi


# --- validation, once per record ------------------------------------------------------

def _real_array(name: str, value, tail: tuple[int, ...], unit: str) -> np.ndarray:
    """``value`` as a new read-only float64 C-contiguous array of shape (n, *tail), finite."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers in {unit}; got dtype {arr.dtype}")
    if arr.ndim != 1 + len(tail) or arr.shape[1:] != tail:
        shape = "(n" + "".join(f", {k}" for k in tail) + ")"
        raise RecordError(f"{name} must have shape {shape} in {unit}; got shape {arr.shape}", name)
    out = np.array(arr, dtype=np.float64, order="C", copy=True)
    finite = np.isfinite(out)
    if not finite.all():
        pos = tuple(int(i) for i in np.argwhere(~finite)[0])
        where = f"[{pos[0]}]" if len(pos) == 1 else f"[{pos[0]}, {pos[1]}]"
        raise RecordError(f"{name}{where} = {out[pos]} is not finite: drop that sample or fill it "
                          "before building the record", name, pos[0])
    out.flags.writeable = False
    return out


def _times(value) -> np.ndarray:
    t = _real_array("t_s", value, (), "s")
    if t.shape[0] == 0:
        raise RecordError("the record is empty: t_s has no sample (a record holds at least one)", "t_s")
    d = np.diff(t)
    bad = np.flatnonzero(~(d > 0))
    if bad.size:
        k = int(bad[0]) + 1
        how = "repeats" if d[k - 1] == 0 else "goes back from"
        raise RecordError(f"t_s must be strictly increasing: t_s[{k}] = {float(t[k])!r} s {how} "
                          f"t_s[{k - 1}] = {float(t[k - 1])!r} s; sort the samples by time and drop "
                          "duplicates (np.unique(t_s, return_index=True) gives both)", "t_s", k)
    return t


def _rows(name: str, value, n: int, tail: tuple[int, ...], unit: str) -> np.ndarray:
    arr = _real_array(name, value, tail, unit)
    if arr.shape[0] != n:
        raise RecordError(f"{name} has {arr.shape[0]} rows but t_s has {n}: one row per sample "
                          "time", name)
    return arr


def _stds(name: str, value, n: int, tail: tuple[int, ...], unit: str) -> np.ndarray:
    arr = _rows(name, value, n, tail, unit)
    bad = ~(arr > 0)
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f"[{pos[0]}]" if len(pos) == 1 else f"[{pos[0]}, {pos[1]}]"
        raise RecordError(f"{name}{where} = {arr[pos]} {unit}: a standard deviation must be > 0 "
                          "(zero claims a perfect measurement and makes the filter's innovation "
                          "covariance singular); give the sensor's real accuracy", name, pos[0])
    return arr


def _within(name: str, arr: np.ndarray, lo: float, hi: float, unit: str, hint: str,
            hi_open: bool = False) -> None:
    bad = (arr < lo) | ((arr >= hi) if hi_open else (arr > hi))
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f"[{pos[0]}]" if len(pos) == 1 else f"[{pos[0]}, {pos[1]}]"
        interval = f"[{lo:.6g}, {hi:.6g}{')' if hi_open else ']'}"
        raise RecordError(f"{name}{where} = {float(arr[pos])!r} {unit} is outside {interval}: {hint}",
                          name, pos[0])


def _source(value) -> str:
    if not isinstance(value, str):
        raise TypeError(f"source must be a str (where the record came from); got {type(value).__name__}")
    return value


def _set(record, **values) -> None:
    for k, v in values.items():
        object.__setattr__(record, k, v)


def _check_lat_lon(lat: np.ndarray, lon: np.ndarray) -> None:
    _within("lat_rad", lat, -math.pi / 2, math.pi / 2, "rad",
            "latitude is in radians (from degrees: np.radians)")
    _within("lon_rad", lon, -math.pi, _TWO_PI, "rad",
            "longitude is in radians, in [-pi, pi] or [0, 2 pi) (from degrees: np.radians)")


# --- what every record offers -----------------------------------------------------------

class Gap(NamedTuple):
    """An interval between two consecutive samples longer than the gap threshold."""
    index: int              #: the sample after the gap: the interval t_s[index-1] -> t_s[index]
    t_before_s: float
    t_after_s: float

    @property
    def length_s(self) -> float:
        return self.t_after_s - self.t_before_s


@dataclass(frozen=True)
class SamplingStats:
    """Statistics of the intervals between consecutive samples (s)."""
    n_intervals: int
    median_s: float
    mean_s: float
    min_s: float
    max_s: float
    gap_threshold_s: float
    gaps: tuple[Gap, ...]

    @property
    def median_rate_hz(self) -> float:
        return 1.0 / self.median_s

    def __str__(self) -> str:
        text = (f"{self.n_intervals} intervals: median {self.median_s * 1e3:.4g} ms "
                f"({self.median_rate_hz:.4g} Hz), mean {self.mean_s * 1e3:.4g} ms, "
                f"min {self.min_s * 1e3:.4g} ms, max {self.max_s * 1e3:.4g} ms; "
                f"{len(self.gaps)} gap(s) over {self.gap_threshold_s:.4g} s")
        for g in self.gaps[:5]:
            text += f"\n  {g.length_s:.4g} s after t = {g.t_before_s:.17g} s (before sample {g.index})"
        if len(self.gaps) > 5:
            text += f"\n  ... {len(self.gaps) - 5} more"
        return text


class _Record:
    """Methods shared by the records (each is a frozen dataclass with ``t_s``, ``source``
    and the per-sample arrays named in ``_ROW_FIELDS``)."""

    t_s: np.ndarray
    source: str
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ()

    def __len__(self) -> int:
        return int(self.t_s.shape[0])

    def __setstate__(self, state: dict) -> None:
        """Unpickling and deep copies give fresh arrays: make them read-only too."""
        for value in state.values():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
        self.__dict__.update(state)

    @property
    def duration_s(self) -> float:
        """Time from the first to the last sample (s)."""
        return float(self.t_s[-1] - self.t_s[0])

    def __repr__(self) -> str:
        kind = f"kind={getattr(self, 'kind')!r}, " if hasattr(self, "kind") else ""
        return (f"{type(self).__name__}({kind}n={len(self)}, t_s=[{self.t_s[0]:.17g} .. "
                f"{self.t_s[-1]:.17g}] s, source={self.source!r})")

    def _take(self, index, note: str | None = None):
        """A new record of the rows ``index`` (a slice or index array), validated again."""
        changes = {f: getattr(self, f)[index] for f in self._ROW_FIELDS if getattr(self, f) is not None}
        if note:
            changes["source"] = f"{self.source}; {note}" if self.source else note
        return dataclasses.replace(self, **changes)

    def slice(self, t0_s: float, t1_s: float):
        """The samples with ``t0_s <= t_s <= t1_s`` (s, on the record's time scale), as a
        new record of the same type. For increments, a sample belongs to the time that
        ends its interval."""
        t0, t1 = float(t0_s), float(t1_s)
        if not (math.isfinite(t0) and math.isfinite(t1) and t0 <= t1):
            raise ValueError(f"slice needs finite t0_s <= t1_s (s); got {t0_s!r}, {t1_s!r}")
        lo = int(np.searchsorted(self.t_s, t0, "left"))
        hi = int(np.searchsorted(self.t_s, t1, "right"))
        if hi <= lo:
            raise RecordError(f"no sample in [{t0:.17g}, {t1:.17g}] s: the record spans "
                              f"[{self.t_s[0]:.17g}, {self.t_s[-1]:.17g}] s (times are on the "
                              "record's own scale; for times from its start add t_s[0])", "t_s")
        return self._take(slice(lo, hi))

    def dt_stats(self, gap_threshold_s: float | None = None) -> SamplingStats:
        """Intervals between consecutive samples: median, mean, min, max, and the gaps
        longer than ``gap_threshold_s`` (default: twice the median)."""
        if len(self) < 2:
            raise RecordError("dt_stats needs at least two samples; the record has one", "t_s")
        d = np.diff(self.t_s)
        med = float(np.median(d))
        thr = 2.0 * med if gap_threshold_s is None else float(gap_threshold_s)
        if not (math.isfinite(thr) and thr > 0):
            raise ValueError(f"gap_threshold_s must be finite and > 0 s; got {gap_threshold_s!r}")
        idx = np.flatnonzero(d > thr) + 1
        gaps = tuple(Gap(int(k), float(self.t_s[k - 1]), float(self.t_s[k])) for k in idx)
        return SamplingStats(int(d.size), med, float(d.mean()), float(d.min()), float(d.max()),
                             thr, gaps)

    # --- our own CSV format ---
    def _csv_table(self) -> tuple[list[str], np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def _csv_layouts(cls) -> list[tuple[str, ...]]:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def _from_csv_table(cls, names: tuple[str, ...], table: np.ndarray, source: str):  # pragma: no cover
        raise NotImplementedError

    def to_csv(self, path) -> pathlib.Path:
        """Write the record as CSV: two comment lines (``# gfins_fmi <type>``,
        ``# source: ...``), a header line of column names that carry their units
        (``t_s,gyro_x_rad_s,...``), then one line per sample at full precision
        (the shortest decimal that reads back as the same float64, bit for bit). The
        file is written beside its destination and renamed into place, so a failure
        never leaves half a file (:class:`~gfins_fmi.io.table_writer.TableWriter`)."""
        names, table = self._csv_table()
        dtypes = [np.int8 if name == "quality" else np.float64 for name in names]
        comments = [f"gfins_fmi {type(self).__name__}", f"source: {self.source}"]
        with TableWriter(path, names, dtypes, comments=comments, format="csv") as w:
            w.write([table[:, j] for j in range(len(names))])
            return w.commit()

    @classmethod
    def csv_head(cls, path) -> tuple[tuple[str, ...], str, int]:
        """The head of a record's CSV, checked: its column names (one of the type's
        layouts), its ``# source:`` and the 1-based line of the names. Read line by line
        up to the names (a record of any length). A ``# gfins_fmi`` line, if present, must
        name this type."""
        path = pathlib.Path(path)
        if not path.is_file():
            raise not_a_file(path, f"{cls.__name__} CSV")
        source, header_line, names = "", None, None
        try:
            with open(path, encoding="utf-8") as f:
                for i, line in enumerate(f):
                    text = line.strip()
                    if text.startswith("#"):
                        body = text[1:].strip()
                        if body.startswith("gfins_fmi "):
                            kind = body.split()[1] if len(body.split()) > 1 else ""
                            if kind != cls.__name__:
                                raise FileFormatError(path, i + 1, f"the file holds a {kind}: read it "
                                                      f"with {kind}.from_csv")
                        elif body.startswith("source:"):
                            source = body[len("source:"):].strip()
                        continue
                    if text:
                        header_line, names = i + 1, tuple(n.strip() for n in text.split(","))
                        break
        except UnicodeDecodeError as exc:   # found by fuzzing: it escaped as is
            raise FileFormatError(path, None, f"not a text file: a {cls.__name__} CSV is "
                                  f"UTF-8 text ({exc.reason} at byte {exc.start})") from exc
        if names is None:
            raise FileFormatError(path, None, f"the file is empty: a {cls.__name__} CSV starts "
                                  "with a line of column names")
        cls.check_layout(path, names, header_line)
        return names, source, header_line

    @classmethod
    def check_layout(cls, path, names: tuple[str, ...], line: int | None = None) -> None:
        """Refuse column names that are not one of the type's layouts (naming them)."""
        layouts = cls._csv_layouts()
        if tuple(names) not in layouts:
            expected = "\n  ".join(",".join(layout) for layout in layouts)
            raise FileFormatError(path, line, f"the column names {','.join(names)!r} are "
                                  f"not a {cls.__name__} layout; expected one of\n  {expected}")

    @classmethod
    def from_csv(cls, path):
        """Read a record written by :meth:`to_csv` (the column names must be one of the
        type's layouts; the ``# gfins_fmi`` line, if present, must name this type)."""
        path = pathlib.Path(path)
        names, source, header_line = cls.csv_head(path)
        what = f"{cls.__name__} CSV"
        reader = TableReader(path, header=True, what=what, format="csv",
                             header_hint="a CSV of a record has one header line")
        table = np.concatenate([block for _, block in reader])
        with record_errors_at_lines(path, csv_line_of(path, header_line)):
            return cls._from_csv_table(names, table, source)

    @classmethod
    def rows_of(cls, first_row: int, t_before: float | None, *args, **kw):
        """A record of the rows from ``first_row`` on of a longer record read in chunks,
        validated as the whole record is, with the whole's messages: its errors name the
        whole's rows (``t_s[first_row + k]``, ``RecordError.index``), and its first time
        must follow ``t_before``, the last time of the rows before it (None: none)."""
        t = np.asarray(kw["t_s"] if "t_s" in kw else args[0])
        if t_before is not None and t.size and t.dtype.kind in "iuf" and np.isfinite(t).all() \
                and not t[0] > t_before:
            k = int(first_row)
            how = "repeats" if t[0] == t_before else "goes back from"
            raise RecordError(f"t_s must be strictly increasing: t_s[{k}] = {float(t[0])!r} s {how} "
                              f"t_s[{k - 1}] = {float(t_before)!r} s; sort the samples by time and drop "
                              "duplicates (np.unique(t_s, return_index=True) gives both)", "t_s", k)
        try:
            return cls(*args, **kw)
        except RecordError as exc:
            if not first_row or exc.index is None:
                raise
            text = _ROW_INDEX.sub(lambda m: f"{m[1]}[{int(m[2]) + first_row}", str(exc))
            raise RecordError(text, exc.field, exc.index + int(first_row)) from None


#: a row index in a record's message (``t_s[12]``, ``gyro[12, 1]``)
_ROW_INDEX = re.compile(r"\b([a-z_]+)\[(\d+)")


def csv_line_of(path, header_line: int):
    """Row index of a record's CSV -> its 1-based line in the file (for messages; the
    file is read only when called)."""
    def line_of(row: int) -> int:
        with open(path, encoding="utf-8", errors="replace") as f:
            return next(itertools.islice(data_lines(f, "#", header_line), row, None)) + 1
    return line_of


_AXES = ("x", "y", "z")


# --- the records ---------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class ImuRecord(_Record):
    """Gyro and accelerometer samples in the body frame (right-front-up).

    Parameters
    ----------
    t_s : array_like (n,)
        Sample times (s), strictly increasing. For increments, the time at the END of
        each sample's interval.
    gyro : array_like (n, 3)
        Angle increments (rad) or angular rates (rad/s), body x, y, z.
    accel : array_like (n, 3)
        Velocity increments (m/s) or specific force (m/s^2), body x, y, z.
    kind : {"increments", "rates"}
    source : str
        Free text: where the record came from.
    """
    t_s: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    kind: str
    source: str = ""
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ("t_s", "gyro", "accel")

    def __post_init__(self):
        if self.kind not in IMU_KINDS:
            raise RecordError(f"kind must be 'increments' (gyro rad, accel m/s per interval) or "
                              f"'rates' (gyro rad/s, accel m/s^2); got {self.kind!r}", "kind")
        t = _times(self.t_s)
        g_unit, a_unit = self.units
        _set(self, t_s=t, gyro=_rows("gyro", self.gyro, len(t), (3,), g_unit),
             accel=_rows("accel", self.accel, len(t), (3,), a_unit), source=_source(self.source))

    @property
    def units(self) -> tuple[str, str]:
        """Units of (gyro, accel) for this kind."""
        return ("rad", "m/s") if self.kind == "increments" else ("rad/s", "m/s^2")

    def to_increments(self) -> ImuRecord:
        """Increments from rates by the trapezoid over each interval:
        ``dtheta_k = (w_(k-1) + w_k) / 2 * (t_k - t_(k-1))`` (and the same for the
        specific force), for k = 1 .. n-1, at times ``t_s[1:]``: the first sample has no
        interval before it, so the result has n - 1 rows.

        Exact when the rates are linear between samples (the model ``gf_sins`` applies
        to rate input); otherwise the error per interval is ``-w'' T^3 / 12``, so the
        increments are third-order accurate per interval and second-order over a record.
        An increments record is returned as it is.
        """
        if self.kind == "increments":
            return self
        if len(self) < 2:
            raise RecordError("to_increments needs at least two rate samples (one interval)", "t_s")
        dt = np.diff(self.t_s)[:, None]
        return ImuRecord(self.t_s[1:], 0.5 * (self.gyro[:-1] + self.gyro[1:]) * dt,
                         0.5 * (self.accel[:-1] + self.accel[1:]) * dt, "increments",
                         f"{self.source}; increments by the trapezoid" if self.source
                         else "increments by the trapezoid")

    def to_rates(self, first_interval_s: float | None = None) -> ImuRecord:
        """Rates from increments by dividing each by its interval:
        ``w_k = dtheta_k / (t_k - t_(k-1))``, the mean rate over the interval, kept at
        its end time t_k.

        As the rate at the interval's midpoint ``t_k - T/2`` this is second-order
        accurate (error ``w'' T^2 / 24``); as the rate at ``t_k``, where the record puts
        it, first-order (error ``-w' T / 2``: it lags by half an interval). Interval 0
        starts at ``t_s[0] - first_interval_s``; by default its length is that of the
        next interval, ``t_s[1] - t_s[0]``. A rates record is returned as it is.
        """
        if self.kind == "rates":
            return self
        if first_interval_s is None:
            if len(self) < 2:
                raise RecordError("to_rates on a single sample needs first_interval_s, the "
                                  "length of its interval (s)", "t_s")
            first = float(self.t_s[1] - self.t_s[0])
        else:
            first = float(first_interval_s)
            if not (math.isfinite(first) and first > 0):
                raise ValueError(f"first_interval_s must be finite and > 0 s; got {first_interval_s!r}")
        dt = np.concatenate([[first], np.diff(self.t_s)])[:, None]
        return ImuRecord(self.t_s, self.gyro / dt, self.accel / dt, "rates",
                         f"{self.source}; rates = increments / interval" if self.source
                         else "rates = increments / interval")

    def _csv_table(self):
        g, a = ("rad", "m_s") if self.kind == "increments" else ("rad_s", "m_s2")
        names = (["t_s"] + [f"gyro_{x}_{g}" for x in _AXES] + [f"accel_{x}_{a}" for x in _AXES])
        return names, np.column_stack([self.t_s, self.gyro, self.accel])

    @classmethod
    def _csv_layouts(cls):
        return [tuple(["t_s"] + [f"gyro_{x}_{g}" for x in _AXES] + [f"accel_{x}_{a}" for x in _AXES])
                for g, a in (("rad", "m_s"), ("rad_s", "m_s2"))]

    @classmethod
    def _from_csv_table(cls, names, table, source):
        kind = "increments" if names[1] == "gyro_x_rad" else "rates"
        return cls(table[:, 0], table[:, 1:4], table[:, 4:7], kind, source)


@dataclass(frozen=True, eq=False, repr=False)
class GnssRecord(_Record):
    """GNSS position (and velocity) solutions of the antenna.

    Parameters
    ----------
    t_s : array_like (m,)
        Times of validity (s), strictly increasing.
    lat_rad, lon_rad, h_m : array_like (m,)
        Geodetic WGS-84 latitude, longitude (rad) and ellipsoidal height (m).
    pos_std_m : array_like (m, 3)
        Standard deviations east, north, up (m), > 0.
    vel_enu_m_s, vel_std_m_s : array_like (m, 3), optional
        Velocity east, north, up relative to the Earth (m/s) and its standard deviations;
        both or neither.
    quality : array_like (m,) of int, optional
        RTKLIB's Q: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP, 0 unknown (default).
    source : str
    """
    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    pos_std_m: np.ndarray
    vel_enu_m_s: np.ndarray | None = None
    vel_std_m_s: np.ndarray | None = None
    quality: np.ndarray | None = None
    source: str = ""
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ("t_s", "lat_rad", "lon_rad", "h_m", "pos_std_m",
                                              "vel_enu_m_s", "vel_std_m_s", "quality")

    def __post_init__(self):
        t = _times(self.t_s)
        n = len(t)
        lat, lon = _rows("lat_rad", self.lat_rad, n, (), "rad"), _rows("lon_rad", self.lon_rad, n, (), "rad")
        _check_lat_lon(lat, lon)
        h = _rows("h_m", self.h_m, n, (), "m")
        std = _stds("pos_std_m", self.pos_std_m, n, (3,), "m")
        if (self.vel_enu_m_s is None) != (self.vel_std_m_s is None):
            raise RecordError("give both vel_enu_m_s and vel_std_m_s, or neither", "vel_std_m_s")
        vel = vstd = None
        if self.vel_enu_m_s is not None:
            vel = _rows("vel_enu_m_s", self.vel_enu_m_s, n, (3,), "m/s")
            vstd = _stds("vel_std_m_s", self.vel_std_m_s, n, (3,), "m/s")
        _set(self, t_s=t, lat_rad=lat, lon_rad=lon, h_m=h, pos_std_m=std, vel_enu_m_s=vel,
             vel_std_m_s=vstd, quality=self._quality(self.quality, n), source=_source(self.source))

    @staticmethod
    def _quality(value, n: int) -> np.ndarray:
        if value is None:
            q = np.zeros(n, np.int8)
        else:
            arr = np.asarray(value)
            if arr.dtype.kind not in "iuf" or arr.shape != (n,):
                raise RecordError(f"quality must be {n} integers (RTKLIB's Q); got dtype "
                                  f"{arr.dtype}, shape {arr.shape}", "quality")
            bad = ~np.isin(arr, list(QUALITY_NAMES))
            if bad.any():
                k = int(np.flatnonzero(bad)[0])
                raise RecordError(f"quality[{k}] = {arr[k].item()!r} is not one of RTKLIB's Q values "
                                  f"{QUALITY_NAMES}", "quality", k)
            q = np.array(arr, dtype=np.int8, order="C", copy=True)
        q.flags.writeable = False
        return q

    @property
    def has_velocity(self) -> bool:
        return self.vel_enu_m_s is not None

    def quality_counts(self) -> dict[str, int]:
        """Epochs per solution quality, e.g. {"fix": 349, "float": 187}."""
        values, counts = np.unique(self.quality, return_counts=True)
        return {QUALITY_NAMES[int(v)]: int(c) for v, c in zip(values, counts)}

    def with_outages(self, outages: Iterable[Sequence[float]]) -> GnssRecord:
        """A copy without the epochs inside any of the ``outages``, each ``(t0_s, t1_s)``
        on the record's time scale, both ends included: simulated GNSS outages. The
        outages are noted in ``source``.

        Raises
        ------
        ValueError
            An outage that is not ``t0 < t1`` (finite), or that lies wholly outside the
            record (most often a time on another scale, e.g. seconds from the start for a
            record in GPS seconds), or outages that leave no epoch.
        """
        t = self.t_s
        keep = np.ones(len(self), bool)
        spans = []
        for i, item in enumerate(outages):
            try:
                t0, t1 = (float(x) for x in item)
            except (TypeError, ValueError):
                raise ValueError(f"outage {i} must be a pair (t0_s, t1_s); got {item!r}") from None
            if not (math.isfinite(t0) and math.isfinite(t1) and t0 < t1):
                raise ValueError(f"outage {i} = {item!r} needs finite t0_s < t1_s (s)")
            if t1 < t[0] or t0 > t[-1]:
                raise ValueError(f"outage {i} = [{t0:.17g}, {t1:.17g}] s lies outside the record, "
                                 f"which spans [{t[0]:.17g}, {t[-1]:.17g}] s: give times on the "
                                 "record's scale (from its start: add t_s[0])")
            keep &= ~((t >= t0) & (t <= t1))
            spans.append(f"[{t0:.17g}, {t1:.17g}]")
        if not keep.any():
            raise RecordError("the outages remove every epoch: keep at least one", "t_s")
        return self._take(np.flatnonzero(keep), note=f"outages {', '.join(spans)} s removed"
                          if spans else None)

    def _csv_table(self):
        names = ["t_s", "lat_rad", "lon_rad", "h_m", "pos_std_e_m", "pos_std_n_m", "pos_std_u_m"]
        cols = [self.t_s, self.lat_rad, self.lon_rad, self.h_m, self.pos_std_m]
        if self.has_velocity:
            names += ["vel_e_m_s", "vel_n_m_s", "vel_u_m_s",
                      "vel_std_e_m_s", "vel_std_n_m_s", "vel_std_u_m_s"]
            cols += [self.vel_enu_m_s, self.vel_std_m_s]
        return names + ["quality"], np.column_stack(cols + [self.quality])

    @classmethod
    def _csv_layouts(cls):
        pos = ("t_s", "lat_rad", "lon_rad", "h_m", "pos_std_e_m", "pos_std_n_m", "pos_std_u_m")
        vel = ("vel_e_m_s", "vel_n_m_s", "vel_u_m_s", "vel_std_e_m_s", "vel_std_n_m_s", "vel_std_u_m_s")
        return [pos + ("quality",), pos + vel + ("quality",)]

    @classmethod
    def _from_csv_table(cls, names, table, source):
        vel = len(names) == 14
        return cls(table[:, 0], table[:, 1], table[:, 2], table[:, 3], table[:, 4:7],
                   table[:, 7:10] if vel else None, table[:, 10:13] if vel else None,
                   table[:, -1], source)


@dataclass(frozen=True, eq=False, repr=False)
class BaroRecord(_Record):
    """Barometric heights ``h_m`` (m) with standard deviations ``std_m`` (m, > 0)."""
    t_s: np.ndarray
    h_m: np.ndarray
    std_m: np.ndarray
    source: str = ""
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ("t_s", "h_m", "std_m")

    def __post_init__(self):
        t = _times(self.t_s)
        _set(self, t_s=t, h_m=_rows("h_m", self.h_m, len(t), (), "m"),
             std_m=_stds("std_m", self.std_m, len(t), (), "m"), source=_source(self.source))

    def _csv_table(self):
        return ["t_s", "h_m", "std_m"], np.column_stack([self.t_s, self.h_m, self.std_m])

    @classmethod
    def _csv_layouts(cls):
        return [("t_s", "h_m", "std_m")]

    @classmethod
    def _from_csv_table(cls, names, table, source):
        return cls(table[:, 0], table[:, 1], table[:, 2], source)


@dataclass(frozen=True, eq=False, repr=False)
class OdometerRecord(_Record):
    """Forward speeds ``speed_m_s`` (m/s, body y) with standard deviations ``std_m_s``."""
    t_s: np.ndarray
    speed_m_s: np.ndarray
    std_m_s: np.ndarray
    source: str = ""
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ("t_s", "speed_m_s", "std_m_s")

    def __post_init__(self):
        t = _times(self.t_s)
        _set(self, t_s=t, speed_m_s=_rows("speed_m_s", self.speed_m_s, len(t), (), "m/s"),
             std_m_s=_stds("std_m_s", self.std_m_s, len(t), (), "m/s"), source=_source(self.source))

    def _csv_table(self):
        return ["t_s", "speed_m_s", "std_m_s"], np.column_stack([self.t_s, self.speed_m_s, self.std_m_s])

    @classmethod
    def _csv_layouts(cls):
        return [("t_s", "speed_m_s", "std_m_s")]

    @classmethod
    def _from_csv_table(cls, names, table, source):
        return cls(table[:, 0], table[:, 1], table[:, 2], source)


@dataclass(frozen=True, eq=False, repr=False)
class TruthRecord(_Record):
    """Reference trajectory: position, velocity and attitude of the body (the IMU).

    Parameters
    ----------
    t_s : array_like (n,)
    lat_rad, lon_rad, h_m : array_like (n,)
        Geodetic WGS-84 (rad, rad, m, ellipsoidal height).
    v_enu_m_s : array_like (n, 3)
        Velocity relative to the Earth, east, north, up (m/s).
    euler_rad : array_like (n, 3)
        [heading in [0, 2 pi), pitch in [-pi/2, pi/2], roll in [-pi, pi]] (rad), with
        C_b^n = Rz(-heading) Rx(pitch) Ry(roll) (body right-front-up, navigation ENU).
    source : str
    """
    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    v_enu_m_s: np.ndarray
    euler_rad: np.ndarray
    source: str = ""
    _ROW_FIELDS: ClassVar[tuple[str, ...]] = ("t_s", "lat_rad", "lon_rad", "h_m", "v_enu_m_s",
                                              "euler_rad")

    def __post_init__(self):
        t = _times(self.t_s)
        n = len(t)
        lat, lon = _rows("lat_rad", self.lat_rad, n, (), "rad"), _rows("lon_rad", self.lon_rad, n, (), "rad")
        _check_lat_lon(lat, lon)
        eul = _rows("euler_rad", self.euler_rad, n, (3,), "rad")
        _within("euler_rad[:, 0] (heading)", eul[:, 0], 0.0, _TWO_PI, "rad",
                "heading is clockwise from north in [0, 2 pi): wrap it with np.mod(heading, 2 * np.pi)",
                hi_open=True)
        _within("euler_rad[:, 1] (pitch)", eul[:, 1], -math.pi / 2, math.pi / 2, "rad",
                "pitch is in [-pi/2, pi/2] rad (from degrees: np.radians)")
        _within("euler_rad[:, 2] (roll)", eul[:, 2], -math.pi, math.pi, "rad",
                "roll is in [-pi, pi] rad (from degrees: np.radians)")
        _set(self, t_s=t, lat_rad=lat, lon_rad=lon, h_m=_rows("h_m", self.h_m, n, (), "m"),
             v_enu_m_s=_rows("v_enu_m_s", self.v_enu_m_s, n, (3,), "m/s"), euler_rad=eul,
             source=_source(self.source))

    def _csv_table(self):
        names = ["t_s", "lat_rad", "lon_rad", "h_m", "v_e_m_s", "v_n_m_s", "v_u_m_s",
                 "heading_rad", "pitch_rad", "roll_rad"]
        return names, np.column_stack([self.t_s, self.lat_rad, self.lon_rad, self.h_m,
                                       self.v_enu_m_s, self.euler_rad])

    @classmethod
    def _csv_layouts(cls):
        return [("t_s", "lat_rad", "lon_rad", "h_m", "v_e_m_s", "v_n_m_s", "v_u_m_s",
                 "heading_rad", "pitch_rad", "roll_rad")]

    @classmethod
    def _from_csv_table(cls, names, table, source):
        return cls(table[:, 0], table[:, 1], table[:, 2], table[:, 3], table[:, 4:7],
                   table[:, 7:10], source)
