"""The overlapping Allan deviation (gfins_fmi.analysis.allan) against truths that are not
its code: allantools' ``oadev`` on the same data and tau set (a peer; round-off apart
they sum the same terms), the closed forms of the discrete processes our noise generator
draws (white noise, random walk, first-order Gauss-Markov: derived here from their
autocovariances, and shown to tend to the continuous forms of IEEE Std 952 / El-Sheimy et
al. 2008), streamed and whole-record sums equal, the equivalent degrees of freedom of NIST
SP 1065 (allantools' edf_simple as a peer), and the refusals.
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi._lib import NonFiniteInputError
from gfins_fmi.analysis.allan import (AllanAccumulator, allan_deviation, averaging_factors,
                                      edf_overlapping)
from gfins_fmi.nav.imu_errors import DEG_H, ImuNoise

allantools = pytest.importorskip("allantools", reason="allantools is in the test extra: "
                                 "pip install -e '.[test]'")


def _record(n=60000, seed=3):
    rng = np.random.default_rng(seed)
    y = rng.normal(0.0, 1e-3, (n, 4))
    y[:, 1] += 9.8 + np.cumsum(rng.normal(0.0, 1e-6, n))       # gravity on a random walk
    y[:, 2] += 0.004 * np.sin(np.arange(n) * 2e-4)              # a slow swing
    y[:, 3] = np.round(y[:, 3] * 2e3) / 2e3                     # quantised
    return y


def test_equals_allantools_on_the_same_tau_set():
    """Every deviation equals allantools' oadev for the same taus (freq data at 200 Hz)
    to <= 1e-9 relative (both sum the same squared second differences of the phase of
    the mean-removed record; measured ~1e-14: summation order), with the same counts."""
    y = _record()
    dt = 0.005
    ad = allan_deviation(y, dt)
    assert ad.tau_s.size > 30
    for c in range(y.shape[1]):
        t, dev, _, ns = allantools.oadev(y[:, c], rate=1 / dt, data_type="freq", taus=ad.tau_s)
        np.testing.assert_array_equal(np.round(t / dt).astype(int), ad.m)
        np.testing.assert_array_equal(ns, ad.n_terms)
        np.testing.assert_allclose(ad.adev[:, c], dev, rtol=1e-9, atol=0)


@pytest.mark.parametrize("chunk", [1, 97, 4096, 100000])
def test_streamed_in_any_chunks_equals_the_whole(chunk):
    """Chunks of any size (one sample, odd sizes, larger than the history) give the
    deviations of the whole record to round-off (1e-12 relative: the phase is summed
    chunk by chunk, the same terms are added in another order)."""
    y = _record(20000)
    whole = allan_deviation(y, 0.01)
    acc = AllanAccumulator(0.01, whole.m, 4)
    for s in range(0, len(y), chunk):
        acc.add(y[s:s + chunk])
    got = acc.result()
    np.testing.assert_array_equal(got.n_terms, whole.n_terms)
    np.testing.assert_allclose(got.adev, whole.adev, rtol=1e-12)


def _discrete_avar_from_acf(acf, m):
    """Allan variance of a stationary sequence with autocovariance acf(k) at factor m:
    half the variance of the difference of two adjacent m-sample means,
    Var(ybar) - Cov(ybar_1, ybar_2), each a weighted sum of the autocovariance."""
    k = np.arange(-(m - 1), m)
    w = (m - np.abs(k)) / m ** 2
    return np.sum(w * acf(np.abs(k))) - np.sum(w * acf(np.abs(k + m)))


def _gm_avar_continuous(sigma, T, tau):
    """First-order Gauss-Markov of stationary std sigma and correlation time T (El-Sheimy,
    Hou and Niu 2008, IEEE TIM 57(1), eq. for the exponentially correlated process):
    sigma^2 T / tau [2 - T / tau (3 - 4 exp(-tau/T) + exp(-2 tau/T))]."""
    x = tau / T
    return sigma ** 2 / x * (2 - (3 - 4 * np.exp(-x) + np.exp(-2 * x)) / x)


def test_discrete_closed_forms_tend_to_the_continuous_ones():
    """The derivations the generator is checked against: the discrete random walk gives
    K^2 dt (2m^2 + 1) / (6m) (-> K^2 tau / 3 of IEEE Std 952), the discrete AR(1) of a =
    exp(-dt/T) gives the continuous Gauss-Markov form as dt/T -> 0 (relative difference
    below 2 dt/T measured; here dt/T = 1e-3, bound 5e-3)."""
    K, dt = 2.0, 0.01
    for m in (1, 10, 1000):
        tau = m * dt
        assert K ** 2 * dt * (2 * m * m + 1) / (6 * m) == pytest.approx(K ** 2 * tau / 3, rel=1 / m ** 2)
    sigma, T = 1.5, 10.0
    a = np.exp(-dt / T)
    for m in (30, 300, 3000, 30000):
        disc = _discrete_avar_from_acf(lambda k: sigma ** 2 * a ** k, m)
        assert disc == pytest.approx(_gm_avar_continuous(sigma, T, m * dt), rel=5e-3)


def _inside(ad, col, truth, alpha, z=3.3):
    """The estimate at each tau inside its chi-square interval around the truth at
    probability 0.999 (z = 3.3 two-sided; a few taus per test, so a false alarm is
    ~1e-3 per tau and seeds are fixed)."""
    from scipy.stats import chi2
    nu = edf_overlapping(ad.n_terms + 2 * ad.m, ad.m, alpha)
    lo = truth * chi2.ppf(0.0005, nu) / nu
    hi = truth * chi2.ppf(0.9995, nu) / nu
    v = ad.avar[:, col]
    return (v >= lo) & (v <= hi), v / truth


def test_noise_generator_matches_the_closed_forms():
    """ImuNoise.sample_parts, 400 000 samples at 100 Hz, seed 11: the white part's Allan
    variance is N^2/tau, the rate random walk's K^2 dt (2m^2+1)/(6m), the Gauss-Markov
    bias's the AR(1) form; each at every tested tau inside its 99.9% chi-square interval
    (edf of NIST SP 1065 for the noise type of the part)."""
    n, dt = 400000, 0.01
    model = ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=20.0,
                     gyro_correlation_time_s=5.0, accel_vrw_ug_sqrt_hz=100.0,
                     accel_rrw_ug_sqrt_s=30.0)
    parts = model.sample_parts(n, dt, np.random.default_rng(11))
    m = np.array([1, 3, 10, 30, 100, 300, 1000, 3000, 10000], dtype=np.int64)
    N = model.gyro_arw_deg_sqrt_h * np.pi / 180 / 60
    ad = allan_deviation(parts["gyro_white"], dt, m)
    ok, ratio = _inside(ad, 0, N ** 2 / ad.tau_s, 0)
    assert ok.all(), ratio
    # the gyro bias: Gauss-Markov only (no rate random walk in this model)
    sigma, T = 20.0 * DEG_H, 5.0
    a = np.exp(-dt / T)
    ad = allan_deviation(parts["gyro_bias"], dt, m)
    truth = np.array([_discrete_avar_from_acf(lambda k: sigma ** 2 * a ** k, int(mm)) for mm in ad.m])
    alpha = np.where(ad.tau_s < T, -2, 0)         # random-walk-like below T, white above
    ok, ratio = _inside(ad, 1, truth, alpha)
    assert ok.all(), ratio
    # the accelerometer bias: a random walk of K ug/sqrt(s)
    K = 30.0 * 9.80665e-6
    ad = allan_deviation(parts["accel_bias"], dt, m[m <= 3000])
    truth = K ** 2 * dt * (2.0 * ad.m ** 2 + 1) / (6.0 * ad.m)
    ok, ratio = _inside(ad, 2, truth, -2)
    assert ok.all(), ratio
    # the accelerometer white noise: one-sided ASD S -> Allan N = S / sqrt(2)
    ad = allan_deviation(parts["accel_white"], dt, m)
    ok, ratio = _inside(ad, 0, (100 * 9.80665e-6 / np.sqrt(2)) ** 2 / ad.tau_s, 0)
    assert ok.all(), ratio


def test_edf_matches_nist_sp1065_as_allantools_writes_it():
    """edf_overlapping = allantools.edf_simple for every noise type and m >= 2 (1e-12);
    for flicker rate at m = 1 ours keeps the square of SP 1065's 2 (N-2)^2 / (2.3 N - 4.9),
    which allantools drops (its value is below 1 degree of freedom for a whole record)."""
    for N in (101, 5001):
        for m in (2, 5, 20, 40):
            for a in (2, 1, 0, -1, -2):
                assert float(edf_overlapping(N, m, a)) == pytest.approx(allantools.edf_simple(N, m, a),
                                                                         rel=1e-12)
    assert float(edf_overlapping(5001, 1, -1)) == pytest.approx(2 * 4999 ** 2 / (2.3 * 5001 - 4.9))
    assert allantools.edf_simple(5001, 1, -1) < 1.0


def test_confidence_interval_covers_the_truth_at_its_rate():
    """White noise of std 1, 50 seeded records of 5000 samples: the 68.3% interval at
    tau0 x {1, 10, 100} covers the truth 1/sqrt(m) in 68% +- 3 binomial stds of the
    150 cases (the edf is right for white rate noise)."""
    m = np.array([1, 10, 100], dtype=np.int64)
    hits = []
    for seed in range(50):
        y = np.random.default_rng(1000 + seed).normal(size=5000)
        ad = allan_deviation(y, 1.0, m)
        lo, hi = ad.confidence(0.683, alpha=0)
        hits += list((lo[:, 0] <= 1 / np.sqrt(m)) & (1 / np.sqrt(m) <= hi[:, 0]))
    frac, sd = np.mean(hits), np.sqrt(0.683 * 0.317 / len(hits))
    assert abs(frac - 0.683) < 3 * sd, frac


def test_refusals_say_what_to_change():
    with pytest.raises(ValueError, match="at least 4 samples"):
        averaging_factors(3)
    with pytest.raises(ValueError, match="integers >= 1"):
        AllanAccumulator(0.01, [0, 1], 3)
    with pytest.raises(ValueError, match="dt_s must be finite and > 0"):
        AllanAccumulator(0.0, [1], 3)
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        AllanAccumulator(0.01, [1], 3).add(np.zeros((5, 2)))
    y = np.random.default_rng(0).normal(size=(1000, 3))
    y[700, 2] = np.nan
    acc = AllanAccumulator(0.01, [1, 10], 3, names=("x", "y", "z"))
    acc.add(y[:500])
    with pytest.raises(NonFiniteInputError, match=r"sample 700 \(z\) is not finite") as err:
        acc.add(y[500:])
    assert err.value.index == 700 and err.value.partial.n_samples == 500
    with pytest.raises(ValueError, match="too short"):
        allan_deviation(np.zeros((10, 1)), 1.0, np.array([8], dtype=np.int64))
