"""Reading numeric text tables with errors that name the file, the line and the fix.

numpy's ``loadtxt`` (its C parser, numpy >= 1.23) reads the table in one call; only
when it refuses a file are the lines scanned in Python, to say which line is wrong and
why (a header where none belongs, a wrong column count, text in a number column).
"""
from __future__ import annotations

import contextlib
import pathlib
import warnings
from typing import Callable, Iterator, Sequence

import numpy as np

from gfins_fmi.io.errors import FileFormatError, RecordError

__all__ = ["read_table", "record_errors_at_lines"]


def _split(line: str, delimiter: str | None) -> list[str]:
    return [f.strip() for f in line.split(delimiter)] if delimiter else line.split()


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _data_lines(lines: Sequence[str], comment: str | None, skip: int) -> list[int]:
    """0-based indices (in ``lines``) of the data lines, as loadtxt counts them."""
    out = []
    for i, line in enumerate(lines):
        if i < skip:
            continue
        body = line.split(comment, 1)[0] if comment else line
        if body.strip():
            out.append(i)
    return out


def _diagnose(path: pathlib.Path, lines: Sequence[str], delimiter: str | None,
              comment: str | None, skip: int, n_columns: Sequence[int], what: str) -> FileFormatError:
    """Why loadtxt refused the file: the first line that is not a row of numbers of an
    accepted width."""
    expected = " or ".join(str(c) for c in n_columns)
    width = None
    for i in _data_lines(lines, comment, skip):
        body = lines[i].split(comment, 1)[0] if comment else lines[i]
        fields = _split(body.strip(), delimiter)
        text = [f for f in fields if not _is_number(f)]
        if text:
            if width is None:
                return FileFormatError(path, i + 1, f"{what} files have no header line, but the "
                                       f"first line holds text ({text[0]!r}): delete that line")
            return FileFormatError(path, i + 1, f"{text[0]!r} is not a number; every {what} "
                                   f"field must be numeric")
        if len(fields) not in n_columns:
            return FileFormatError(path, i + 1, f"{len(fields)} columns where a {what} line has "
                                   f"{expected} (a truncated or merged line, or another format)")
        if width is not None and len(fields) != width:
            return FileFormatError(path, i + 1, f"{len(fields)} columns after {width} on the lines "
                                   "before: every line must have the same columns")
        width = len(fields)
    return FileFormatError(path, None, f"numpy could not read the file as a {what} table")


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
        raise FileNotFoundError(f"{path}: no such file (a {what} file was expected)")

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
        raise _diagnose(path, file_lines(), delimiter, comment, skip_lines, n_columns, what) from exc

    def line_of(row: int) -> int:
        return _data_lines(file_lines(), comment, skip_lines)[row] + 1

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
