"""An IMU record of any format ``gfins integrate`` reads, a chunk of samples at a time
(issue 20: the memory of a run does not grow with the record's length).

Formats (``fmt``): ``"csv"`` our :class:`~gfins_fmi.io.records.ImuRecord` table (CSV
text as :meth:`~gfins_fmi.io.records.ImuRecord.to_csv` writes it, or Parquet / npz with
the same column names, by the file's suffix), ``"kfgins"`` (KF-GINS's IMU text or
``.bin``: increments, forward-right-down) and ``"rtk_walk"`` (the rtk_walk CSV: rates in
g and rad/s, sensor axes). Each chunk is converted at the door exactly as the
whole-record readers convert (:mod:`gfins_fmi.io.kfgins`, :mod:`gfins_fmi.io.rtk_walk`)
and validated as the whole record is (:meth:`~gfins_fmi.io.records.ImuRecord.rows_of`:
finite, strictly increasing times across chunk boundaries too), with the whole record's
messages: they name the row of the whole record and, in text, its line.
"""
from __future__ import annotations

import pathlib
import zipfile
from typing import Callable, Iterator

import numpy as np

from gfins_fmi.io._text import data_lines
from gfins_fmi.io.conventions import GPS_EPOCH_FROM_1970_S, frd_to_rfu
from gfins_fmi.io.errors import FileFormatError, RecordError, not_a_file
from gfins_fmi.io.kfgins import check_kfgins_imu, read_kfgins_imu
from gfins_fmi.io.raw_floats import read_floats
from gfins_fmi.io.records import ImuRecord, csv_line_of
from gfins_fmi.io.rtk_walk import STANDARD_GRAVITY_M_S2, read_rtk_walk_imu, rtk_walk_mounting
from gfins_fmi.io.tables import TableReader, pyarrow_module, table_format

__all__ = ["ImuChunks", "read_imu_record", "IMU_FORMATS"]

#: the IMU formats of ``gfins integrate --imu-format``
IMU_FORMATS = ("csv", "kfgins", "rtk_walk")
#: samples the head holds at least: the start of a run over increments is one interval
#: (the median of the first 100) before the first sample (cli/initial.py record_start_s)
_HEAD_SAMPLES = 101
#: Transform of a validated chunk (``--imu-errors``): (t, gyro, accel, kind, t_before) -> (gyro, accel)
Transform = Callable[[np.ndarray, np.ndarray, np.ndarray, str, "float | None"], tuple]


def read_imu_record(path, fmt: str = "csv", gps_week: int | None = None, n_columns: int = 7) -> ImuRecord:
    """A whole IMU record of any of :data:`IMU_FORMATS` (the readers of the whole record;
    Parquet and npz of our columns through :class:`ImuChunks`)."""
    path = pathlib.Path(path)
    if fmt == "kfgins":
        return read_kfgins_imu(path, n_columns, gps_week)
    if fmt == "rtk_walk":
        return read_rtk_walk_imu(path, rtk_walk_mounting())
    if fmt != "csv":
        raise ValueError(f"IMU format must be one of {IMU_FORMATS}; got {fmt!r}")
    if table_format(path) == "csv":
        return ImuRecord.from_csv(path)
    return ImuChunks(path, fmt).whole()


class ImuChunks:
    """An IMU file read as :class:`~gfins_fmi.io.records.ImuRecord` chunks.

    Parameters
    ----------
    path : str or path-like
    fmt : {"csv", "kfgins", "rtk_walk"}
        The format (module docstring); ``"csv"`` takes Parquet (``.parquet``, ``.pq``) and
        npz (``.npz``) of the same columns by the suffix.
    gps_week : int, optional
        KF-GINS: seconds of week -> GPS seconds (``--gps-week``).
    chunk : int
        Samples per chunk (the last may be shorter).
    n_columns : int
        KF-GINS text: the columns of a line (``imudatalen``; the first seven are read).

    Attributes
    ----------
    kind : {"increments", "rates"}
        What the file holds.
    t_end : float
        The time of the last sample (s, read from the file's end).
    first : ImuRecord
        The head of the record (:meth:`head`): at least its first chunk and 101 samples.

    Iteration yields the chunks from the file's start, each with the samples
    ``lo < t <= hi`` (:meth:`keep`), after the transform and conversion of :meth:`convert`.
    A file that breaks the format or a sample the record refuses raises
    :class:`~gfins_fmi.io.errors.FileFormatError` (naming the line of text) when its chunk
    is read.
    """

    def __init__(self, path, fmt: str = "csv", gps_week: int | None = None, chunk: int = 48_000,
                 n_columns: int = 7):
        self.path, self.fmt, self.chunk, self.n_columns = pathlib.Path(path), fmt, int(chunk), n_columns
        if fmt not in IMU_FORMATS:
            raise ValueError(f"IMU format must be one of {IMU_FORMATS}; got {fmt!r}")
        if gps_week is not None and (isinstance(gps_week, bool) or not isinstance(gps_week, (int, np.integer))
                                     or gps_week < 0):
            raise ValueError(f"gps_week must be a non-negative integer (GPS week number); got {gps_week!r}")
        self.offset_s = 0.0 if gps_week is None else float(int(gps_week) * 604800)
        self.lo, self.hi = -np.inf, np.inf
        self._transform, self._increments = None, False
        self.table = table_format(self.path) if fmt == "csv" else ("bin" if self._is_bin() else "csv")
        self.names, self.source_note, self._line_of = None, "", None
        self.kind = "rates" if fmt == "rtk_walk" else "increments"
        self._open_checks()
        self.t_end = self._last_time() + self.offset_s
        self.first = self.head()

    # --- the file -------------------------------------------------------------------------
    def _is_bin(self) -> bool:
        return self.fmt == "kfgins" and self.path.suffix.lower() == ".bin"

    def _what(self) -> str:
        return {"csv": "ImuRecord CSV" if self.table == "csv" else "IMU record", "kfgins": "KF-GINS IMU",
                "rtk_walk": "rtk_walk IMU CSV"}[self.fmt]

    def _open_checks(self) -> None:
        path = self.path
        if self.fmt == "kfgins":
            check_kfgins_imu(path, self.n_columns)
        if self.table == "bin":
            return
        if self.fmt == "csv" and self.table == "csv":
            self.names, self.source_note, header_line = ImuRecord.csv_head(path)
            self._line_of = csv_line_of(path, header_line)
        elif self.fmt == "csv":
            with TableReader(path, chunk_rows=1, what="IMU record") as r:
                self.names = tuple(r.names or ())
            ImuRecord.check_layout(path, self.names)
        else:
            if not path.is_file():
                raise not_a_file(path, f"{self._what()} file")
            self._line_of = self._text_line_of
        if self.names is not None:
            self.kind = "increments" if self.names[1] == "gyro_x_rad" else "rates"

    def _text_line_of(self, row: int) -> int:
        with open(self.path, encoding="utf-8", errors="replace") as f:
            return next(i for k, i in enumerate(data_lines(f, "#", 0)) if k == row) + 1

    def _last_time(self) -> float:
        """The time of the last sample, from the file's end."""
        path = self.path
        if self.table == "bin":
            with open(path, "rb") as f:
                f.seek(-56, 2)
                return float(np.frombuffer(f.read(8), "<f8")[0])
        if self.table == "parquet":
            _, pq = pyarrow_module()
            with pq.ParquetFile(path, pre_buffer=False) as pf:
                last = pf.read_row_group(pf.num_row_groups - 1, columns=["t_s"]).column(0)
                return float(last[len(last) - 1].as_py())
        if self.table == "npz":
            with zipfile.ZipFile(path) as z, z.open("t_s.npy") as fh:
                shape, _, dtype = _npy_header(fh)
                fh.seek(fh.tell() + (shape[0] - 1) * dtype.itemsize)
                return float(np.frombuffer(fh.read(dtype.itemsize), dtype)[0])
        with open(path, "rb") as f:
            f.seek(0, 2)
            size = f.tell()
            f.seek(max(0, size - 8192))
            lines = [x for x in f.read().split(b"\n") if x.strip() and not x.strip().startswith(b"#")]
        if not lines:
            raise FileFormatError(path, None, f"no data line (empty, or comments only): not a {self._what()} file")
        try:
            t = float(lines[-1].replace(b",", b" ").split()[0])
        except (IndexError, ValueError):
            raise FileFormatError(path, None, f"its last line ({lines[-1][:60]!r} ...) is not a row of numbers: "
                                  f"a cut or damaged {self._what()} file") from None
        return t - GPS_EPOCH_FROM_1970_S if self.fmt == "rtk_walk" else t

    def _first_line_has_comma(self) -> bool:
        with open(self.path, "rb") as f:
            first = next((line for line in f if line.strip()), b"")
        return b"," in first

    def _blocks(self) -> Iterator[np.ndarray]:
        """The file's rows, ``chunk`` at a time, as read (float64 (m, k))."""
        if self.table == "bin":
            # read, not mapped: a map's pages stay resident (and count in the peak) as the
            # record passes: 541 MiB for 10 h at 200 Hz where a chunk is 2.7 MB
            with open(self.path, "rb") as f:
                while True:
                    block = read_floats(f, 7 * self.chunk, "<f8")
                    if len(block) == 0:
                        return
                    yield block.reshape(-1, 7)
        # text in 4 MiB blocks: 16 MiB ones (the reader's default, a third faster to parse) cost
        # ~75 MiB more peak memory in a run (249 against 175 MiB, 30 min of our CSV)
        # KF-GINS's own loader splits at spaces, tabs and commas: a file whose first line has
        # a comma is read as CSV (as the whole-record reader does, io/kfgins.py)
        kw = {"kfgins": dict(whitespace=not self._first_line_has_comma()), "rtk_walk": {},
              "csv": dict(header=self.table == "csv",
                          header_hint="a CSV of a record has one header line")}[self.fmt]
        kw["block_bytes"] = 4 << 20
        with TableReader(self.path, chunk_rows=self.chunk, what=self._what(), **kw) as r:
            if self.fmt == "kfgins" and r.n_columns < 7:
                raise ValueError(f"{self.path}: {r.n_columns} columns; a KF-GINS IMU file has 7 (time, 3 angle "
                                 "and 3 velocity increments, forward-right-down) or more")
            if self.fmt == "rtk_walk" and r.n_columns != 11:
                raise FileFormatError(self.path, self._line_of(0), f"{r.n_columns} columns where a "
                                      "rtk_walk IMU CSV line has 11")
            for _, block in r:
                yield block

    def _record(self, block: np.ndarray, start: int, t_before: float | None) -> ImuRecord:
        """A block of rows as the whole-record reader converts them, validated."""
        if self.fmt == "kfgins":
            t, g, a = block[:, 0] + self.offset_s, frd_to_rfu(block[:, 1:4]), frd_to_rfu(block[:, 4:7])
            src = f"KF-GINS IMU file {self.path.name}: increments, FRD -> RFU (in chunks)"
        elif self.fmt == "rtk_walk":
            c = rtk_walk_mounting()
            t, g, a = (block[:, 0] - GPS_EPOCH_FROM_1970_S, block[:, 4:7] @ c.T,
                       (block[:, 1:4] * STANDARD_GRAVITY_M_S2) @ c.T)
            src = f"rtk_walk IMU file {self.path.name}: g -> m/s^2, sensor -> RFU (in chunks)"
        else:
            t, g, a = block[:, 0], block[:, 1:4], block[:, 4:7]
            src = self.source_note
        try:
            return ImuRecord.rows_of(start, t_before, t, g, a, self.kind, src)
        except RecordError as exc:
            line = self._line_of(exc.index) if (self._line_of and exc.index is not None) else None
            raise FileFormatError(self.path, line, str(exc)) from exc

    def _raw(self) -> Iterator[ImuRecord]:
        """Every sample of the file, validated, a chunk at a time."""
        start, t_before = 0, None
        for block in self._blocks():
            rec = self._record(block, start, t_before)
            start, t_before = start + len(rec), float(rec.t_s[-1])
            yield rec

    # --- what a run takes -----------------------------------------------------------------
    def convert(self, transform: Transform | None = None, increments: bool = False) -> None:
        """Set what every chunk goes through after validation: ``transform`` (the
        ``--imu-errors`` compensation, given the time before the chunk) and, for rates,
        ``increments``: the trapezoid of :meth:`ImuRecord.to_increments` across chunk
        boundaries (the first sample has no interval before it and is dropped). The head
        is converted again."""
        self._transform, self._increments = transform, increments and self.kind == "rates"
        self.first = self.head()

    def _converted(self, chunks: Iterator[ImuRecord]) -> Iterator[ImuRecord]:
        prev = None         # the last sample of the previous chunk, converted
        for rec in chunks:
            t = rec.t_s
            if self._transform is not None:
                g, a = self._transform(t, rec.gyro, rec.accel, rec.kind, None if prev is None else prev.t_s[-1])
                rec = ImuRecord(t, g, a, rec.kind, rec.source)
            out = rec
            if self._increments:
                both = rec if prev is None else ImuRecord(np.r_[prev.t_s[-1:], t], np.vstack([prev.gyro[-1:], rec.gyro]),
                                                          np.vstack([prev.accel[-1:], rec.accel]), rec.kind, rec.source)
                out = both.to_increments() if len(both) > 1 else None
            prev = rec
            if out is not None:
                yield out

    def head(self, until_s: float | None = None) -> ImuRecord:
        """The record's first samples, converted: whole chunks up to the one that holds
        ``until_s`` (s) and at least 101 samples (or the whole record if shorter)."""
        parts, n = [], 0
        gen = self._converted(self._raw())
        try:
            for rec in gen:
                parts.append(rec)
                n += len(rec)
                if n >= _HEAD_SAMPLES and (until_s is None or rec.t_s[-1] >= until_s):
                    break
        finally:
            gen.close()       # its file closed now, not when collected
        if not parts:
            raise FileFormatError(self.path, None, "no sample left once rates are made increments (one "
                                  "sample has no interval)")
        return _joined(parts)

    def whole(self) -> ImuRecord:
        """The whole record (converted) as one ImuRecord."""
        return _joined(list(self._converted(self._raw())))

    def start_at(self, start_s: float) -> None:
        """``first`` := the first chunk that reaches ``start_s`` (KF-GINS's starttime may
        lie minutes into the file)."""
        if self.first.t_s[-1] >= start_s:
            return
        gen = self._converted(self._raw())
        try:
            for rec in gen:
                if rec.t_s[-1] >= start_s:
                    self.first = rec
                    return
        finally:
            gen.close()
        raise ValueError(f"starttime {start_s:.10g} s is not before the IMU record's end ({self.t_end:.10g} s)")

    def keep(self, lo: float, hi: float | None) -> None:
        """Iterate over the samples with ``lo < t <= hi`` only (None: to the end)."""
        self.lo, self.hi = lo, (np.inf if hi is None else hi)

    def __iter__(self) -> Iterator[ImuRecord]:
        for rec in self._converted(self._raw()):
            t = rec.t_s
            if t[-1] <= self.lo:
                continue
            if t[0] > self.hi:
                return
            sel = (t > self.lo) & (t <= self.hi)
            if not np.all(sel):
                if not np.any(sel):
                    continue
                rec = ImuRecord(t[sel], rec.gyro[sel], rec.accel[sel], rec.kind, rec.source)
            yield rec


def _joined(parts: list[ImuRecord]) -> ImuRecord:
    if len(parts) == 1:
        return parts[0]
    return ImuRecord(np.concatenate([p.t_s for p in parts]), np.vstack([p.gyro for p in parts]),
                     np.vstack([p.accel for p in parts]), parts[0].kind, parts[0].source)


def _npy_header(fh):
    fmt = np.lib.format
    version = fmt.read_magic(fh)
    read = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
    return read(fh)
