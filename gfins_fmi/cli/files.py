"""What the commands read and write, in one place: every command's outputs are one
:class:`~gfins_fmi.io.output_set.OutputSet` (:func:`outputs`: no output is an input, the
files appear together when the run has succeeded, partial tables are named as such);
the record commands' streaming path (a :class:`~gfins_fmi.io.TableReader` in chunks ->
the solver -> a table of the set, with the time column checked as it streams and a
progress bar); and the recorded files of the estimation commands read by format
(:func:`read_imu`, :func:`read_gnss`, ...), with messages that name the file and what is
wrong with it."""
from __future__ import annotations

import re
import sys

import numpy as np

from gfins_fmi import io
from gfins_fmi._lib import NonFiniteInputError
from gfins_fmi.io.imu_stream import read_imu_record
from gfins_fmi.io.output_set import OutputSet
from gfins_fmi.io.tables import TableReader

__all__ = ["TimeColumn", "Refused", "outputs", "record_reader", "stream", "nav_columns",
           "read_imu", "read_gnss", "read_optional", "read_truth", "cause", "run_writing",
           "compensated", "compensated_block"]


#: relative tolerance of a fixed sampling interval in a time column: timestamps rounded
#: to microseconds at 1 kHz, or written with 6 decimals at 100 Hz, stay well inside it
_UNIFORM_RTOL = 1e-3


class TimeColumn:
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
#: progress bars by default from this input size on: 10^6 samples (binary), or about as
#: many lines of text
_PROGRESS_ROWS, _PROGRESS_BYTES = 1_000_000, 64 << 20


#: the end of a solver's message that points to the exception's ``.partial`` attribute (the
#: API's); the commands name the partial file instead
_PARTIAL_NOTE = re.compile(r"; (no sample was \w+ before it \(\.partial is empty\)|"
                           r"samples? [\d.]+ (was|were) \w+ \(see \.partial\)|"
                           r"the solution before it is in \.partial)$")


def cause(error: Exception) -> str:
    """A solver's message without the API's pointer to ``.partial``."""
    return _PARTIAL_NOTE.sub("", str(error))


def outputs(*inputs) -> OutputSet:
    """The set of files a command writes; ``inputs``: its input files (None skipped),
    which no output may be."""
    return OutputSet(inputs)


def run_writing(run, args, inputs=(), files=(), folder=None) -> int:
    """``run(args, outs)`` with the command's outputs as one set: ``files`` (None skipped)
    and the figure ``folder`` claimed before the run, the set committed when it returns
    (nothing of it kept if it raises)."""
    with outputs(*inputs) as outs:
        for path in files:
            if path:
                outs.claim(path)
        if folder:
            outs.claim_folder(folder)
        status = run(args, outs)
        outs.commit()
        return status


class Refused(Exception):
    """The solver refused a sample: ``error`` (with ``.partial``) and the output
    columns of the ``rows`` before it in the chunk."""

    def __init__(self, error: Exception, columns: list, rows: int):
        super().__init__(str(error))
        self.error, self.columns, self.rows = error, columns, rows


def record_reader(args, what: str):
    """The input of a record command, read in chunks of ``--chunk`` rows."""
    return TableReader(args.input, header=args.header, chunk_rows=args.chunk, what=what,
                       header_hint=_HEADER_HINT)


def stream(args, outs: OutputSet, reader, names, dtypes, solve, verb: str,
           group: int = 1) -> tuple[int, int]:
    """Read, solve and write a record chunk by chunk: ``solve(start, block)`` gives the
    output columns of the rows of ``block`` (the first is row ``start``) or raises
    :class:`Refused`. The output, a table of ``outs``, appears under ``args.output`` when
    the whole record is done (``outs`` is committed here). After a refused sample the
    rows before it go to the partial file (``sol.partial.csv``, its first line says
    where and why it stopped) and ``args.output`` stays as it was; when there is no row
    before it, nothing is written.

    Returns (status, rows written): status 0, or 1 after a refused sample. ``group``:
    input rows per output row (the last output row takes the rows left).
    """
    status, error = 0, None
    with reader, outs.table(args.output, names, dtypes,
                            rows=None if reader.n_rows is None else -(-reader.n_rows // group)) as writer, \
            _progress(args, reader, verb) as bar:
        for start, block in reader:
            try:
                cols = solve(start, block)
            except Refused as refused:
                if refused.rows:
                    writer.write(refused.columns)
                status, error = 1, refused.error
                break
            writer.write(cols)
            bar.update(reader.position - bar.n)
            bar.set_postfix_str(f"{writer.rows} samples")
        else:
            bar.update(reader.size - bar.n)     # trailing comment lines, if any
        if status:
            why = cause(error)
            at = getattr(error, "index", None)
            where = f"input row {at}" if isinstance(at, int) and at >= 0 else "a refused sample"
            rows = writer.rows
            outs.keep_partial(f"stopped at {where} of {args.input}: {why}; the {rows} rows here "
                              f"are the samples {verb} before it")
            if rows == 0:
                print(f"error: {why}; no sample was {verb}: {outs.outcome()}", file=sys.stderr)
            else:
                print(f"error: {why}; the {rows} samples {verb} before it are in "
                      f"{_names(outs.partial)} ({outs.outcome().split('; ', 1)[1]})", file=sys.stderr)
            return status, rows
        writer.commit()
    outs.commit()
    return status, writer.rows


def _names(paths) -> str:
    return ", ".join(str(p) for p in paths)


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
    from tqdm import tqdm   # lazy: only with a progress bar
    text = reader.unit == "B"
    return tqdm(total=reader.size, unit="B" if text else " samples", unit_scale=True,
                unit_divisor=1024 if text else 1000, desc=f"read, {verb[:-1]}, write")


def nav_columns(sol) -> list:
    """The columns of :data:`~gfins_fmi.io.columns.NAV_COLUMNS` from a NavSolution: time,
    latitude and longitude (deg), height (m), ENU velocity (m/s), Euler angles (deg),
    quaternion."""
    deg = 180.0 / np.pi
    e = sol.euler_rad * deg if len(sol) else np.empty((0, 3))
    return ([sol.t_s, sol.lat_rad * deg, sol.lon_rad * deg, sol.h_m]
            + [sol.v_n_m_s[:, j] for j in range(3)] + [e[:, j] for j in range(3)]
            + [sol.q_bn[:, j] for j in range(4)])


def read_imu(path, fmt: str = "csv", gps_week=None, n_columns: int = 7):
    """A whole IMU record: ``csv`` (our ImuRecord: CSV text, or Parquet / npz of its
    columns), ``kfgins`` (KF-GINS IMU text/.bin: increments, front-right-down; ``n_columns``
    of its text) or ``rtk_walk`` (the rtk_walk CSV, with its mounting)
    (:func:`gfins_fmi.io.imu_stream.read_imu_record`)."""
    return read_imu_record(path, fmt, gps_week, n_columns)


def read_gnss(path, fmt: str = "pos", gps_week=None):
    """A GNSS record: ``pos`` (RTKLIB .pos), ``kfgins`` (KF-GINS GNSS text) or ``csv``
    (our GnssRecord CSV)."""
    if fmt == "pos":
        return io.read_rtklib_pos(path)
    if fmt == "kfgins":
        return io.read_kfgins_gnss(path, gps_week=gps_week)
    return io.GnssRecord.from_csv(path)


def read_optional(record_type, path):
    """``record_type.from_csv(path)``, or None without a path (an optional sensor)."""
    return record_type.from_csv(path) if path else None


def read_truth(path, gps_week=None):
    """A reference: a KF-GINS ``.nav`` file or our TruthRecord CSV (None without a path)."""
    if not path:
        return None
    return (io.read_kfgins_nav(path, gps_week=gps_week) if path.suffix == ".nav"
            else io.TruthRecord.from_csv(path))


def compensated(imu, errors):
    """An ImuRecord with the IMU errors removed (``--imu-errors``): rates by
    ImuErrors.compensate, increments through the mean rate of each interval
    (compensate_increments; the first interval taken as long as the second)."""
    if errors is None:
        return imu
    if imu.kind == "rates":
        w, f = errors.compensate(imu.gyro, imu.accel)
    else:
        first = imu.t_s[1] - imu.t_s[0] if len(imu) > 1 else 1.0
        dt = np.diff(imu.t_s, prepend=imu.t_s[0] - first)
        w, f = errors.compensate_increments(imu.gyro, imu.accel, dt)
    return io.ImuRecord(t_s=imu.t_s, gyro=w, accel=f, kind=imu.kind, source=f"{imu.source}; compensated")


def compensated_block(errors, t, gyro, accel, kind: str, t_prev=None):
    """One chunk of a streamed record compensated (``--imu-errors``): (gyro, accel). Rows
    from the first one the error model refuses (not finite) on are passed as they are,
    for the navigator to refuse at the same row with its own message. ``t_prev``: the
    time before the chunk (increments: the first interval)."""
    if kind == "rates":
        fn, args = errors.compensate, ()
    else:
        before = t_prev if t_prev is not None else (t[0] - (t[1] - t[0]) if len(t) > 1 else t[0] - 1.0)
        fn, args = errors.compensate_increments, (np.diff(t, prepend=before),)
    try:
        return fn(gyro, accel, *args)
    except NonFiniteInputError as exc:
        k = exc.index
        w, f = exc.partial
        return np.vstack([w, gyro[k:]]), np.vstack([f, accel[k:]])
