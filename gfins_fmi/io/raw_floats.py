"""float64 arrays to and from open binary files, through the file's own ``readinto`` and
``write``: numpy's ``tofile``/``fromfile`` on a file object flush and duplicate the
file's handle, and a Ctrl-C that lands in that flush comes out as ``TypeError:
expected str, bytes or os.PathLike object`` (numpy then tries the object as a path): a
run interrupted there reported a usage error (exit 2) instead of an interruption (130).
Found by the interrupt study (tests/support/interrupts.py, in chunks)."""
from __future__ import annotations

import numpy as np

__all__ = ["append_floats", "read_floats"]


def append_floats(f, array: np.ndarray) -> None:
    """Write ``array``'s values as native float64 at ``f``'s position."""
    a = np.ascontiguousarray(array, dtype=np.float64)
    f.write(memoryview(a).cast("B"))


def read_floats(f, count: int, dtype="=f8") -> np.ndarray:
    """Up to ``count`` float64 values (``dtype``: native, or ``"<f8"`` for a file format's
    little-endian) from ``f``'s position (fewer at the end of the file: as many whole
    values as remain)."""
    out = np.empty(int(count), dtype=dtype)
    view = memoryview(out).cast("B")
    got = 0
    while got < len(view):
        n = f.readinto(view[got:])
        if not n:
            break
        got += n
    return out[: got // 8]
