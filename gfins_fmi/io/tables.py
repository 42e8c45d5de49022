"""Numeric tables in files, read in chunks of rows: CSV text, npz and Parquet (docs/io.md,
"Tables"); their writer is :class:`gfins_fmi.io.table_writer.TableWriter`.

A :class:`TableReader` yields a file's rows in chunks of a fixed number of rows
(float64, C-contiguous), so a record of any length flows through the C core with
bounded memory: read a chunk, run it, write it (the writer appends chunks to a temporary
file beside its destination and renames it into place only when complete).

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
    CSV text: comma-separated numbers, one row per line (``whitespace=True``: separated
    by runs of spaces or tabs, as KF-GINS's files); ``#`` comment lines and blank lines
    are skipped, spaces and tabs around a field ignored, CRLF line ends taken; with
    ``header=True`` the first other line holds the column names (or, when that line
    holds numbers, the comment line before it, as numpy's ``savetxt`` writes a header). Numbers in the usual forms,
    ``nan`` and ``inf`` included; written as the shortest decimal that reads back as
    the same float64 (``0.1``, ``1e-7``, ``0.00002201446582700049``), so every value
    round-trips bit for bit.

Text is parsed in C (``gf_text_parse``: 16-30 ns a value, correctly rounded, no polars
import), straight into the chunks this reader yields; text is written by polars (Rust;
shortest round-trip digits: 55-65 ns a value) or, with fixed decimals, in C
(``gf_text_fixed``) (docs/io.md, "Why these parsers"; docs/benchmarks.md). When the
parser refuses a line, that line alone is diagnosed in Python to name its fault
(:func:`gfins_fmi.io._text.diagnose`).
"""
from __future__ import annotations

import pathlib
import re
import zipfile
from typing import Iterator

import numpy as np

from gfins_fmi._lib import check_status, ffi, lib, ptr
from gfins_fmi.io._text import is_number, diagnose
from gfins_fmi.io.errors import FileFormatError, not_a_file

__all__ = ["TableReader", "table_format", "checked_format", "pyarrow_module", "FORMATS",
           "DEFAULT_CHUNK_ROWS"]

#: the formats, as :func:`table_format` names them
FORMATS = ("csv", "parquet", "npz")
#: rows per chunk: 2^18 rows of 10 float64 columns are 21 MB, a few tenths of a second
#: of parsing; large enough that per-chunk costs vanish, small enough for a smooth
#: progress bar and a small memory footprint
DEFAULT_CHUNK_ROWS = 1 << 18
#: bytes of text read at a time: the parser costs nothing per call, so a block only has
#: to be long against a line (a longer line doubles the buffer)
_TEXT_BLOCK_BYTES = 4 << 20
#: rows allocated for a text chunk at first (doubled up to chunk_rows as rows come)
_FIRST_CHUNK_ROWS = 1 << 16


def table_format(path) -> str:
    """The format of a table file from its name: ``"parquet"`` (``.parquet``, ``.pq``),
    ``"npz"`` (``.npz``), otherwise ``"csv"`` (text)."""
    suffix = pathlib.Path(path).suffix.lower()
    if suffix in (".parquet", ".pq"):
        return "parquet"
    if suffix == ".npz":
        return "npz"
    return "csv"


def checked_format(path, format: str | None) -> str:
    """``format`` checked, or the format of ``path``'s name (:func:`table_format`)."""
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
    """CSV or whitespace-separated text: read in blocks, whole lines parsed by the C core
    (``gf_text_parse``) straight into the chunks the reader yields. The head of the file
    (comments, the header line, the first data line) is read here to know the columns;
    the parser counts the lines it consumes, so a refused line is named and diagnosed
    alone."""

    format = "csv"

    def __init__(self, path: pathlib.Path, header: bool, what: str, header_hint: str, whitespace: bool = False,
                 block_bytes: int = _TEXT_BLOCK_BYTES, chunk_rows: int = DEFAULT_CHUNK_ROWS):
        self.path, self.what, self.whitespace, self.block_bytes = path, what, whitespace, block_bytes
        self.chunk_rows = chunk_rows
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
                fields = body.split() if whitespace else body.split(",")
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

    def batches(self) -> Iterator[np.ndarray]:
        """The table in (m, k) float64 arrays of ``chunk_rows`` rows (the last shorter),
        each filled by the parser in place."""
        k, want = self.n_columns, self.chunk_rows
        sep = lib.GF_TEXT_SEP_WHITESPACE if self.whitespace else lib.GF_TEXT_SEP_COMMA
        buf = np.empty(max(self.block_bytes, 1), np.uint8)
        lo = hi = 0                 # buf[lo:hi]: read from the file, not parsed yet
        final = False               # the file's end is in buf
        line, rows = self._skip, 0  # lines of the file before buf[lo]; rows before `out`
        # a chunk's rows: allocated as they come (doubling) up to chunk_rows, so that a
        # huge chunk_rows (the whole record at once) costs only the rows there are
        out, filled = np.empty((min(want, _FIRST_CHUNK_ROWS), k)), 0
        n_rows, n_used, n_lines = ffi.new("size_t *"), ffi.new("size_t *"), ffi.new("size_t *")
        self.position = self._offset
        with open(self.path, "rb") as f:
            f.seek(self._offset)
            while True:
                if filled == len(out):      # full below chunk_rows: room for more
                    grown = np.empty((min(want, 2 * len(out)), k))
                    grown[:filled] = out
                    out = grown
                room = len(out) - filled
                status = lib.gf_text_parse(ptr(buf[lo:hi], hi - lo, "uint8_t"), hi - lo, int(final), k, sep,
                                           ptr(out[filled:], room * k), room, n_rows, n_used, n_lines)
                filled += n_rows[0]
                lo += n_used[0]
                line += n_lines[0]
                self.position += n_used[0]
                if status == lib.GF_ERR_BAD_TEXT:
                    raise self._bad_line(buf[lo:hi].tobytes(), line, rows + filled)
                check_status(status, "gf_text_parse")
                if filled == want:
                    yield out
                    rows += want
                    out, filled = np.empty((want, k)), 0    # a file that filled one fills more
                    continue
                if filled == len(out):      # stopped for room: grow and parse on
                    continue
                if final:
                    break
                # every whole line parsed: the incomplete one to the front, then read on
                # (a line longer than the buffer doubles it)
                rest = hi - lo
                if lo:
                    buf[:rest] = buf[lo:hi]
                lo, hi = 0, rest
                if hi == len(buf):
                    buf = np.concatenate([buf, np.empty(len(buf), np.uint8)])
                n = f.readinto(memoryview(buf)[hi:])
                final = not n
                hi += n or 0
        if filled:
            # the last chunk: copied when most of its rows would be empty
            yield out[:filled] if 2 * filled > len(out) else out[:filled].copy()

    def _bad_line(self, text: bytes, before: int, row: int) -> FileFormatError:
        """The error for the line at the start of ``text``: line ``before + 1`` of the
        file, row ``row`` of the table when it were one."""
        end = text.find(b"\n")
        body = text[:end if end >= 0 else None].decode("utf-8", errors="replace").rstrip("\r")
        k = self.n_columns
        err = diagnose(self.path, [body], None if self.whitespace else ",", None, 0, [k], self.what,
                       self.header_message, first_row=row, line_offset=before)
        if err.line is not None:
            return err
        # numbers to Python that this reader does not take ("1_000", "0x10" is not one)
        fields = body.split() if self.whitespace else [x.strip() for x in body.split(",")]
        bad = next((x for x in fields if not _NUMBER.fullmatch(x)), body.strip())
        return FileFormatError(self.path, before + 1, f"{bad!r} is not a number in the forms a table "
                               "takes (digits with an optional '.' and exponent, nan, inf); every "
                               f"{self.what} field must be numeric")

    def close(self) -> None:
        pass


#: the numbers gf_text_parse reads (for the message when Python's float() reads more)
_NUMBER = re.compile(r"[+-]?(([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|nan|inf|infinity)",
                     re.IGNORECASE)


def pyarrow_module():
    """pyarrow and pyarrow.parquet, or a ValueError that says how to get them."""
    try:
        import pyarrow   # lazy: pyarrow: optional extra (Parquet)
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
        pa, pq = pyarrow_module()
        try:
            # no pre-buffering: it reads the whole file ahead (memory = file size); column
            # chunks read through a 1 MiB buffer, not whole: a row group of 10^6 rows of 7
            # columns held 56 MB (a 10 h record read: 174 -> 106 MiB peak, the same CPU)
            self._pf = pq.ParquetFile(path, pre_buffer=False, buffer_size=1 << 20)
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
    whitespace : bool
        Text: fields separated by runs of spaces or tabs (KF-GINS's files), not commas.
    block_bytes : int, optional
        Text: bytes parsed at a time (default 16 MiB; less memory, a little more time).

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
                 what: str = "table", header_hint: str | None = None, format: str | None = None,
                 whitespace: bool = False, block_bytes: int | None = None):
        self.path = pathlib.Path(path)
        self.chunk_rows = _chunk_rows(chunk_rows)
        if not self.path.is_file():
            raise not_a_file(self.path, f"{what} file")
        self.format = checked_format(self.path, format)
        if self.format == "csv":
            hint = header_hint or "if it is a line of column names, read it with header=True"
            self._src = _TextSource(self.path, header, what, hint, whitespace, block_bytes or _TEXT_BLOCK_BYTES,
                                    self.chunk_rows)
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
        if self.format == "csv":
            # text: the parser fills chunks of chunk_rows rows in place
            start = 0
            for block in self._src.batches():
                yield start, block
                start += len(block)
            return
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
