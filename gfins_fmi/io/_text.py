"""Reading numeric text tables with errors that name the file, the line and the fix.

numpy's ``loadtxt`` (its C parser, numpy >= 1.23) reads the table in one call; only
when it refuses a file are the lines scanned in Python, to say which line is wrong and
why (a header where none belongs, a wrong column count, text in a number column).
"""
from __future__ import annotations

import contextlib
import itertools
import pathlib
import warnings
from typing import Callable, Iterable, Iterator, Sequence

import numpy as np

from gfins_fmi.io.errors import FileFormatError, RecordError, not_a_file

__all__ = ["read_table", "record_errors_at_lines", "diagnose", "data_lines", "is_number"]


def _split(line: str, delimiter: str | None) -> list[str]:
    return [f.strip() for f in line.split(delimiter)] if delimiter else line.split()


def is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def data_lines(lines: Iterable[str], comment: str | None, skip: int) -> Iterator[int]:
    """0-based indices (in ``lines``) of the data lines, as loadtxt counts them."""
    for i, line in enumerate(lines):
        if i < skip:
            continue
        body = line.split(comment, 1)[0] if comment else line
        if body.strip():
            yield i


def diagnose(path: pathlib.Path, lines: Iterable[str], delimiter: str | None,
             comment: str | None, skip: int, n_columns: Sequence[int] | None, what: str,
             header_message: str | None = None, *, first_row: int = 0,
             line_offset: int = 0) -> FileFormatError:
    """Why a parser refused the file: the first line that is not a row of numbers of an
    accepted width (``n_columns``; None: the width of the first data line). Its
    ``line`` is None when every line is a row of numbers.

    ``lines`` may be a lazy iterable (an open file), read once up to the bad line, or
    a block of the file: its first line is line ``line_offset + 1`` of the file and
    its first data line row ``first_row`` of the table. ``header_message`` is the
    message when row 0 holds text (``{text}`` stands for the text; default: the format
    has no header line, delete that line).
    """
    expected = " or ".join(str(c) for c in n_columns) if n_columns else None
    width = None
    row = first_row - 1
    for i, line in enumerate(lines):
        if i < skip:
            continue
        body = line.split(comment, 1)[0] if comment else line
        body = body.strip()
        if not body:
            continue
        row += 1
        where = line_offset + i + 1
        fields = _split(body, delimiter)
        text = [f for f in fields if not is_number(f)]
        if text:
            if row == 0 and len(text) == len(fields):
                message = header_message or (f"{what} files have no header line, but the first "
                                             "line holds text ({text}): delete that line")
                return FileFormatError(path, where, message.replace("{text}", repr(text[0])))
            bad = f"{text[0]!r} is not a number" if text[0] else "an empty field"
            return FileFormatError(path, where, f"{bad}; every {what} field must be numeric")
        if expected is not None and len(fields) not in n_columns:
            return FileFormatError(path, where, f"{len(fields)} columns where a {what} line has "
                                   f"{expected} (a truncated or merged line, or another format)")
        if width is not None and len(fields) != width:
            return FileFormatError(path, where, f"{len(fields)} columns after {width} on the lines "
                                   "before: every line must have the same columns")
        width = len(fields)
    return FileFormatError(path, None, f"the file could not be read as a {what} table")


def read_table(path, n_columns: Sequence[int], what: str, *, delimiter: str | None = None,
               comment: str | None = None, skip_lines: int = 0,
               lines: Sequence[str] | None = None) -> tuple[np.ndarray, Callable[[int], int]]:
    """Read a numeric text table.

    Parameters
    ----------
    path : str or path-like
        The file.
    n_columns : sequence of int
        Accepted numbers of columns.
    what : str
        Name of the format, for messages ("KF-GINS IMU").
    delimiter : str, optional
        Field separator; None splits on whitespace.
    comment : str, optional
        Comment marker (the rest of a line after it is ignored).
    skip_lines : int
        Lines at the top that are not data (a header).
    lines : sequence of str, optional
        The file's lines as the caller prepared them (one per line of the file, blank
        where a line is not data), read instead of the file.

    Returns
    -------
    table : ndarray (n, k), float64
    line_of : callable
        Row index -> 1-based line number in the file (for messages).
    """
    path = pathlib.Path(path)
    if lines is None and not path.is_file():
        raise not_a_file(path, f"{what} file")

    def file_lines() -> Sequence[str]:
        if lines is not None:
            return lines
        return path.read_text(encoding="utf-8", errors="replace").splitlines()

    try:
        with warnings.catch_warnings():     # an empty file is reported below, as an error
            warnings.filterwarnings("ignore", message=".*input contained no data")
            table = np.loadtxt(path if lines is None else lines, dtype=np.float64,
                               delimiter=delimiter, comments=comment, skiprows=skip_lines,
                               ndmin=2, encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise FileFormatError(path, None, f"not a text file (a {what} file is text; "
                              "binary files need their own reader)") from exc
    except (ValueError, IndexError) as exc:
        raise diagnose(path, file_lines(), delimiter, comment, skip_lines, n_columns, what) from exc

    def line_of(row: int) -> int:
        return next(itertools.islice(data_lines(file_lines(), comment, skip_lines), row, None)) + 1

    if table.shape[0] == 0:
        raise FileFormatError(path, None, f"no data lines: the file is empty (a {what} file "
                              "holds one sample per line)")
    if table.shape[1] not in n_columns:
        expected = " or ".join(str(c) for c in n_columns)
        raise FileFormatError(path, line_of(0), f"{table.shape[1]} columns where a {what} line "
                              f"has {expected}")
    return table, line_of


@contextlib.contextmanager
def record_errors_at_lines(path, line_of: Callable[[int], int] | None) -> Iterator[None]:
    """Turn a :class:`RecordError` raised while building a record from a file into a
    :class:`FileFormatError` that names the file and the line of the bad sample."""
    try:
        yield
    except RecordError as exc:
        line = line_of(exc.index) if (line_of is not None and exc.index is not None) else None
        raise FileFormatError(path, line, str(exc)) from exc
