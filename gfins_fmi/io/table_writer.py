"""Numeric tables in files, read and written in chunks of rows: CSV text, npz and
Parquet (docs/io.md, "Tables").

A :class:`TableReader` yields a file's rows in chunks of a fixed number of rows
(float64, C-contiguous), so a record of any length flows through the C core with
bounded memory: read a chunk, run it, write it. A :class:`TableWriter` appends chunks
to a temporary file beside its destination and renames it into place only in
:meth:`TableWriter.commit`: a failed or interrupted write never leaves half a file and
never replaces an existing one.

Formats, by the file name's suffix (:func:`table_format`):

``.npz``
    numpy's zip of ``.npy`` arrays: one 1-D array per column, named by the column
    (what this writer makes: ``np.load(path)["t_s"]``), or a single 2-D array (n, k).
    Stored uncompressed and streamed member by member; written in place when the row
    count is known beforehand, otherwise through side files zipped at the end.
``.parquet``, ``.pq``
    Apache Parquet: named numeric columns, one row group per chunk. Needs pyarrow
    (the optional extra ``gfins_fmi[parquet]``).
anything else
    CSV text: comma-separated numbers, one row per line; ``#`` comment lines and blank
    lines are skipped, spaces and tabs ignored; with ``header=True`` the first other
    line holds the column names (or, when that line holds numbers, the comment line
    before it, as numpy's ``savetxt`` writes a header). Numbers in the usual forms,
    ``nan`` and ``inf`` included; written as the shortest decimal that reads back as
    the same float64 (``0.1``, ``1e-7``, ``0.00002201446582700049``), so every value
    round-trips bit for bit.

CSV parsing and formatting are polars' (Rust; shortest round-trip digits): 40-55 ns
a value to read and 55-65 ns to write on one core of the development machine, where
numpy's ``loadtxt`` takes 300 ns and ``savetxt`` 900 ns (docs/io.md, "Why polars";
docs/benchmarks.md, "Record I/O"). When polars refuses a block of lines, the block is scanned in Python to
name the line at fault (:func:`gfins_fmi.io._text.diagnose`).
"""
from __future__ import annotations

import os
import pathlib
import secrets
import shutil
import struct
import weakref
import zipfile
import zlib
from typing import Iterator, Sequence

import numpy as np

from gfins_fmi.io._text import is_number, diagnose
from gfins_fmi.io.errors import FileFormatError

__all__ = ["TableReader", "TableWriter", "table_format", "FORMATS", "DEFAULT_CHUNK_ROWS"]

#: the formats, as :func:`table_format` names them
FORMATS = ("csv", "parquet", "npz")
#: rows per chunk: 2^18 rows of 10 float64 columns are 21 MB, a few tenths of a second
#: of parsing; large enough that per-chunk costs vanish, small enough for a smooth
#: progress bar and a small memory footprint
DEFAULT_CHUNK_ROWS = 1 << 18
#: bytes of text parsed at a time (whole lines): polars' cost per call is about that of
#: 1 MB of text, so 16 MB blocks parse a third faster than 4 MB (docs/benchmarks.md,
#: "Record I/O"); the text, its columns and the chunk are 40 MB or so
_TEXT_BLOCK_BYTES = 16 << 20
#: bytes copied at a time when assembling an npz file
_COPY_BYTES = 16 << 20


def table_format(path) -> str:
    """The format of a table file from its name: ``"parquet"`` (``.parquet``, ``.pq``),
    ``"npz"`` (``.npz``), otherwise ``"csv"`` (text)."""
    suffix = pathlib.Path(path).suffix.lower()
    if suffix in (".parquet", ".pq"):
        return "parquet"
    if suffix == ".npz":
        return "npz"
    return "csv"


def _format(path, format: str | None) -> str:
    if format is None:
        return table_format(path)
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}; got {format!r}")
    return format


def _chunk_rows(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"chunk_rows must be an integer >= 1; got {value!r}")
    return int(value)


# --- reading ---------------------------------------------------------------------------------

class _TextSource:
    """CSV text: read in blocks of whole lines, each parsed by polars. The head of the
    file (comments, the header line, the first data line) is read here to know the
    columns; the line number of each block's start is counted, so a refused block is
    diagnosed alone, naming the line."""

    format = "csv"

    def __init__(self, path: pathlib.Path, header: bool, what: str, header_hint: str):
        self.path, self.what = path, what
        self.header_message = ("the first data line holds text ({text}) where numbers were "
                               f"expected: {header_hint}")
        self.n_rows = None
        self.size = path.stat().st_size
        skip, offset, names, first, comment = 0, 0, None, None, None
        with open(path, "rb") as f:
            for raw in f:
                body = raw.decode("utf-8", errors="replace").strip()
                if not body or body.startswith("#"):
                    skip, offset = skip + 1, offset + len(raw)
                    comment = body[1:] if body else comment
                    continue
                fields = body.split(",")
                if header and names is None:
                    if not all(is_number(x) for x in fields):
                        names = tuple(x.strip() for x in fields)
                        skip, offset = skip + 1, offset + len(raw)
                        continue
                    # numbers: the names may be the comment line before them, as numpy's
                    # savetxt writes its header ("# t,gx,gy")
                    if comment is None or len(comment.split(",")) != len(fields):
                        raise FileFormatError(path, skip + 1, "a header line of column names was "
                                              "expected, but the first line holds numbers")
                    names = tuple(x.strip() for x in comment.split(","))
                first = fields
                break
        if first is None:
            if names is not None:
                raise FileFormatError(path, None, f"no data lines after the header line "
                                      f"({','.join(names)}): a {what} holds at least one row")
            raise FileFormatError(path, None, f"no data lines: the file is empty (a {what} holds "
                                  "one row of numbers per line)")
        self.names, self.n_columns = names, len(first)
        self._skip, self._offset = skip, offset
        if names is not None and len(names) != self.n_columns:
            raise FileFormatError(path, skip + 1, f"{self.n_columns} columns where the header line "
                                  f"names {len(names)} ({','.join(names)})")
        self.position = 0

    def batches(self) -> Iterator[list[np.ndarray]]:
        offset, rows, rest = self._offset, 0, b""
        with open(self.path, "rb") as f:
            f.seek(offset)
            while True:
                buf = f.read(_TEXT_BLOCK_BYTES)
                if buf:
                    cut = buf.rfind(b"\n") + 1
                    if cut == 0:          # a line longer than a block: read on
                        rest += buf
                        continue
                    # the lines: one copy (none when the block ends a line); the partial
                    # line after them starts the next block
                    view = memoryview(buf)
                    block = b"".join((rest, view[:cut])) if rest or cut < len(buf) else buf
                    rest = bytes(view[cut:])
                else:
                    block, rest = rest, b""
                if block:
                    cols = self._parse(block, offset, rows)
                    self.position = offset = f.tell() - len(rest)
                    if len(cols[0]):
                        rows += len(cols[0])
                        yield cols
                if not buf:
                    break

    def _parse(self, block: bytes, offset: int, rows: int) -> list[np.ndarray]:
        """The columns of a block of whole lines that starts at byte ``offset`` of the
        file, its first data line row ``rows`` of the table."""
        import polars as pl
        k = self.n_columns
        text = block.translate(None, b" \t") if (b" " in block or b"\t" in block) else block
        # comment lines are looked for only in a block that holds a '#': polars parses
        # 40 % slower when it must look for them
        comment = "#" if b"#" in block else None
        try:
            df = pl.read_csv(text, has_header=False, schema=self._schema(), comment_prefix=comment,
                             quote_char=None)
        except pl.exceptions.PolarsError as exc:
            err = self._diagnose(block, offset, rows)
            if err.line is None and not any(_data(x) for x in block.split(b"\n")):
                return [np.empty(0)] * k          # comments and blank lines only
            raise (err if err.line is not None else FileFormatError(
                self.path, None, f"the file could not be read as a {self.what} table ({exc})")) from None
        if df.null_count().sum_horizontal().item():
            # a blank line reads as a row of nulls (dropped); a missing or empty field
            # leaves a null in a row with numbers (refused)
            blank = df.select(pl.all_horizontal(pl.all().is_null())).to_series()
            if k > 1 and (df.null_count().sum_horizontal().item() > k * int(blank.sum())):
                raise self._diagnose(block, offset, rows)
            df = df.filter(~blank)
        return [s.to_numpy() for s in df.get_columns()]

    def _schema(self):
        import polars as pl
        return {f"c{j}": pl.Float64 for j in range(self.n_columns)}

    def _diagnose(self, block: bytes, offset: int, rows: int) -> FileFormatError:
        """The line at fault in a refused block (the lines before it are counted only
        now: a good file is never scanned in Python)."""
        line = 0
        with open(self.path, "rb") as f:
            while f.tell() < offset:
                line += f.read(min(_TEXT_BLOCK_BYTES, offset - f.tell())).count(b"\n")
        lines = block.decode("utf-8", errors="replace").split("\n")
        # comment lines of another width are comments; one of k fields is a row to polars
        k = self.n_columns
        lines = ["" if x.lstrip().startswith("#") and x.count(",") + 1 != k else x for x in lines]
        return diagnose(self.path, lines, ",", None, 0, [k], self.what, self.header_message,
                        first_row=rows, line_offset=line)

    def close(self) -> None:
        pass


def _data(line: bytes) -> bool:
    body = line.strip()
    return bool(body) and not body.startswith(b"#")


def _pyarrow():
    """pyarrow and pyarrow.parquet, or a ValueError that says how to get them."""
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        raise ValueError("Parquet files need pyarrow, which is not installed: pip install "
                         "'gfins_fmi[parquet]' (or use .npz or .csv)") from None
    return pyarrow, pyarrow.parquet


def _numeric(path, name: str, dtype) -> None:
    if np.dtype(dtype).kind not in "iuf":
        raise FileFormatError(path, None, f"column {name!r} holds {dtype}, not numbers")


class _ParquetSource:
    format = "parquet"

    def __init__(self, path: pathlib.Path, chunk_rows: int):
        pa, pq = _pyarrow()
        try:
            # no pre-buffering: it reads the whole file ahead (memory = file size)
            self._pf = pq.ParquetFile(path, pre_buffer=False)
        except (pa.ArrowInvalid, OSError) as exc:
            raise FileFormatError(path, None, f"not a Parquet file ({exc})") from None
        schema = self._pf.schema_arrow
        for field in schema:
            if not (pa.types.is_integer(field.type) or pa.types.is_floating(field.type)):
                raise FileFormatError(path, None, f"column {field.name!r} holds {field.type}, "
                                      "not numbers")
        self.path, self.chunk_rows = path, chunk_rows
        self.names = tuple(schema.names)
        self.n_columns = len(self.names)
        self.n_rows = self.size = int(self._pf.metadata.num_rows)
        self.position = 0
        if self.n_columns == 0 or self.n_rows == 0:
            raise FileFormatError(path, None, "no data: the file holds no column or no row")

    def batches(self) -> Iterator[list[np.ndarray]]:
        rows = 0
        try:
            for batch in self._pf.iter_batches(batch_size=self.chunk_rows, use_threads=False):
                cols = []
                for name, col in zip(self.names, batch.columns):
                    if col.null_count:
                        k = rows + int(np.flatnonzero(col.is_null().to_numpy(zero_copy_only=False))[0])
                        raise FileFormatError(self.path, None, f"column {name!r}, row {k}: no value "
                                              "(null); every field must hold a number")
                    cols.append(col.to_numpy())
                rows += batch.num_rows
                self.position = rows
                yield cols
        finally:
            self.close()

    def close(self) -> None:
        self._pf.close()


class _NpzSource:
    """An npz file streamed member by member: its members' ``.npy`` headers give shapes
    and types; the data are read in chunks from the members' streams."""

    format = "npz"

    def __init__(self, path: pathlib.Path, chunk_rows: int):
        self.chunk_rows = chunk_rows
        try:
            self._zip = zipfile.ZipFile(path)
        except (zipfile.BadZipFile, OSError) as exc:
            raise FileFormatError(path, None, f"not an npz (zip) file ({exc})") from None
        self.path = path
        members = self._zip.namelist()
        heads = []
        for m in members:
            if not m.endswith(".npy"):
                raise FileFormatError(path, None, f"member {m!r} is not a .npy array: an npz "
                                      "record holds .npy arrays only")
            with self._zip.open(m) as fh:
                shape, fortran, dtype = _npy_header(path, m, fh)
                heads.append((m, shape, fortran, dtype, fh.tell()))
        layout = ("an npz record holds one 2-D array (n, k) or 1-D arrays of one length, "
                  "one per column")
        if len(heads) == 1 and len(heads[0][1]) == 2:
            m, (n, k), fortran, dtype, offset = heads[0]
            _numeric(path, m, dtype)
            self.names = None
            # C order: rows are contiguous, one stream; Fortran order: one stream per column
            self._plan = ([(m, offset, dtype, k)] if not fortran else
                          [(m, offset + j * n * dtype.itemsize, dtype, 1) for j in range(k)])
        elif heads and all(len(h[1]) == 1 for h in heads):
            lengths = {h[1][0] for h in heads}
            if len(lengths) != 1:
                raise FileFormatError(path, None, f"{layout}; the 1-D arrays have lengths "
                                      f"{sorted(lengths)}")
            for h in heads:
                _numeric(path, h[0], h[3])
            n, k = heads[0][1][0], len(heads)
            self.names = tuple(h[0][:-4] for h in heads)
            self._plan = [(h[0], h[4], h[3], 1) for h in heads]
        else:
            shapes = ", ".join(f"{h[0]} {h[1]}" for h in heads) or "nothing"
            raise FileFormatError(path, None, f"{layout}; found {shapes}")
        self.n_rows, self.n_columns, self.size = int(n), int(k), int(n)
        if self.n_rows == 0 or self.n_columns == 0:
            raise FileFormatError(path, None, "no data: the arrays are empty")
        self.position = 0

    def batches(self) -> Iterator[list[np.ndarray]]:
        streams = []
        try:
            for m, offset, dtype, width in self._plan:
                fh = self._zip.open(m)
                fh.seek(offset)
                streams.append((fh, dtype, width))
            rows = 0
            while rows < self.n_rows:
                m = min(self.chunk_rows, self.n_rows - rows)
                cols = []
                for fh, dtype, width in streams:
                    nbytes = m * width * dtype.itemsize
                    buf = fh.read(nbytes)
                    if len(buf) != nbytes:
                        raise FileFormatError(self.path, None, "an array ends before its header's "
                                              "shape says: the file is truncated")
                    a = np.frombuffer(buf, dtype=dtype).reshape(m, width)
                    cols.extend(a[:, j] for j in range(width))
                rows += m
                self.position = rows
                yield cols
        finally:
            for fh, _, _ in streams:
                fh.close()
            self.close()

    def close(self) -> None:
        self._zip.close()


def _npy_header(path, member: str, fh):
    fmt = np.lib.format
    try:
        version = fmt.read_magic(fh)
        read = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
        shape, fortran, dtype = read(fh)
    except ValueError as exc:
        raise FileFormatError(path, None, f"member {member!r} is not a .npy array ({exc})") from None
    return shape, fortran, dtype


class TableReader:
    """A table file read in chunks of rows.

    Parameters
    ----------
    path : str or path-like
        The file; its format from its suffix (:func:`table_format`).
    header : bool
        CSV text: the first line that is not a comment holds the column names.
    chunk_rows : int
        Rows per chunk (the last may be shorter).
    what : str
        What the file holds, for messages ("navigation record").
    header_hint : str
        The end of the message when the first data line of a text file holds text
        (default: how to read it with this class).
    format : {"csv", "npz", "parquet"}, optional
        The format, whatever the file's name (default: from the name).

    Attributes
    ----------
    format : str
    n_columns : int
    names : tuple of str or None
        Column names (Parquet, npz of columns, CSV with a header).
    n_rows : int or None
        Known before reading for the binary formats.
    size, position : int
        Progress: bytes of the file (text) or rows (binary), in total and read so far.

    Iterating gives ``(start, block)``: the index of the chunk's first row in the table
    and a float64 C-contiguous array of shape (m, n_columns). A file that breaks the
    format raises :class:`FileFormatError` naming the line (text) or the column.
    """

    def __init__(self, path, *, header: bool = False, chunk_rows: int = DEFAULT_CHUNK_ROWS,
                 what: str = "table", header_hint: str | None = None, format: str | None = None):
        self.path = pathlib.Path(path)
        self.chunk_rows = _chunk_rows(chunk_rows)
        if not self.path.is_file():
            raise FileNotFoundError(f"{self.path}: no such file (a {what} file was expected)")
        self.format = _format(self.path, format)
        if self.format == "csv":
            hint = header_hint or "if it is a line of column names, read it with header=True"
            self._src = _TextSource(self.path, header, what, hint)
        elif self.format == "parquet":
            self._src = _ParquetSource(self.path, self.chunk_rows)
        else:
            self._src = _NpzSource(self.path, self.chunk_rows)
        self.n_columns = self._src.n_columns
        self.names = self._src.names
        self.n_rows = self._src.n_rows
        self.size = self._src.size

    @property
    def position(self) -> int:
        """Bytes (text) or rows (binary) read so far."""
        return self._src.position

    @property
    def unit(self) -> str:
        """The unit of :attr:`size` and :attr:`position`: ``"B"`` or ``"row"``."""
        return "B" if self.format == "csv" else "row"

    def __iter__(self) -> Iterator[tuple[int, np.ndarray]]:
        k, want = self.n_columns, self.chunk_rows
        pending: list[list[np.ndarray]] = []
        n_pending, start = 0, 0
        for cols in self._src.batches():
            pending.append(cols)
            n_pending += len(cols[0])
            while n_pending >= want:
                block, pending = _take(pending, want, k)
                n_pending -= want
                yield start, block
                start += want
        if n_pending:
            block, _ = _take(pending, n_pending, k)
            yield start, block

    def close(self) -> None:
        self._src.close()

    def __enter__(self) -> "TableReader":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _take(pending: list[list[np.ndarray]], m: int, k: int) -> tuple[np.ndarray, list]:
    """The first ``m`` rows of the pending batches as one (m, k) float64 array, and the
    batches left."""
    out = np.empty((m, k))
    row = 0
    rest = []
    for i, cols in enumerate(pending):
        n = len(cols[0])
        take = min(n, m - row)
        for j in range(k):
            out[row:row + take, j] = cols[j][:take]
        row += take
        if take < n:
            rest = [[c[take:] for c in cols]] + pending[i + 1:]
            break
        if row == m:
            rest = pending[i + 1:]
            break
    return out, rest


# --- writing ---------------------------------------------------------------------------------

def _remove_temporary(tmp: pathlib.Path) -> None:
    """A temporary output and its side folder (npz), where they exist."""
    tmp.unlink(missing_ok=True)
    side = pathlib.Path(str(tmp) + ".d")
    if side.exists():
        shutil.rmtree(side, ignore_errors=True)


def _temp_beside(path: pathlib.Path, owner) -> tuple[pathlib.Path, weakref.finalize]:
    """A new empty file beside ``path`` (same folder, so the final rename stays on one
    file system), created with the process's umask like any output, and the finalizer
    that removes it. The finalizer is registered before the file exists: a Ctrl-C at any
    point after (even before the caller has entered its ``with`` block) leaves no
    temporary file once ``owner`` is collected or the interpreter exits; a commit
    detaches it."""
    for _ in range(100):
        tmp = path.with_name(f"{path.name}.{secrets.token_hex(4)}.partial")
        remove = weakref.finalize(owner, _remove_temporary, tmp)
        try:
            with open(tmp, "xb"):
                return tmp, remove
        except FileExistsError:
            remove.detach()
    raise FileExistsError(f"{path}: no free temporary name beside it")  # pragma: no cover


#: bytes of output written between two steps of :class:`_WriteBehind`
_WRITE_BEHIND_BYTES = 64 << 20


def _sync_file_range():
    """libc's ``sync_file_range`` (Linux), or None."""
    if not hasattr(os, "posix_fadvise"):
        return None
    try:
        import ctypes
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

    def __init__(self, tmp: pathlib.Path, names, dtypes, comments, rows=None, float_format=None):
        self.names, self.dtypes, self.float_format = names, dtypes, float_format
        self._file = open(tmp, "wb")
        head = "".join(f"# {' '.join(c.split())}\n" for c in comments) + ",".join(names) + "\n"
        self._file.write(head.encode("utf-8"))
        self._end = len(head.encode("utf-8"))
        self._behind = _WriteBehind(self._file.fileno())

    def write(self, arrays) -> None:
        if self.float_format == "repr":
            cols = [[repr(x) for x in a.tolist()] if a.dtype.kind == "f" else
                    [str(x) for x in a.tolist()] for a in arrays]
            self._file.write("".join(",".join(row) + "\n" for row in zip(*cols)).encode("utf-8"))
        else:
            import polars as pl   # lazy: polars costs start-up time (0.1-0.2 s)
            pl.DataFrame([pl.Series(n, a) for n, a in zip(self.names, arrays)]).write_csv(
                self._file, include_header=False)
        self._file.flush()
        end = self._file.tell()
        self._behind.written(self._end, end - self._end)
        self._end = end

    def close(self) -> None:
        self._file.close()

    def abort(self) -> None:
        self._file.close()


class _ParquetSink:
    def __init__(self, tmp: pathlib.Path, names, dtypes, comments, rows=None, float_format=None):
        pa, pq = _pyarrow()
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
    import io
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
                 float_format=None):
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
                 rows: int | None = None, float_format: str | None = None):
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
        self.format = _format(self.path, format)
        if float_format not in (None, "repr"):
            raise ValueError(f"float_format must be None or 'repr'; got {float_format!r}")
        if self.format != "csv" and (float_format or any(d.kind == "U" for d in self.dtypes)):
            raise ValueError(f"{self.path}: text columns and float_format are CSV only")
        if self.path.is_dir():
            raise IsADirectoryError(f"{self.path} is a folder: give a file name for the output")
        self._tmp, self._remove = _temp_beside(self.path, self)
        try:
            self._sink = _SINKS[self.format](self._tmp, self.names, self.dtypes, list(comments),
                                             rows, float_format)
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

    def commit(self) -> pathlib.Path:
        """Finish the file and rename it to :attr:`path` (replacing any file there)."""
        if not self._open:
            raise ValueError(f"{self.path}: the writer is closed")
        self._open = False
        try:
            self._sink.close()
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
        self.discard()
