"""Access to the C core (the cffi extension ``gfins_fmi._core``) and the checks done
once at the boundary: dtype, shape, contiguity, finiteness of parameters.

Everything that calls C goes through here, so every status code becomes the same kind
of exception with a message that says what to change.
"""
from __future__ import annotations

import numbers

import numpy as np

try:
    from gfins_fmi._core import ffi, lib
except ImportError as exc:  # pragma: no cover - only without a build
    raise ImportError(
        "the compiled core gfins_fmi._core is missing: install the package with "
        "'pip install .' from the repository root (an in-place checkout has no build)"
    ) from exc

__all__ = ["ffi", "lib", "GfinsError", "NonFiniteInputError", "check_status",
           "as_rows", "as_positive_scalar", "as_vector3", "ptr"]


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


def status_text(status: int) -> str:
    return ffi.string(lib.gf_status_string(status)).decode()


def check_status(status: int, what: str) -> None:
    """Raise GfinsError unless ``status`` is GF_OK."""
    if status != lib.GF_OK:
        raise GfinsError(f"{what}: {status_text(status)} (status {status})", int(status))


def as_rows(name: str, value, n_cols: int, unit: str) -> np.ndarray:
    """``value`` as a C-contiguous float64 array of shape (n, n_cols)."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers in {unit}; got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != n_cols:
        hint = f" (for a single sample use {name}.reshape(1, {n_cols}))" if arr.shape == (n_cols,) else ""
        raise ValueError(f"{name} must have shape (n, {n_cols}) in {unit}; got shape {arr.shape}{hint}")
    return np.ascontiguousarray(arr, dtype=np.float64)


def as_positive_scalar(name: str, value, unit: str) -> float:
    """``value`` as a finite float > 0."""
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number in {unit}; got {type(value).__name__}")
    x = float(value)
    if not np.isfinite(x) or x <= 0.0:
        raise ValueError(f"{name} must be finite and > 0 {unit}; got {x!r}")
    return x


def as_vector3(name: str, value, unit: str) -> np.ndarray:
    """``value`` as a finite float64 array of shape (3,)."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "iuf" or arr.shape != (3,):
        raise ValueError(f"{name} must be 3 real numbers in {unit}; got {value!r}")
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr.tolist()}")
    return arr


def ptr(arr: np.ndarray, ctype: str = "double"):
    """A cffi view of a C-contiguous array's data (the array must outlive the view)."""
    return ffi.from_buffer(f"{ctype}[]", arr)


def first_nonfinite(arr: np.ndarray, row: int) -> int:
    """Column of the first non-finite value in ``arr[row]``."""
    bad = np.flatnonzero(~np.isfinite(arr[row]))
    return int(bad[0]) if bad.size else -1
