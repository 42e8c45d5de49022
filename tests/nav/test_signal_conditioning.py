"""Chebyshev-II signal conditioning: the C biquad cascade against scipy.signal.sosfilt,
streamed in chunks; design and input errors; cutoff recommendation."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import sosfilt

from gfins_fmi.nav import signal_conditioning as sc


def test_c_cascade_matches_scipy_streamed_in_random_chunks(rng):
    """Same transposed-direct-form-II operations as scipy's sosfilt: equal to 1e-12
    relative (of the output's scale; scipy may contract to FMA, the core does not)."""
    fs = 200.0
    sos = sc.design_cheby2(8.0, fs, order=6, stopband_db=50.0)
    x = np.cumsum(rng.normal(size=(20_000, 3)), axis=0) + rng.normal(0, 5, (20_000, 3))
    ref = sosfilt(sos, x, axis=0)
    f = sc.BiquadFilter(sos, n_channels=3)
    parts, k = [], 0
    while k < len(x):
        m = int(rng.integers(1, 700))
        parts.append(f.filter(x[k:k + m]))
        k += m
    y = np.concatenate(parts)
    assert np.max(np.abs(y - ref)) <= 1e-12 * np.max(np.abs(ref))


def test_steady_state_start_has_no_transient():
    sos = sc.design_cheby2(5.0, 100.0)
    f = sc.BiquadFilter(sos)
    f.steady_state([9.81])
    y = f.filter(np.full(500, 9.81))
    assert np.max(np.abs(y - 9.81)) < 1e-12


def test_cutoff_recommendation_separates_motion_from_noise(rng):
    """Motion energy below 2 Hz plus white noise over 0..50 Hz whose variance is 0.5% of
    the motion's: the 99% point lies in the motion band's edge region, and the low-pass
    there removes most of the noise."""
    fs, n = 100.0, 60_000
    t = np.arange(n) / fs
    motion = np.sin(2 * np.pi * 0.3 * t) + 0.5 * np.sin(2 * np.pi * 1.5 * t)
    noise = rng.normal(0, np.sqrt(0.005 * motion.var()), n)
    fc = sc.recommend_cutoff(motion + noise, fs)
    assert 1.4 <= fc <= 10.0, fc
    sos = sc.design_cheby2(max(2 * fc, 3.0), fs, order=6)
    f = sc.BiquadFilter(sos)
    y = f.filter(motion + noise)
    # steady part (after the transient): residual noise much below the input noise
    resid = y[2000:] - sosfilt(sos, motion)[2000:]
    assert resid.std() < 0.5 * noise.std()


@pytest.mark.parametrize("kwargs, match", [
    (dict(cutoff_hz=50.0, fs_hz=100.0), "below the Nyquist frequency"),
    (dict(cutoff_hz=60.0, fs_hz=100.0), "below the Nyquist frequency"),
    (dict(cutoff_hz=0.0, fs_hz=100.0), "cutoff_hz must be finite and > 0"),
    (dict(cutoff_hz=5.0, fs_hz=100.0, order=0), "order must be an integer"),
])
def test_bad_designs(kwargs, match):
    with pytest.raises(ValueError, match=match):
        sc.design_cheby2(**kwargs)


def test_unstable_or_malformed_sections_are_refused():
    with pytest.raises(ValueError, match="section 1 is unstable"):
        sc.BiquadFilter([[1, 0, 0, 1, 0, 0], [1, 0, 0, 1, -2.1, 1.2]])
    with pytest.raises(ValueError, match="a0 != 1"):
        sc.BiquadFilter([[1, 0, 0, 2, 0, 0]])
    with pytest.raises(ValueError, match=r"shape \(n_sections, 6\)"):
        sc.BiquadFilter(np.zeros((2, 5)))


def test_nonfinite_sample_keeps_filtered_rows(rng):
    sos = sc.design_cheby2(5.0, 100.0)
    x = rng.normal(size=(100, 2))
    x[40, 1] = np.inf
    f = sc.BiquadFilter(sos, 2)
    with pytest.raises(Exception, match=r"x\[40, 1\]") as exc:
        f.filter(x)
    np.testing.assert_allclose(exc.value.partial, sosfilt(sos, x[:40], axis=0), rtol=0,
                               atol=1e-12 * np.abs(x[:40]).max())


def test_plot_spectrum(tmp_path, rng):
    x = rng.normal(size=(4000, 3))
    sos = sc.design_cheby2(10.0, 100.0)
    p = sc.plot_spectrum(x, 100.0, sos, tmp_path / "s.png", cutoff_hz=10.0)
    assert p.read_bytes()[:4] == b"\x89PNG"
