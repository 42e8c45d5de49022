"""Access to the C core (the cffi extension ``gfins_fmi._core``) and the checks done
once at the boundary: dtype, shape, contiguity, finiteness of parameters.

Everything that calls C goes through here, so every status code becomes the same kind
of exception with a message that says what to change.
"""
from __future__ import annotations

import numbers
import operator

import numpy as np

try:
    from gfins_fmi._core import ffi, lib
except ImportError as exc:  # pragma: no cover - only without a build
    raise ImportError(
        "the compiled core gfins_fmi._core is missing: install the package with "
        "'pip install .' from the repository root (an in-place checkout has no build)"
    ) from exc

__all__ = ["ffi", "lib", "GfinsError", "NonFiniteInputError", "SampleError", "check_status",
           "as_array", "as_scalar", "as_rows", "as_positive_scalar", "as_vector3", "ptr",
           "struct_columns", "struct_doubles"]


class GfinsError(RuntimeError):
    """A C-core call failed; ``status`` is the gf_status code."""

    def __init__(self, message: str, status: int | None = None):
        super().__init__(message)
        self.status = status


class NonFiniteInputError(GfinsError, ValueError):
    """A sample holds NaN or Inf.

    Attributes
    ----------
    index : int
        Row of the first bad sample.
    column : int
        Column of its first non-finite value.
    partial : object
        The result for the samples before ``index`` (nothing is lost).
    """

    def __init__(self, message: str, index: int, column: int, partial=None):
        super().__init__(message, int(lib.GF_ERR_NONFINITE_INPUT))
        self.index = index
        self.column = column
        self.partial = partial


class SampleError(GfinsError, ValueError):
    """A sample was refused (out of range, bad time step) or the state diverged there.
    ``index`` is the sample, ``partial`` the solution before it."""

    def __init__(self, message: str, status: int, index: int, partial=None):
        super().__init__(message, status)
        self.index = index
        self.partial = partial


def status_text(status: int) -> str:
    return ffi.string(lib.gf_status_string(status)).decode()


def check_status(status: int, what: str) -> None:
    """Raise GfinsError unless ``status`` is GF_OK."""
    if status != lib.GF_OK:
        raise GfinsError(f"{what}: {status_text(status)} (status {status})", int(status))


def _real_dtype(name: str, arr: np.ndarray, unit: str) -> None:
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers in {unit}; got dtype {arr.dtype}")


def _shape_text(shape: tuple) -> str:
    dims = ["n" if d is None else str(d) for d in shape]
    return f"({dims[0]},)" if len(dims) == 1 else f"({', '.join(dims)})"


def as_array(name: str, value, shape: tuple, unit: str, *, finite: bool = True) -> np.ndarray:
    """The one check of a caller's array before the C core sees it.

    Parameters
    ----------
    name : str
        How the caller knows the argument (used in the messages).
    value : array_like
    shape : tuple of int or None
        Expected shape; ``None`` accepts any length along that axis (a record's rows).
    unit : str
        Unit of the values, for the messages.
    finite : bool
        Refuse NaN and Inf. Records pass ``False``: the C core stops at their first bad
        sample and keeps the solution before it.

    Returns
    -------
    numpy.ndarray
        A C-contiguous float64 array of that shape (a copy unless ``value`` already is
        one).

    Raises
    ------
    TypeError
        Not real numbers (complex, bool, text, objects).
    ValueError
        Another shape (the message names both), or a non-finite value.
    """
    arr = np.asarray(value)
    _real_dtype(name, arr, unit)
    if arr.ndim != len(shape) or any(d is not None and d != a for d, a in zip(shape, arr.shape)):
        hint = ""
        if len(shape) == 2 and shape[0] is None and arr.shape == (shape[1],):
            hint = f" (for a single sample use {name}.reshape(1, {shape[1]}))"
        raise ValueError(f"{name} must have shape {_shape_text(shape)} in {unit}; got shape "
                         f"{arr.shape}{hint}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if finite and not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr.tolist()}")
    return arr


def as_scalar(name: str, value, unit: str, *, above: float | None = None,
              at_least: float | None = None, below: float | None = None,
              at_most: float | None = None) -> float:
    """``value`` as a finite float, optionally within bounds (``above`` / ``below``
    exclusive, ``at_least`` / ``at_most`` inclusive); the scalar form of
    :func:`as_array`, with messages such as "dt_s must be finite and > 0 s".
    """
    if isinstance(value, (bool, np.bool_)) or not (
            isinstance(value, numbers.Real) or
            (isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf")):
        raise TypeError(f"{name} must be a real number in {unit}; got {type(value).__name__}")
    x = float(value)
    # (bracket, symbol, test, bound) of each side given
    lo = ("(", ">", operator.gt, above) if above is not None else \
        ("[", ">=", operator.ge, at_least) if at_least is not None else None
    hi = (")", "<", operator.lt, below) if below is not None else \
        ("]", "<=", operator.le, at_most) if at_most is not None else None
    if np.isfinite(x) and all(side[2](x, side[3]) for side in (lo, hi) if side):
        return x
    if lo and hi:
        rule = f"finite and in {lo[0]}{lo[3]:g}, {hi[3]:g}{hi[0]} {unit}"
    elif lo or hi:
        side = lo or hi
        rule = f"finite and {side[1]} {side[3]:g} {unit}"
    else:
        rule = f"finite (in {unit})"
    raise ValueError(f"{name} must be {rule}; got {x!r}")


def as_rows(name: str, value, n_cols: int, unit: str) -> np.ndarray:
    """A record: ``value`` as a C-contiguous float64 array of shape (n, n_cols); NaN and
    Inf are left for the C core to locate (see :func:`as_array`)."""
    return as_array(name, value, (None, n_cols), unit, finite=False)


def as_positive_scalar(name: str, value, unit: str) -> float:
    """``value`` as a finite float > 0 (see :func:`as_scalar`)."""
    return as_scalar(name, value, unit, above=0.0)


def as_vector3(name: str, value, unit: str) -> np.ndarray:
    """``value`` as a finite float64 array of shape (3,) (see :func:`as_array`)."""
    return as_array(name, value, (3,), unit)


_CTYPES = {"double": np.float64, "uint8_t": np.uint8, "int8_t": np.int8, "int64_t": np.int64,
           "uint64_t": np.uint64}


def ptr(arr: np.ndarray, n: int | None = None, ctype: str = "double"):
    """A cffi view of ``arr``'s data for a C function that accesses ``n`` elements.

    The only way a buffer reaches the C core: ``arr`` must be a C-contiguous array of
    the C type (checked by :func:`as_array` for callers' data, allocated by the caller
    of ``ptr`` for outputs) and hold exactly ``n`` elements, so C can neither read nor
    write beyond it. The array must outlive the view. (``n=None`` skips the size check;
    tests/lib/test_validation.py makes sure no module calls it so.)
    """
    if ctype not in _CTYPES:
        # an array of C structs: a numpy structured array laid out as the struct
        if not isinstance(arr, np.ndarray) or arr.dtype.itemsize != ffi.sizeof(ctype) \
                or arr.dtype.names is None:
            raise TypeError(f"a {ctype} buffer for C must be a numpy structured array of "
                            f"{ffi.sizeof(ctype)}-byte records")
        if not arr.flags.c_contiguous:
            raise ValueError("a buffer for C must be C-contiguous")
        if n is not None and arr.size != n:
            raise ValueError(f"a {ctype} buffer of {arr.size} records where C accesses {n}")
        return ffi.cast(f"{ctype} *", ffi.from_buffer(arr))
    want = _CTYPES[ctype]
    if not isinstance(arr, np.ndarray) or arr.dtype != want:
        raise TypeError(f"a {ctype} buffer for C must be a numpy {np.dtype(want).name} array; "
                        f"got {getattr(arr, 'dtype', type(arr).__name__)}")
    if not arr.flags.c_contiguous:
        raise ValueError("a buffer for C must be C-contiguous")
    if n is not None and arr.size != n:
        raise ValueError(f"a {ctype} buffer of {arr.size} elements where C accesses {n}")
    return ffi.from_buffer(f"{ctype}[]", arr)


def done_before(k: int, start: int = 0, verb: str = "solved") -> str:
    """How much of a record was done before a bad sample, for error messages: ``k``
    samples of this call, the first of them sample ``start`` of the record."""
    if k == 0:
        return f"no sample was {verb} before it (.partial is empty)"
    if k == 1:
        return f"sample {start} was {verb} (see .partial)"
    return f"samples {start}..{start + k - 1} were {verb} (see .partial)"


def as_start_index(value) -> int:
    """``start_index`` of the streaming solvers: an integer >= 0."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
        raise ValueError(f"start_index must be an integer >= 0 (samples of the record before "
                         f"this call's first); got {value!r}")
    return int(value)


def first_nonfinite(arr: np.ndarray, row: int) -> int:
    """Column of the first non-finite value in ``arr[row]``."""
    bad = np.flatnonzero(~np.isfinite(arr[row]))
    return int(bad[0]) if bad.size else -1


def struct_doubles(ctype: str) -> int:
    """Number of doubles in a C struct made of doubles only (a row of its numpy buffer)."""
    return ffi.sizeof(ctype) // 8


def struct_columns(buf: np.ndarray, ctype: str) -> dict:
    """Views of the fields of an array of C structs made of doubles only (one struct a
    row of ``buf``, shape (n, struct_doubles(ctype))), by field name: (n,) for a double,
    (n, k) for a double[k]."""
    t = ffi.typeof(ctype)
    if buf.shape[1] * 8 != ffi.sizeof(t):  # pragma: no cover - layout guard
        raise GfinsError(f"{ctype} is not {buf.shape[1]} doubles")
    cols = {}
    for name, f in t.fields:
        i, width = f.offset // 8, ffi.sizeof(f.type) // 8
        cols[name] = buf[:, i] if f.type.kind == "primitive" else buf[:, i:i + width]
    return cols
