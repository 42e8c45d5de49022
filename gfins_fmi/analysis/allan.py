"""Overlapping Allan deviation of IMU records, streamed, with confidence intervals.

The estimator is the overlapping Allan variance of IEEE Std 952-1997 (Annex C) and
IEEE Std 1293-2018, NIST SP 1065 eq. (11): for n samples y_k of a rate (gyro, rad/s) or
specific force (accelerometer, m/s^2) at interval tau0, the phase x (x_0 = 0,
x_k = x_(k-1) + y_k tau0) has N = n + 1 points and

    sigma^2(tau = m tau0) = sum_{k=0}^{N-2m-1} (x_(k+2m) - 2 x_(k+m) + x_k)^2 / (2 tau^2 (N - 2m)).

The sums are the C core's (``gf_allan_sums``, one pass over the buffer per averaging
factor); :class:`AllanAccumulator` streams a record through a buffer that holds only the
last 2 m_max rows of phase and the new chunk, so a record of any length is analysed
with memory set by the largest tau, not by the record (``gfins noise`` reads its file in
chunks). A constant (the first chunk's mean) is removed before the phase is formed, as
allantools removes the mean: the variance does not change, and a phase that grows with
the record (9.8 m/s^2 x 10 h) would lose the digits the differences need.

Confidence intervals: chi-square with the equivalent degrees of freedom of the
overlapping estimator for the noise type (NIST SP 1065 sec. 5.3, the simple formulas of
Howe, Allan and Barnes 1981), the type taken from the local slope of the curve (or
given): white phase (AVAR ~ tau^-2, quantisation), white rate (tau^-1, angle/velocity
random walk), flicker rate (tau^0, bias instability), random-walk rate (tau^+1).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import NonFiniteInputError, as_array, as_scalar, ffi, lib, ptr, status_text

__all__ = ["AllanAccumulator", "AllanDeviation", "allan_deviation", "averaging_factors",
           "edf_overlapping", "MAX_FRACTION", "ALPHA_NAMES"]

#: the largest tau by default: a quarter of the record (Stable32's stop ratio for the
#: overlapping ADEV); beyond it the estimate has fewer than ~3 degrees of freedom
MAX_FRACTION = 0.25
#: the power-law noise types by alpha (S_y(f) ~ f^alpha) in the words of an IMU
ALPHA_NAMES = {2: "white phase (quantisation)", 0: "white rate (random walk of angle or velocity)",
               -1: "flicker rate (bias instability)", -2: "random-walk rate (rate random walk)"}
#: rows of a streamed chunk when an array is analysed in memory
_CHUNK_ROWS = 1 << 18
#: the fewest new rows the buffer takes between two moves of its history
_MIN_PIECE = 1 << 16


def averaging_factors(n_samples: int, per_decade: int = 10,
                      max_fraction: float = MAX_FRACTION) -> np.ndarray:
    """Averaging factors m (tau = m tau0): about ``per_decade`` per decade, log-spaced
    from 1 to ``max_fraction`` of the record, unique integers (int64)."""
    n = int(n_samples)
    if n < 4:
        raise ValueError(f"an Allan deviation needs at least 4 samples; got {n}")
    if not (isinstance(per_decade, (int, np.integer)) and per_decade >= 1):
        raise ValueError(f"per_decade must be an integer >= 1; got {per_decade!r}")
    frac = as_scalar("max_fraction", max_fraction, "of the record", above=0.0, below=0.5)
    m_max = max(1, int(np.floor(frac * n)))
    count = max(2, int(np.ceil(per_decade * np.log10(m_max))) + 1) if m_max > 1 else 1
    return np.unique(np.round(np.logspace(0.0, np.log10(m_max), count)).astype(np.int64))


def edf_overlapping(n_phase, m, alpha) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping Allan variance at factor m for
    N = ``n_phase`` phase points and noise type ``alpha`` (2 white phase, 1 flicker phase,
    0 white rate, -1 flicker rate, -2 random-walk rate): NIST SP 1065 sec. 5.3 (Howe,
    Allan and Barnes 1981), broadcast over the arguments."""
    N = np.asarray(n_phase, dtype=float)
    m = np.asarray(m, dtype=float)
    alpha = np.asarray(alpha)
    N, m, alpha = np.broadcast_arrays(N, m, alpha)
    out = np.empty(N.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        wpm = (N + 1) * (N - 2 * m) / (2 * (N - m))
        fpm = np.exp(np.sqrt(np.log((N - 1) / (2 * m)) * np.log((2 * m + 1) * (N - 1) / 4)))
        wfm = (3 * (N - 1) / (2 * m) - 2 * (N - 2) / N) * 4 * m ** 2 / (4 * m ** 2 + 5)
        # m = 1: 2 (N - 2)^2 / (2.3 N - 4.9) (the square that allantools' edf_simple omits:
        # without it an estimate from a whole record would have < 1 degree of freedom)
        ffm = np.where(m == 1, 2 * (N - 2) ** 2 / (2.3 * N - 4.9), 5 * N ** 2 / (4 * m * (N + 3 * m)))
        rwfm = (N - 2) / m * ((N - 1) ** 2 - 3 * m * (N - 1) + 4 * m ** 2) / (N - 3) ** 2
    for a, v in ((2, wpm), (1, fpm), (0, wfm), (-1, ffm), (-2, rwfm)):
        sel = alpha == a
        out[sel] = v[sel]
    bad = ~np.isin(alpha, (2, 1, 0, -1, -2))
    if np.any(bad):
        raise ValueError(f"alpha must be one of 2, 1, 0, -1, -2; got {np.unique(alpha[bad]).tolist()}")
    return np.maximum(out, 1.0)


@dataclass
class AllanDeviation:
    """Overlapping Allan deviation of the columns of a record.

    Attributes
    ----------
    tau_s : (k,) averaging times, s
    adev : (k, c) Allan deviation of each column, in the column's unit (rad/s, m/s^2)
    n_terms : (k,) second differences averaged at each tau (N - 2m)
    m : (k,) averaging factors
    n_samples : samples of the record
    dt_s : sampling interval, s
    names : (c,) column names
    """

    tau_s: np.ndarray
    adev: np.ndarray
    n_terms: np.ndarray
    m: np.ndarray
    n_samples: int
    dt_s: float
    names: tuple = field(default_factory=tuple)

    @property
    def avar(self) -> np.ndarray:
        """The Allan variance (k, c)."""
        return self.adev ** 2

    def local_alpha(self) -> np.ndarray:
        """The noise type at each tau and column, from the local log-log slope mu of
        the variance (smoothed over neighbouring taus): alpha = -mu - 1 rounded to 2, 0,
        -1 or -2 (k, c)."""
        lt = np.log(self.tau_s)
        lv = np.log(np.maximum(self.avar, np.finfo(float).tiny))
        if len(lt) < 3:
            return np.zeros(lv.shape, dtype=int)
        mu = np.gradient(lv, lt, axis=0)
        ker = np.ones(5) / 5.0
        mu = np.apply_along_axis(lambda v: np.convolve(np.pad(v, 2, mode="edge"), ker, "valid"), 0, mu)
        a = np.clip(np.round(-mu - 1.0), -2, 2).astype(int)
        a[a == 1] = 2            # flicker phase is not an IMU term: the quantisation family
        return a

    def edf(self, alpha=None) -> np.ndarray:
        """Equivalent degrees of freedom (k, c) for noise type ``alpha`` (scalar or (k, c);
        default :meth:`local_alpha`)."""
        a = self.local_alpha() if alpha is None else np.broadcast_to(alpha, self.adev.shape)
        return edf_overlapping((self.n_terms + 2 * self.m)[:, None], self.m[:, None], a)

    def confidence(self, probability: float = 0.683, alpha=None) -> tuple[np.ndarray, np.ndarray]:
        """The two-sided chi-square interval of the deviation at ``probability``
        (default 0.683, "1 sigma"): (low, high), each (k, c)."""
        from scipy.stats import chi2   # lazy: scipy.stats is slow to import
        p = as_scalar("probability", probability, "", above=0.0, below=1.0)
        nu = self.edf(alpha)
        lo = self.adev * np.sqrt(nu / chi2.ppf(0.5 + p / 2, nu))
        hi = self.adev * np.sqrt(nu / chi2.ppf(0.5 - p / 2, nu))
        return lo, hi


class AllanAccumulator:
    """The overlapping Allan variance of a record fed chunk by chunk.

    Parameters
    ----------
    dt_s : float
        Sampling interval, s.
    m : array_like of int
        Averaging factors (:func:`averaging_factors` of the record's length when known).
    n_cols : int
        Columns of every chunk (6 for gyro x y z, accel x y z).
    names : sequence of str, optional
        Column names, for messages and results.

    Memory: a buffer of 2.5 max(m) rows of phase per column (at least 2 max(m) + 65536),
    whatever the record's length.
    """

    def __init__(self, dt_s: float, m, n_cols: int, names=None):
        self.dt_s = as_scalar("dt_s", dt_s, "s", above=0.0)
        m = np.asarray(m)
        if m.ndim != 1 or m.size == 0 or m.dtype.kind not in "iu" or np.any(m < 1):
            raise ValueError(f"m must be a non-empty 1-D array of integers >= 1; got {m!r}")
        self.m = np.unique(m).astype(np.int64)
        if not (isinstance(n_cols, (int, np.integer)) and 1 <= n_cols <= int(lib.GF_ALLAN_MAX_COLS)):
            raise ValueError(f"n_cols must be an integer in 1..{int(lib.GF_ALLAN_MAX_COLS)}; got {n_cols!r}")
        self.n_cols = int(n_cols)
        self.names = tuple(names) if names is not None else tuple(f"col{j}" for j in range(self.n_cols))
        if len(self.names) != self.n_cols:
            raise ValueError(f"{len(self.names)} names for {self.n_cols} columns")
        self._hist = 2 * int(self.m[-1])
        self._sums = np.zeros(self.m.size * self.n_cols)
        self._counts = np.zeros(self.m.size, dtype=np.uint64)
        self._buf = None
        self._fill = 0                 # rows of the buffer in use
        self._offset = None            # the constant removed before the phase is formed
        self.n_samples = 0

    def add(self, y) -> None:
        """Feed the next chunk of samples (rows, n_cols): rates in the columns' units."""
        y = as_array("chunk", y, (None, self.n_cols), "the columns' units", finite=False)
        if self._offset is None and y.shape[0]:
            with np.errstate(invalid="ignore"):
                self._offset = np.mean(y, axis=0)
            self._offset[~np.isfinite(self._offset)] = 0.0
            # column after column (C reads each column's phase contiguously): the history
            # and a piece of new rows; when full, the last 2 m_max rows move to the front
            # (a copy of 2 m_max rows per piece of at least m_max / 2 rows: <= 4 copies of
            # each sample in all)
            self._buf = np.zeros((self.n_cols, self._hist + max(self._hist // 4, _MIN_PIECE) + 1))
            self._fill = 1                                   # x_0 = 0
        piece = self._buf.shape[1] - self._hist - 1 if self._buf is not None else 0
        for start in range(0, y.shape[0], max(piece, 1)):
            self._add_piece(y[start:start + piece])

    def _add_piece(self, y: np.ndarray) -> None:
        rows = y.shape[0]
        if self._fill + rows > self._buf.shape[1]:
            keep = min(self._fill, self._hist)
            shift = self._fill - keep
            for a in range(0, keep, shift):    # blocks that do not overlap: no temporary
                b = min(a + shift, keep)
                self._buf[:, a:b] = self._buf[:, a + shift:b + shift]
            self._fill = keep
        start = self._fill
        new = self._buf[:, start:start + rows]
        np.subtract(y.T, self._offset[:, None], out=new)
        np.cumsum(new, axis=1, out=new)
        new += self._buf[:, start - 1:start]
        bad = ffi.new("size_t *")
        k = self.m.size
        status = lib.gf_allan_sums(start + rows, self.n_cols, ptr(self._buf, self._buf.size),
                                   self._buf.shape[1], start, k, ptr(self.m, k, "int64_t"),
                                   ptr(self._sums, k * self.n_cols), ptr(self._counts, k, "uint64_t"), bad)
        if status != lib.GF_OK:
            if status == lib.GF_ERR_NONFINITE_INPUT:
                row = int(bad[0]) - start
                col = int(np.flatnonzero(~np.isfinite(y[row]))[0]) if row < rows else -1
                raise NonFiniteInputError(
                    f"sample {self.n_samples + row} ({self.names[col] if col >= 0 else '?'}) is not "
                    f"finite: the sums hold the {self.n_samples} samples before its piece of the "
                    "record (.partial; remove or repair the sample)", self.n_samples + row, col,
                    self.result() if self.n_samples >= 4 else None)
            raise ValueError(f"gf_allan_sums: {status_text(status)}")
        self._fill = start + rows
        self.n_samples += rows

    def result(self) -> AllanDeviation:
        """The deviation at every factor with at least two second differences."""
        n_phase = self.n_samples + 1
        sel = self._counts >= 2
        if not np.any(sel):
            raise ValueError(f"{self.n_samples} samples: too short for the smallest averaging "
                             f"factor m = {int(self.m[0])} (needs 2m + 2 samples)")
        m = self.m[sel]
        n = self._counts[sel].astype(float)
        sums = self._sums.reshape(-1, self.n_cols)[sel]
        adev = np.sqrt(sums / (2.0 * n[:, None])) / m[:, None]
        assert np.all(n == n_phase - 2 * m), "every term counted once"
        return AllanDeviation(m * self.dt_s, adev, n.astype(np.int64), m, self.n_samples,
                              self.dt_s, self.names)


def allan_deviation(y, dt_s: float, m=None, *, names=None, per_decade: int = 10,
                    max_fraction: float = MAX_FRACTION) -> AllanDeviation:
    """Overlapping Allan deviation of the columns of ``y`` ((n,) or (n, c) rates, the
    columns' units per second of averaging) sampled every ``dt_s`` s, at factors ``m``
    (default :func:`averaging_factors`); streamed in chunks through
    :class:`AllanAccumulator`.

    Examples
    --------
    >>> import numpy as np
    >>> y = np.random.default_rng(0).normal(0.0, 0.01, (100000, 3))   # white, 0.01 per sample
    >>> ad = allan_deviation(y, 0.01)
    >>> bool(abs(ad.adev[0, 0] / 0.01 - 1) < 0.02)       # sigma(tau0) = per-sample std
    True
    """
    arr = np.asarray(y)
    if arr.ndim == 1:
        arr = arr[:, None]
    arr = as_array("y", arr, (None, None), "the columns' units", finite=False)
    if m is None:
        m = averaging_factors(arr.shape[0], per_decade, max_fraction)
    acc = AllanAccumulator(dt_s, m, arr.shape[1], names)
    for start in range(0, arr.shape[0], _CHUNK_ROWS):
        acc.add(arr[start:start + _CHUNK_ROWS])
    return acc.result()
