"""The Kalman engine's pieces that the integrated navigator added (csrc/est/gf_kalman via cffi):
structured predict, Joseph update with the NIS gate, the unscented transform, one
Rauch-Tung-Striebel step and the chi-square gate's quantiles, each against a numpy
re-derivation of its formula (not the code under test).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from gfins_fmi._lib import ffi, lib, ptr


def _kf(P):
    n = P.shape[0]
    kf = ffi.new("gf_kalman *")
    x0 = np.zeros(n)
    assert lib.gf_kalman_init(kf, n, ptr(x0), ptr(np.ascontiguousarray(P))) == lib.GF_OK
    return kf


def _P(kf, n):
    return np.frombuffer(ffi.buffer(kf.P), dtype=float)[:n * n].reshape(n, n).copy()


def _random_spd(rng, n):
    B = rng.normal(size=(n, n))
    return B @ B.T + n * np.eye(n)


def test_structured_predict_equals_dense(rng):
    n = 15
    P = _random_spd(rng, n)
    A = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.3)
    q1, q2 = rng.random(n), rng.random(n)
    kf = _kf(P)
    assert lib.gf_kalman_predict_sparse(kf, ptr(np.ascontiguousarray(A)), ptr(q1), ptr(q2)) == lib.GF_OK
    Phi = np.eye(n) + A
    ref = Phi @ (P + np.diag(q1)) @ Phi.T + np.diag(q2)
    np.testing.assert_allclose(_P(kf, n), ref, rtol=1e-13, atol=1e-12 * np.abs(ref).max())
    A[2, 3] = np.inf
    before = _P(kf, n)
    assert lib.gf_kalman_predict_sparse(kf, ptr(np.ascontiguousarray(A)), ptr(q1), ptr(q2)) == \
        lib.GF_ERR_NONFINITE_INPUT
    assert np.array_equal(_P(kf, n), before)


def test_joseph_update_and_gate(rng):
    """The factored Joseph update equals the textbook product form; a gated update
    leaves the filter unchanged."""
    n, m = 15, 3
    P = _random_spd(rng, n)
    H = rng.normal(size=(m, n))
    R = np.diag(rng.random(m) + 0.5)
    r = rng.normal(size=m)
    kf = _kf(P)
    nis = ffi.new("double *")
    acc = ffi.new("int *")
    assert lib.gf_kalman_update_gated(kf, m, ptr(r), ptr(np.ascontiguousarray(H)), ptr(R), 0.0, nis, acc) == lib.GF_OK
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    IKH = np.eye(n) - K @ H
    ref = IKH @ P @ IKH.T + K @ R @ K.T
    np.testing.assert_allclose(_P(kf, n), ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())
    np.testing.assert_allclose(np.frombuffer(ffi.buffer(kf.x), float)[:n], K @ r, rtol=1e-11, atol=1e-13)
    assert acc[0] == 1 and nis[0] == pytest.approx(r @ np.linalg.solve(S, r), rel=1e-12)
    kf2 = _kf(P)
    assert lib.gf_kalman_update_gated(kf2, m, ptr(r * 100), ptr(np.ascontiguousarray(H)), ptr(R), 5.0, nis, acc) == lib.GF_OK
    assert acc[0] == 0 and nis[0] > 5.0
    assert np.array_equal(_P(kf2, n), P)


def test_unscented_transform_against_numpy(rng):
    n = 6
    P = _random_spd(rng, n) * 1e-2
    w = ffi.new("gf_ukf_weights *")
    alpha, beta, kappa = 0.5, 2.0, 0.0
    assert lib.gf_ukf_weights_init(w, n, alpha, beta, kappa) == lib.GF_OK
    lam = alpha ** 2 * (n + kappa) - n                      # seed 004 below eq. 28
    assert w.gamma == pytest.approx(np.sqrt(n + lam))
    assert w.wm0 == pytest.approx(lam / (n + lam))
    assert w.wc0 == pytest.approx(lam / (n + lam) + 1 - alpha ** 2 + beta)
    assert w.wi == pytest.approx(1 / (2 * (n + lam)))
    kf = _kf(P)
    X = np.empty((2 * n + 1, n))
    assert lib.gf_ukf_sigma_points(kf, w, ptr(X)) == lib.GF_OK
    # the points reproduce mean and covariance exactly (any square root of P)
    Wm = np.r_[w.wm0, np.full(2 * n, w.wi)]
    Wc = np.r_[w.wc0, np.full(2 * n, w.wi)]
    np.testing.assert_allclose(Wm @ X, 0, atol=1e-15)
    np.testing.assert_allclose((X * Wc[:, None]).T @ X - (1 - alpha ** 2 + beta) * 0, P, rtol=1e-12)
    # a linear measurement: the UKF update equals the Kalman update
    H = rng.normal(size=(2, n))
    R = np.diag([0.3, 0.2])
    z = rng.normal(size=2)
    Z = X @ H.T
    nis = ffi.new("double *")
    acc = ffi.new("int *")
    assert lib.gf_ukf_update(kf, w, ptr(X), 2, ptr(Z), ptr(z), ptr(R), 0.0, nis, acc) == lib.GF_OK
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    np.testing.assert_allclose(_P(kf, n), P - K @ S @ K.T, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(np.frombuffer(ffi.buffer(kf.x), float)[:n], K @ z, rtol=1e-10, atol=1e-14)
    # a nonlinear time update: mean and covariance of y = x + 0.5 x0^2 e0 through the points
    kf3 = _kf(P)
    Y = X.copy()
    Y[:, 0] += 0.5 * X[:, 0] ** 2
    assert lib.gf_ukf_predict(kf3, w, ptr(Y), ffi.NULL) == lib.GF_OK
    x3 = np.frombuffer(ffi.buffer(kf3.x), float)[:n]
    assert x3[0] == pytest.approx(0.5 * P[0, 0], rel=1e-12)     # E[x0^2]/2, exact for Gaussians


def test_rts_step_against_numpy(rng):
    n = 5
    Pp, Ps_next = _random_spd(rng, n), _random_spd(rng, n)
    Phi = np.eye(n) + 0.1 * rng.normal(size=(n, n))
    Q = np.diag(rng.random(n))
    Pprior = Phi @ Pp @ Phi.T + Q
    xp, xprior, xs_next = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    xs, Ps = np.empty(n), np.empty((n, n))
    assert lib.gf_kalman_rts_step(n, ptr(Pp), ptr(xp), ptr(np.ascontiguousarray(Phi)), ptr(Pprior), ptr(xprior),
                                  ptr(Ps_next), ptr(xs_next), ptr(xs), ptr(Ps)) == lib.GF_OK
    Ag = Pp @ Phi.T @ np.linalg.inv(Pprior)
    np.testing.assert_allclose(xs, xp + Ag @ (xs_next - xprior), rtol=1e-12)
    np.testing.assert_allclose(Ps, Pp + Ag @ (Ps_next - Pprior) @ Ag.T, rtol=1e-11)


@pytest.mark.parametrize("m", [1, 2, 3, 6])
@pytest.mark.parametrize("p", [0.9, 0.99, 0.9999])
def test_chi2_gate_quantile(m, p):
    q = ffi.new("double *")
    assert lib.gf_chi2_quantile(m, p, q) == lib.GF_OK
    # Newton on the closed-form distribution: converged to round-off
    assert q[0] == pytest.approx(chi2.ppf(p, m), rel=1e-10)
