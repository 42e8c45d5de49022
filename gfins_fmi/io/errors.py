"""The two exceptions of record I/O: a record that breaks its contract, and a file that
does not hold what its format promises (both are ValueErrors); and the one message of an
input that is not a file (:func:`not_a_file`)."""
from __future__ import annotations

import pathlib

__all__ = ["RecordError", "FileFormatError", "not_a_file"]


class RecordError(ValueError):
    """A record's content breaks its contract (shape, finiteness, time order, std > 0,
    ranges); the message says what to change.

    Attributes
    ----------
    field : str or None
        The offending field (``"t_s"``, ``"gyro"``, ...).
    index : int or None
        Row of the first offending sample.
    """

    def __init__(self, message: str, field: str | None = None, index: int | None = None):
        super().__init__(message)
        self.field = field
        self.index = index


class FileFormatError(ValueError):
    """A file does not hold what its format promises.

    Attributes
    ----------
    path : pathlib.Path
        The file.
    line : int or None
        1-based number of the first offending line, when one line is at fault.
    """

    def __init__(self, path, line: int | None, message: str):
        where = f"{path}:{line}" if line is not None else f"{path}"
        super().__init__(f"{where}: {message}")
        self.path = pathlib.Path(path)
        self.line = line


def _article(what: str) -> str:
    return "an" if what[:1].lower() in "aeio" else "a"


def not_a_file(path, what: str) -> OSError:
    """The error for an input ``path`` that is not a readable file: a folder
    (IsADirectoryError) or nothing (FileNotFoundError), the file expected named (``what``:
    "ImuRecord CSV", "RTKLIB .pos file")."""
    path = pathlib.Path(path)
    if path.is_dir():
        return IsADirectoryError(f"{path}: is a folder, not a file ({_article(what)} {what} was "
                                 "expected): give the file's path")
    return FileNotFoundError(f"{path}: no such file ({_article(what)} {what} was expected)")
