"""Signal conditioning of inertial records (seed 004): a Chebyshev type-II low-pass
designed with scipy.signal as second-order sections and run by the C core
(``gf_biquad``) as a streaming cascade; a cutoff recommended from the record's spectrum
(the FFT study seed 004 made before choosing its filter), and a plot of both.
"""
from __future__ import annotations

import pathlib

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_positive_scalar, ffi, first_nonfinite,
                            lib, ptr)

__all__ = ["design_cheby2", "BiquadFilter", "recommend_cutoff", "plot_spectrum"]

MAX_SECTIONS = int(lib.GF_BIQUAD_MAX_SECTIONS)
MAX_CHANNELS = int(lib.GF_BIQUAD_MAX_CHANNELS)


def design_cheby2(cutoff_hz: float, fs_hz: float, order: int = 4,
                  stopband_db: float = 40.0) -> np.ndarray:
    """Chebyshev type-II low-pass as second-order sections (scipy.signal.cheby2).

    Parameters
    ----------
    cutoff_hz : float
        Stop-band edge (Hz): from here on the attenuation is at least ``stopband_db``.
        Must lie strictly between 0 and the Nyquist frequency fs/2.
    fs_hz : float
        Sampling rate (Hz).
    order : int
        Filter order (1..2*MAX_SECTIONS).
    stopband_db : float
        Minimum stop-band attenuation (dB), > 0.

    Returns
    -------
    ndarray (n_sections, 6)
    """
    from scipy.signal import cheby2   # lazy: scipy (0.1-0.5 s) off the start-up path
    fs_hz = as_positive_scalar("fs_hz (sampling rate)", fs_hz, "Hz")
    cutoff_hz = as_positive_scalar("cutoff_hz", cutoff_hz, "Hz")
    if cutoff_hz >= fs_hz / 2:
        raise ValueError(f"cutoff_hz = {cutoff_hz} Hz must be below the Nyquist frequency "
                         f"{fs_hz / 2} Hz (fs_hz / 2)")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 2 * MAX_SECTIONS:
        raise ValueError(f"order must be an integer in 1..{2 * MAX_SECTIONS}; got {order!r}")
    stopband_db = as_positive_scalar("stopband_db", stopband_db, "dB")
    sos = cheby2(int(order), stopband_db, cutoff_hz, btype="low", output="sos", fs=fs_hz)
    poles = np.concatenate([np.roots(s[3:]) for s in sos])
    if np.any(np.abs(poles) >= 1.0):
        raise ValueError("the design is unstable (a pole on or outside the unit circle): "
                         "lower the order or raise the cutoff")
    return sos


class BiquadFilter:
    """Streaming SOS filter (C core): :meth:`filter` continues where the last call ended.

    Parameters
    ----------
    sos : array_like (n_sections, 6)
        Second-order sections [b0 b1 b2 a0 a1 a2] with a0 = 1 (scipy's format).
    n_channels : int
        Columns filtered side by side (e.g. 3 gyro axes).
    """

    def __init__(self, sos, n_channels: int = 1):
        s = np.ascontiguousarray(sos, dtype=float)
        if s.ndim != 2 or s.shape[1] != 6 or not 1 <= s.shape[0] <= MAX_SECTIONS:
            raise ValueError(f"sos must have shape (n_sections, 6) with 1..{MAX_SECTIONS} "
                             f"sections; got {s.shape}")
        if isinstance(n_channels, bool) or not isinstance(n_channels, (int, np.integer)) \
                or not 1 <= n_channels <= MAX_CHANNELS:
            raise ValueError(f"n_channels must be an integer in 1..{MAX_CHANNELS}; got {n_channels!r}")
        self.sos = s
        self.n_channels = int(n_channels)
        self._c = ffi.new("gf_biquad *")
        bad = ffi.new("size_t *")
        status = lib.gf_biquad_init(self._c, s.shape[0], ptr(s, s.size), self.n_channels, bad)
        if status != lib.GF_OK:
            i = int(bad[0])
            reason = {lib.GF_ERR_NONFINITE_INPUT: "has a non-finite coefficient",
                      lib.GF_ERR_BAD_PARAMETER: "has a0 != 1 (normalise the section)",
                      lib.GF_ERR_SINGULAR_GEOMETRY: "is unstable (a pole on or outside the unit circle)",
                      }.get(status, "was refused")
            raise ValueError(f"sos section {i} {reason}: {s[i].tolist()}")

    def steady_state(self, x0) -> None:
        """Start at steady state for a constant input x0 (n_channels,): no transient."""
        from scipy.signal import sosfilt_zi   # lazy: scipy (0.1-0.5 s) off the start-up path
        x0 = np.asarray(x0, float).reshape(self.n_channels)
        zi = sosfilt_zi(self.sos)                              # (n_sections, 2) per unit step
        z = np.ascontiguousarray(zi[:, None, :] * x0[None, :, None])
        if lib.gf_biquad_set_state(self._c, ptr(z, z.size), z.size) != lib.GF_OK:
            raise ValueError("x0 must be finite")

    def filter(self, x) -> np.ndarray:
        """Filter a chunk (n, n_channels) or (n,) for one channel; returns the same shape."""
        arr = np.asarray(x, dtype=float)
        one_d = arr.ndim == 1
        if one_d and self.n_channels == 1:
            arr = arr[:, None]
        if arr.ndim != 2 or arr.shape[1] != self.n_channels:
            raise ValueError(f"x must have shape (n, {self.n_channels}); got {np.shape(x)}")
        arr = np.ascontiguousarray(arr)
        y = np.empty_like(arr)
        done = ffi.new("size_t *")
        status = lib.gf_biquad_run(self._c, arr.shape[0], ptr(arr, arr.size), ptr(y, y.size), done)
        if status == lib.GF_ERR_OUT_OF_RANGE:
            k = int(done[0])
            raise SampleError(f"x[{k}] = {arr[k].tolist()} overflows the filter (its output or "
                              "state is beyond the double range): scale the record down; rows "
                              "before it were filtered (see .partial)", int(status), k,
                              y[:k, 0].copy() if one_d else y[:k].copy())
        if status != lib.GF_OK:
            k = int(done[0])
            col = first_nonfinite(arr, k)
            raise NonFiniteInputError(f"x[{k}, {col}] = {arr[k, col]} is not finite; rows before "
                                      "it were filtered (see .partial)", k, col,
                                      y[:k, 0].copy() if one_d else y[:k].copy())
        return y[:, 0] if one_d else y


def recommend_cutoff(x, fs_hz: float, energy_fraction: float = 0.99,
                     nperseg: int | None = None) -> float:
    """Lowest frequency (Hz) below which ``energy_fraction`` of the record's variance
    lies (Welch power spectrum of the detrended record, channels summed): the band the
    motion occupies, which a low-pass should keep (seed 004 read it off an FFT of its
    vehicle data: the energy sits at low frequency)."""
    from scipy.signal import welch   # lazy: scipy (0.1-0.5 s) off the start-up path
    fs_hz = as_positive_scalar("fs_hz (sampling rate)", fs_hz, "Hz")
    if not 0 < energy_fraction < 1:
        raise ValueError(f"energy_fraction must be in (0, 1); got {energy_fraction!r}")
    arr = np.asarray(x, float)
    arr = arr[:, None] if arr.ndim == 1 else arr
    if arr.ndim != 2 or arr.shape[0] < 16 or not np.all(np.isfinite(arr)):
        raise ValueError("x must be a finite record of at least 16 samples, shape (n,) or (n, k)")
    f, p = welch(arr, fs=fs_hz, nperseg=nperseg or min(arr.shape[0], 4096), axis=0,
                 detrend="linear")
    psd = p.sum(axis=1)
    cum = np.cumsum(psd)
    if cum[-1] <= 0:
        raise ValueError("the record has no variance: nothing to choose a cutoff from")
    return float(f[np.searchsorted(cum / cum[-1], energy_fraction)])


def plot_spectrum(x, fs_hz: float, sos=None, path: str | pathlib.Path = "spectrum.png",
                  cutoff_hz: float | None = None) -> pathlib.Path:
    """Power spectrum of a record (Welch) with, if given, the filter's magnitude
    response and the cutoff; written to ``path`` (PNG)."""
    import matplotlib   # lazy: matplotlib (~0.3 s) only for figures
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy.signal import sosfreqz, welch
    arr = np.asarray(x, float)
    arr = arr[:, None] if arr.ndim == 1 else arr
    f, p = welch(arr, fs=fs_hz, nperseg=min(arr.shape[0], 4096), axis=0, detrend="linear")
    fig, ax = plt.subplots(figsize=(9, 4.5), constrained_layout=True)
    for j in range(p.shape[1]):
        ax.semilogy(f, p[:, j], lw=0.8, label=f"channel {j}")
    ax.set(xlabel="frequency (Hz)", ylabel="power spectral density (unit²/Hz)",
           title="Record spectrum and low-pass response")
    if sos is not None:
        w, h = sosfreqz(sos, worN=2048, fs=fs_hz)
        ax2 = ax.twinx()
        ax2.plot(w, 20 * np.log10(np.maximum(np.abs(h), 1e-12)), "k", lw=1.2, label="filter")
        ax2.set_ylabel("filter gain (dB)")
        ax2.set_ylim(-100, 5)
    if cutoff_hz is not None:
        ax.axvline(cutoff_hz, color="r", ls="--", label=f"cutoff {cutoff_hz:.3g} Hz")
    ax.legend(fontsize=8, loc="lower left")
    path = pathlib.Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
