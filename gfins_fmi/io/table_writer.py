"""Numeric tables written in chunks of rows (docs/io.md, "Tables"): a
:class:`TableWriter` appends chunks to a temporary file beside its destination and renames
it into place only in :meth:`TableWriter.commit`: a failed or interrupted write never
leaves half a file and never replaces an existing one. Formats as
:mod:`gfins_fmi.io.tables` reads them: CSV text (polars formats the numbers: the shortest
decimal that reads back as the same float64), npz (stored zip of ``.npy`` columns, in
place when the row count is known), Parquet (pyarrow, one row group per chunk).

The temporaries and the partial tables of a failed run are named in
:mod:`gfins_fmi.io.temporaries`; a run's whole set of files is
:class:`gfins_fmi.io.output_set.OutputSet`.
"""
from __future__ import annotations

import ctypes
import io
import os
import pathlib
import shutil
import struct
import zipfile
import zlib
from typing import Sequence

import numpy as np

from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.io.tables import checked_format, pyarrow_module
from gfins_fmi.io.temporaries import temporary_beside

__all__ = ["TableWriter"]

#: bytes copied at a time when assembling an npz file
_COPY_BYTES = 16 << 20

#: values formatted at a time by gf_text_fixed (its buffer: 40 bytes a value)
_FIXED_BLOCK_VALUES = 1 << 18

#: bytes of output written between two steps of :class:`_WriteBehind`
_WRITE_BEHIND_BYTES = 64 << 20


def _sync_file_range():
    """libc's ``sync_file_range`` (Linux), or None."""
    if not hasattr(os, "posix_fadvise"):
        return None
    try:
        fn = ctypes.CDLL(None, use_errno=True).sync_file_range
    except (OSError, AttributeError):    # pragma: no cover - not glibc/musl Linux
        return None
    fn.argtypes = [ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_uint]
    fn.restype = ctypes.c_int
    return fn


class _WriteBehind:
    """Keeps a long output out of the page cache: the ranges written since the last
    step are sent to the disk (without waiting), and those of the step before, by now
    written or nearly, are waited for and dropped from the cache.

    A record's output is written once and not read back; left to the kernel, all of
    it (gigabytes) stays in memory as dirty pages until written back, and filling
    memory with them costs the writer far more than the writing itself on a VM
    (3.6 GB written plainly: 6.6-13.2 s of system time; 1.3 s synced and dropped as it
    went; docs/benchmarks.md, "Record I/O"). Linux only (``sync_file_range`` and ``posix_fadvise``); elsewhere,
    and wherever a call fails (a file system without them), it does nothing."""

    #: SYNC_FILE_RANGE_WAIT_BEFORE, _WRITE, _WAIT_AFTER (linux/fs.h)
    _WAIT_BEFORE, _WRITE, _WAIT_AFTER = 1, 2, 4

    def __init__(self, fd: int):
        self._fd = fd
        self._fn = _sync_file_range()
        self._new: list[tuple[int, int]] = []     # (offset, length) since the last step
        self._sent: list[tuple[int, int]] = []    # sent to the disk at the last step
        self._bytes = 0

    def written(self, offset: int, length: int) -> None:
        """``length`` bytes were written at ``offset``."""
        if self._fn is None or length <= 0:
            return
        if self._new and self._new[-1][0] + self._new[-1][1] == offset:
            self._new[-1] = (self._new[-1][0], self._new[-1][1] + length)
        else:
            self._new.append((offset, length))
        self._bytes += length
        if self._bytes >= _WRITE_BEHIND_BYTES:
            self._step()

    def _step(self) -> None:
        fn, fd = self._fn, self._fd
        wait = self._WAIT_BEFORE | self._WRITE | self._WAIT_AFTER
        try:
            ok = all(fn(fd, offset, length, self._WRITE) == 0 for offset, length in self._new)
            for offset, length in self._sent if ok else ():
                ok = fn(fd, offset, length, wait) == 0
                if not ok:
                    break
                os.posix_fadvise(fd, offset, length, os.POSIX_FADV_DONTNEED)
        except OSError:
            ok = False
        if not ok:
            self._fn = None      # not on this file system: left to the kernel, as before
        self._sent, self._new, self._bytes = self._new, [], 0


class _CsvSink:
    """CSV text: ``# `` comment lines, the header line, then each chunk formatted by
    polars (the shortest decimal that reads back as the same float64), or, with
    ``float_format="repr"``, by Python (the same shortest digits in Python's notation:
    ``1e-05``, ``nan``)."""

    def __init__(self, tmp: pathlib.Path, names, dtypes, comments, rows=None, float_format=None,
                 decimals=None, separator=",", header=True):
        self.names, self.dtypes, self.float_format = names, dtypes, float_format
        self.decimals, self.separator = decimals, separator
        self._file = open(tmp, "wb")
        head = "".join(f"# {' '.join(c.split())}\n" for c in comments) + (separator.join(names) + "\n"
                                                                          if header else "")
        self._file.write(head.encode("utf-8"))
        self._end = len(head.encode("utf-8"))
        self._behind = _WriteBehind(self._file.fileno())

    def _fixed(self, arrays) -> bool:
        """Fixed decimals formatted in C (gf_text_fixed, ~13 ns a value), a block of rows
        at a time into one reused buffer; False when a value is beyond its range (then
        polars formats the chunk)."""
        m = len(arrays[0])
        k = len(arrays)
        rows = max(1, _FIXED_BLOCK_VALUES // k)     # a block's rows, whatever this chunk's length
        if getattr(self, "_buf", None) is None:
            self._cap = rows * k * 40
            self._buf = ffi.new("char[]", self._cap)
        n_written = ffi.new("size_t *")
        for lo in range(0, m, rows):
            hi = min(m, lo + rows)
            table = np.ascontiguousarray(np.column_stack([a[lo:hi] for a in arrays]), dtype=np.float64)
            status = lib.gf_text_fixed(hi - lo, k, ptr(table, table.size), self.decimals,
                                       self.separator.encode("ascii"), self._buf, self._cap, n_written)
            if status == lib.GF_ERR_OUT_OF_RANGE and lo == 0:
                return False
            if status != lib.GF_OK:
                raise ValueError(f"gf_text_fixed: status {int(status)}")
            self._file.write(ffi.buffer(self._buf, n_written[0]))
        return True

    def write(self, arrays) -> None:
        if (self.decimals is not None and len(self.separator) == 1 and self.decimals <= int(lib.GF_TEXT_MAX_DECIMALS)
                and all(a.dtype.kind == "f" for a in arrays) and self._fixed(arrays)):
            pass
        elif self.float_format == "repr":
            cols = [[repr(x) for x in a.tolist()] if a.dtype.kind == "f" else
                    [str(x) for x in a.tolist()] for a in arrays]
            self._file.write("".join(",".join(row) + "\n" for row in zip(*cols)).encode("utf-8"))
        else:
            import polars as pl   # lazy: polars costs start-up time (0.1-0.2 s)
            pl.DataFrame([pl.Series(n, a) for n, a in zip(self.names, arrays)]).write_csv(
                self._file, include_header=False, separator=self.separator, float_precision=self.decimals)
        self._file.flush()
        end = self._file.tell()
        self._behind.written(self._end, end - self._end)
        self._end = end

    def close(self) -> None:
        self._file.close()

    def abort(self) -> None:
        self._file.close()


class _ParquetSink:
    def __init__(self, tmp: pathlib.Path, names, dtypes, comments, rows=None, float_format=None, **text):
        pa, pq = pyarrow_module()
        self._pa = pa
        meta = {"gfins_fmi.comments": "\n".join(comments)} if comments else None
        self.schema = pa.schema([(n, pa.from_numpy_dtype(d)) for n, d in zip(names, dtypes)],
                                metadata=meta)
        # plain encoding: dictionaries of float noise only cost time (12x) and memory
        self._writer = pq.ParquetWriter(str(tmp), self.schema, compression="none",
                                        use_dictionary=False)
        # pyarrow writes the file through its own handle; this one follows its size
        self._fd = os.open(tmp, os.O_RDONLY)
        self._end = 0
        self._behind = _WriteBehind(self._fd)

    def write(self, arrays) -> None:
        pa = self._pa
        self._writer.write_batch(pa.RecordBatch.from_arrays(
            [pa.array(a, type=f.type) for a, f in zip(arrays, self.schema)], schema=self.schema))
        end = os.fstat(self._fd).st_size
        self._behind.written(self._end, end - self._end)
        self._end = end

    def close(self) -> None:
        try:
            self._writer.close()
        finally:
            if self._fd is not None:
                os.close(self._fd)
                self._fd = None

    def abort(self) -> None:
        try:
            self.close()
        except Exception:   # already failing: the file is deleted anyway
            pass


def _npy_head(dtype: np.dtype, rows: int) -> bytes:
    """The ``.npy`` header of a 1-D array of ``rows`` values of ``dtype``."""
    fmt = np.lib.format
    buf = io.BytesIO()
    fmt.write_array_header_1_0(buf, {"descr": fmt.dtype_to_descr(dtype), "fortran_order": False,
                                     "shape": (rows,)})
    return buf.getvalue()


class _ZipLayout:
    """A stored (uncompressed) zip64 archive whose members' sizes are known before
    their data (APPNOTE 6.3: local headers, data, central directory, zip64 end
    records): the data can be written in place, column by column and chunk by chunk,
    and the headers with their CRC-32 at the end."""

    _LOCAL = struct.Struct("<4s2B4HL2L2H")
    _CENTRAL = struct.Struct("<4s4B4HL2L5H2L")
    _END64 = struct.Struct("<4sQ2H2L4Q")
    _LOCATOR64 = struct.Struct("<4sLQL")
    _END = struct.Struct("<4s4H2LH")
    _DATE = (1 << 5) | 1                    # 1980-01-01 in DOS form, time 00:00

    def __init__(self, names: list[str], sizes: list[int]):
        self.names = [n.encode("utf-8") for n in names]
        self.sizes = sizes
        self.local, self.data = [], []
        pos = 0
        for name, size in zip(self.names, sizes):
            self.local.append(pos)
            pos += self._LOCAL.size + len(name) + 20
            self.data.append(pos)
            pos += size
        self.end = pos

    def headers(self, crcs: list[int]) -> list[tuple[int, bytes]]:
        """(offset, bytes) of every local header and of the central directory."""
        out = []
        central = b""
        for name, size, offset, crc in zip(self.names, self.sizes, self.local, crcs):
            extra = struct.pack("<2H2Q", 1, 16, size, size)
            out.append((offset, self._LOCAL.pack(b"PK\x03\x04", 45, 0, 0, 0, 0, self._DATE, crc,
                                                  0xFFFFFFFF, 0xFFFFFFFF, len(name), len(extra))
                        + name + extra))
            extra = struct.pack("<2H3Q", 1, 24, size, size, offset)
            central += (self._CENTRAL.pack(b"PK\x01\x02", 45, 3, 45, 0, 0, 0, 0, self._DATE, crc,
                                           0xFFFFFFFF, 0xFFFFFFFF, len(name), len(extra), 0, 0, 0,
                                           0o100644 << 16, 0xFFFFFFFF) + name + extra)
        n = len(self.names)
        end64 = self.end + len(central)
        central += (self._END64.pack(b"PK\x06\x06", 44, 45, 45, 0, 0, n, n, len(central), self.end)
                    + self._LOCATOR64.pack(b"PK\x06\x07", 0, end64, 1)
                    + self._END.pack(b"PK\x05\x06", 0, 0, 0xFFFF, 0xFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0))
        out.append((self.end, central))
        return out


def _pwrite(fd: int, data, offset: int) -> None:
    view = memoryview(data).cast("B")
    while view:
        done = os.pwrite(fd, view, offset)
        view, offset = view[done:], offset + done


class _NpzSink:
    """Columns as ``<name>.npy`` members of a stored zip. With the row count known
    beforehand (``rows``), each column's data is written in place, its CRC-32 kept as
    it goes, and the headers at :meth:`close`; otherwise (or when the count turns out
    different: a partial output) the columns go to raw side files, zipped at
    :meth:`close`."""

    def __init__(self, tmp: pathlib.Path, names, dtypes, comments, rows: int | None = None,
                 float_format=None, **text):
        self.tmp = tmp
        self.side = pathlib.Path(str(tmp) + ".d")
        self.names, self.dtypes = list(names), [np.dtype(d) for d in dtypes]
        self.rows = 0
        self._files = None
        self._fd = None
        if rows:
            self._planned = rows
            self._heads = [_npy_head(d, rows) for d in self.dtypes]
            self._zip = _ZipLayout([f"{n}.npy" for n in self.names],
                                   [len(h) + rows * d.itemsize for h, d in zip(self._heads, self.dtypes)])
            self._crcs = [zlib.crc32(h) for h in self._heads]
            self._fd = os.open(tmp, os.O_WRONLY)
            self._behind = _WriteBehind(self._fd)
        else:
            self._to_side_files()

    def _to_side_files(self) -> None:
        """From here on, columns go to side files (those written in place are moved)."""
        self.side.mkdir()
        self._files = [open(self.side / f"{j}.raw", "wb") for j in range(len(self.names))]
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
            with open(self.tmp, "rb") as src:
                for f, h, d, at in zip(self._files, self._heads, self.dtypes, self._zip.data):
                    src.seek(at + len(h))
                    left = self.rows * d.itemsize
                    while left:
                        piece = src.read(min(left, _COPY_BYTES))
                        f.write(piece)
                        left -= len(piece)

    def write(self, arrays) -> None:
        m = len(arrays[0])
        if self._fd is not None and self.rows + m > self._planned:
            self._to_side_files()
        if self._fd is not None:
            for j, (a, h, d, at) in enumerate(zip(arrays, self._heads, self.dtypes, self._zip.data)):
                a = np.ascontiguousarray(a)
                _pwrite(self._fd, a, at + len(h) + self.rows * d.itemsize)
                self._behind.written(at + len(h) + self.rows * d.itemsize, a.nbytes)
                self._crcs[j] = zlib.crc32(a, self._crcs[j])
        else:
            for f, a in zip(self._files, arrays):
                f.write(memoryview(np.ascontiguousarray(a)).cast("B"))
        self.rows += m

    def close(self) -> None:
        if self._fd is not None and self.rows == self._planned:
            for j, (h, at) in enumerate(zip(self._heads, self._zip.data)):
                _pwrite(self._fd, h, at)
            for offset, data in self._zip.headers(self._crcs):
                _pwrite(self._fd, data, offset)
            os.close(self._fd)
            self._fd = None
            return
        if self._fd is not None:
            self._to_side_files()
        for f in self._files:
            f.close()
        fmt = np.lib.format
        with zipfile.ZipFile(self.tmp, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
            for j, (name, dtype) in enumerate(zip(self.names, self.dtypes)):
                with zf.open(f"{name}.npy", "w", force_zip64=True) as out, \
                        open(self.side / f"{j}.raw", "rb") as raw:
                    fmt.write_array_header_1_0(out, {"descr": fmt.dtype_to_descr(dtype),
                                                     "fortran_order": False, "shape": (self.rows,)})
                    shutil.copyfileobj(raw, out, _COPY_BYTES)
        shutil.rmtree(self.side)

    def abort(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        for f in self._files or ():
            f.close()
        shutil.rmtree(self.side, ignore_errors=True)


_SINKS = {"csv": _CsvSink, "parquet": _ParquetSink, "npz": _NpzSink}


class TableWriter:
    """A table file written in chunks, put under its name only by :meth:`commit`.

    Parameters
    ----------
    path : str or path-like
        The destination; its format from its suffix (:func:`table_format`). An existing
        file there is replaced only when :meth:`commit` succeeds.
    names : sequence of str
        Column names (letters, digits, ``_``; they carry the units: ``t_s``, ``v_e_m_s``).
    dtypes : sequence of numpy dtypes, optional
        Per column: float64 (the default) or an integer type (flags).
    comments : sequence of str
        CSV: ``# `` lines before the header (one line each); Parquet: the file's
        metadata ``gfins_fmi.comments``; npz: not kept.
    format : {"csv", "npz", "parquet"}, optional
        The format, whatever the file's name (default: from the name).
    rows : int, optional
        The number of rows expected, when known (a binary input): an npz file is then
        written in place, without side files (any other count is still written right).
    float_format : {None, "repr"}, optional
        CSV only: ``"repr"`` writes every value as Python's ``repr`` (the same shortest
        round-trip digits as the default, in Python's notation: ``1e-05`` where polars
        writes ``0.00001``, ``nan`` for ``NaN``), row by row in Python — for small tables
        whose bytes must stay those of an earlier writer (the innovation log of ``gfins
        integrate``).
    decimals, separator, header : optional
        CSV only: fixed ``decimals`` after the point (a format that defines them, as
        KF-GINS's ``%.9f``), the field ``separator`` (default ","), no line of column
        names with ``header=False``.

    output_set : OutputSet, optional
        The run's set of files this table belongs to
        (:meth:`gfins_fmi.io.output_set.OutputSet.table` passes it): :meth:`commit` then
        only finishes the file, and the set renames it with the others when the whole
        run has succeeded; the temporary lives as long as the set, and leaving the
        ``with`` block without a commit leaves the rows to the set (its partial file, or
        nothing when it is discarded).

    Text columns (dtype ``str``: words without commas, quotes or line breaks, such as
    the names of measurement kinds) are written to CSV only.

    Use as a context manager: leaving the block without :meth:`commit` (an exception,
    Ctrl-C) deletes the temporary file and leaves the destination as it was::

        with TableWriter("sol.csv", ["t_s", "x_m"]) as w:
            for chunk in ...:
                w.write([t, x])
            w.commit()
    """

    def __init__(self, path, names: Sequence[str], dtypes: Sequence | None = None, *,
                 comments: Sequence[str] = (), format: str | None = None,
                 rows: int | None = None, float_format: str | None = None, output_set=None,
                 decimals: int | None = None, separator: str = ",", header: bool = True):
        self.path = pathlib.Path(path)
        self.names = tuple(names)
        if not self.names or not all(isinstance(n, str) and n and n.replace("_", "a").isalnum()
                                     for n in self.names):
            raise ValueError(f"column names must be non-empty words of letters, digits and _; "
                             f"got {self.names!r}")
        self.dtypes = tuple(np.dtype(d) for d in (dtypes or [np.float64] * len(self.names)))
        if len(self.dtypes) != len(self.names) or any(d.kind not in "iufU" for d in self.dtypes):
            raise ValueError(f"dtypes must give a numeric type (or str) per column "
                             f"({len(self.names)}); got {dtypes!r}")
        self.format = checked_format(self.path, format)
        if float_format not in (None, "repr"):
            raise ValueError(f"float_format must be None or 'repr'; got {float_format!r}")
        if self.format != "csv" and (float_format or any(d.kind == "U" for d in self.dtypes)
                                     or decimals is not None or separator != "," or not header):
            raise ValueError(f"{self.path}: text columns, float_format, decimals, separator and header "
                             "are CSV only")
        if decimals is not None and (float_format or not 0 <= int(decimals) <= 17):
            raise ValueError(f"decimals must be 0..17 and exclude float_format; got {decimals!r}")
        if self.path.is_dir():
            raise IsADirectoryError(f"{self.path} is a folder: give a file name for the output")
        self.output_set = output_set
        self._tmp, self._remove = temporary_beside(
            self.path, self if output_set is None else output_set,
            None if output_set is None else output_set.temporaries)
        try:
            text = {"decimals": decimals, "separator": separator, "header": header} if self.format == "csv" else {}
            self._sink = _SINKS[self.format](self._tmp, self.names, self.dtypes, list(comments),
                                             rows, float_format, **text)
        except BaseException:
            self._remove()
            raise
        self.rows = 0
        self._open = True

    def write(self, columns: Sequence) -> None:
        """Append rows: one 1-D array per column, all of one length."""
        if not self._open:
            raise ValueError(f"{self.path}: the writer is closed")
        if len(columns) != len(self.names):
            raise ValueError(f"{len(columns)} columns given for {len(self.names)} names")
        arrays = [np.asarray(c, dtype=d) for c, d in zip(columns, self.dtypes)]
        m = arrays[0].shape[0] if arrays[0].ndim == 1 else -1
        if any(a.ndim != 1 or a.shape[0] != m for a in arrays):
            raise ValueError("columns must be 1-D arrays of one length; got shapes "
                             f"{[a.shape for a in arrays]}")
        for name, a in zip(self.names, arrays):
            if a.dtype.kind == "U" and any(set(x) & set(',"\r\n') for x in a.tolist()):
                raise ValueError(f"text column {name}: values must not hold commas, quotes or "
                                 "line breaks")
        self._sink.write(arrays)
        self.rows += m

    @property
    def temporary(self) -> pathlib.Path:
        """The file being written (beside :attr:`path`)."""
        return self._tmp

    def finish(self) -> pathlib.Path:
        """Close the file without renaming it; returns the temporary, which is removed
        like an unfinished one unless a set (``output_set``) renames it."""
        if not self._open:
            raise ValueError(f"{self.path}: the writer is closed")
        self._open = False
        try:
            self._sink.close()
        except BaseException:
            self._cleanup()
            raise
        return self._tmp

    def release(self) -> None:
        """The finished temporary is the caller's now (an output set renames or removes
        it): the writer no longer removes it."""
        self._remove.detach()

    def commit(self) -> pathlib.Path:
        """Finish the file and rename it to :attr:`path` (replacing any file there); in
        an ``output_set``, finish it and leave the renaming to the set's commit."""
        self.finish()
        if self.output_set is not None:
            self.output_set.finished(self)
            return self.path
        try:
            os.replace(self._tmp, self.path)
            self._remove.detach()
        except BaseException:
            self._cleanup()
            raise
        return self.path

    def discard(self) -> None:
        """Drop what was written; the destination stays as it was."""
        if self._open:
            self._open = False
            self._sink.abort()
            self._cleanup()

    def _cleanup(self) -> None:
        self._remove()

    def __enter__(self) -> "TableWriter":
        return self

    def __exit__(self, *exc) -> None:
        # a table of a set: what was written is the set's to keep (its partial file) or
        # drop, when the run ends; alone: dropped unless committed
        if self.output_set is None:
            self.discard()
