"""Coloured noise shared by the sensor-error models (simulation only): the IMU's
(:class:`gfins_fmi.nav.imu_errors.ImuNoise`) and the accelerometer array's
(:class:`gfins_fmi.gyrofree.array_errors.ArraySensorErrors`). It sits in ``nav`` beside
the first of them so that both import it downward (``sim`` builds on both)."""
from __future__ import annotations

import numpy as np

__all__ = ["first_order_lowpass_noise"]


def first_order_lowpass_noise(n: int, channels: int, std: float, corner_hz: float,
                              dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """(n, channels) white noise through y_k = a y_(k-1) + (1 - a) x_k, a = exp(-2 pi fc
    dt), scaled to the stationary std ``std`` and started in steady state (the state
    drawn from the stationary distribution). Band-limited noise of bandwidth fc; with
    a = exp(-dt/tau) the same recursion is a first-order Gauss-Markov process."""
    from scipy.signal import lfilter   # lazy: scipy (0.1-0.5 s) off the start-up path
    if std == 0 or n == 0:
        return np.zeros((n, channels))
    a = np.exp(-2 * np.pi * corner_hz * dt_s)
    # stationary variance of y: sx^2 (1 - a) / (1 + a)
    sx = std / np.sqrt((1 - a) / (1 + a))
    x = rng.normal(0.0, sx, (n, channels))
    y0 = rng.normal(0.0, std, channels)
    y, _ = lfilter([1 - a], [1, -a], x, axis=0, zi=(a * y0)[None, :])
    return y
