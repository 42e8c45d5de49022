"""Stability of an array's rate loop: the linearised error dynamics of each rate strategy
at frozen rates over the rate envelope (the one linearisation of the loop that
:mod:`gfins_fmi.analysis.gyrofree_errors` reuses)."""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import as_positive_scalar
from gfins_fmi.gyrofree.array import ArrayGeometry
from gfins_fmi.gyrofree.geometry import STRATEGIES, fit_pinv, on_jacobian, rate_model, solver_maps

__all__ = ["LoopStability", "rate_loop_stability"]

def _fibonacci_sphere(n: int) -> np.ndarray:
    """n unit vectors spread evenly over the sphere (golden-angle spiral)."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + np.sqrt(5.0)) * k
    r = np.sqrt(1 - z * z)
    return np.c_[r * np.cos(phi), r * np.sin(phi), z]


@dataclass(frozen=True)
class LoopStability:
    """The linearised error dynamics of a rate strategy on an array, at frozen rates of
    magnitude ``max_rate_rad_s`` in every direction (and a fifth of it for ``fused``).

    Attributes
    ----------
    strategy : str
    verdict : {"stable", "marginal", "unstable", "not applicable"}
        stable: rate errors decay (or, per-sample strategies, do not propagate);
        marginal: they neither grow nor decay exponentially (an w_dot error integrates);
        unstable: they grow exponentially somewhere in the rate envelope.
    growth_rate_s : float
        Largest exponential growth rate of the rate error (1/s) over the envelope;
        -inf when errors do not propagate, 0 for marginal loops.
    worst_rate_rad_s : (3,) array
        The rate (body axes) where it is largest.
    reason : str
        One sentence for the user.
    """
    strategy: str
    verdict: str
    growth_rate_s: float
    worst_rate_rad_s: np.ndarray
    reason: str


#: relative threshold on growth rates: below it (times the loop gain), round-off
_GROWTH_TOL = 1e-9


def _integrate_stability(maps, dirs, wmax):
    A = maps.loop_matrix(wmax * dirs)
    ev = np.linalg.eigvals(A)
    g = ev.real.max(axis=1)
    k = int(np.argmax(g))
    gain = np.abs(A).max()
    if maps.n_conf == 0:
        return "marginal", 0.0, wmax * dirs[k], ("nothing feeds back: w is the integral of w_dot "
                                                 "(a w_dot bias makes a rate ramp)")
    if g[k] > _GROWTH_TOL * gain:
        return "unstable", float(g[k]), wmax * dirs[k], (
            f"the {maps.n_conf} confounded product combination(s), taken from the predicted "
            f"rate, feed rate errors back into w_dot with positive eigenvalues (up to "
            f"{g[k]:.3g}/s at {wmax:g} rad/s)")
    return "marginal", 0.0, wmax * dirs[k], ("the confounded products feed rate errors back "
                                             "with eigenvalues on the imaginary axis only")


def _sqrt_stability(maps, dirs, wmax, dt, model):
    if model == "none":
        return "not applicable", np.nan, np.zeros(3), (
            f"the array observes {maps.n_obs} product combination(s); reading the rate from "
            "them sample by sample needs at least 3")
    if maps.n_conf == 0:
        return "stable", -np.inf, np.zeros(3), (
            "every sample is solved on its own (no confounded products): errors do not "
            "propagate; mirror images are resolved by the w_dot integral")
    W = wmax * dirs
    J = on_jacobian(W)
    G = np.einsum("jc,njk->nck", maps.observed, J)                 # (n, n_obs, 3)
    Kz = np.einsum("cj,njk->nck", maps.K_pred[6:], J)               # dz / d(w_pred)
    M = -np.einsum("nkc,ncl->nkl", fit_pinv(maps, G, model), Kz)
    A = maps.loop_matrix(W)
    M = M @ (np.eye(3) + dt * A)                                     # w_pred = w + dt w_dot
    rho = np.abs(np.linalg.eigvals(M)).max(axis=1)
    k = int(np.argmax(rho))
    g = np.log(rho[k]) / dt if rho[k] > 0 else -np.inf
    if rho[k] > 1 + _GROWTH_TOL:
        return "unstable", float(g), W[k], (
            f"the confounded products of the predicted rate corrupt the observed ones: a rate "
            f"error is multiplied by up to {rho[k]:.3g} each sample (near rates where the "
            "observed products barely determine w)")
    if rho[k] < 1e-9:
        return "stable", float(g), W[k], (
            "the confounded products do not reach the observed ones: every sample is solved "
            "on its own, errors do not propagate; mirror images are resolved by the w_dot "
            "integral")
    if rho[k] < 1 - _GROWTH_TOL:
        return "stable", float(g), W[k], (
            f"a rate error fed back through the confounded products shrinks by a factor "
            f"{rho[k]:.3g} or better each sample")
    return "marginal", 0.0, W[k], "rate errors are carried from sample to sample unchanged"


def _fused_stability(maps, dirs, wmax):
    if maps.n_obs == 0:
        return "not applicable", np.nan, np.zeros(3), (
            "the array observes no product combination: there is nothing to fuse "
            "(the filter would only integrate w_dot)")
    Mz = maps.measurement_matrix()
    worst, where, n_unobs = -np.inf, np.zeros(3), 0
    for scale in (1.0, 0.2):
        W = scale * wmax * dirs
        A = maps.loop_matrix(W)
        C = np.einsum("cj,njk->nck", Mz, on_jacobian(W))
        n = W.shape[0]
        Ac = np.zeros((n, 6, 6))
        Ac[:, :3, :3] = A
        Ac[:, :3, 3:] = -np.eye(3)
        Cc = np.zeros((n, maps.n_obs, 6))
        Cc[:, :, :3] = C
        # observability matrix of the pair scaled to unit norms (the subspace does not
        # depend on the scales; unscaled, the powers of A span ~1e10 and the rank
        # tolerance would count weakly observed directions as unobservable)
        a_n = np.maximum(np.linalg.norm(Ac, axis=(1, 2)), 1e-300)[:, None, None]
        c_n = np.maximum(np.linalg.norm(Cc, axis=(1, 2)), 1e-300)[:, None, None]
        As, blocks, P = Ac / a_n, [], Cc / c_n
        for _ in range(6):
            blocks.append(P)
            P = P @ As
        O = np.concatenate(blocks, axis=1)
        _, sv, vt = np.linalg.svd(O)
        for i in range(n):
            r = int(np.sum(sv[i] > 1e-9 * max(sv[i, 0], 1e-300)))
            if r == 6:
                continue
            N = vt[i, r:].T                          # unobservable subspace: A-invariant
            M = N.T @ Ac[i] @ N
            if np.linalg.norm(Ac[i] @ N - N @ M) > 1e-6 * a_n[i, 0, 0]:
                continue                             # not invariant: a rank-tolerance artefact
            n_unobs = max(n_unobs, 6 - r)
            lam = np.linalg.eigvals(M).real.max()
            if lam > worst:
                worst, where = lam, W[i]
    # eigenvalues of the restricted map carry ~1e-6 |A| of the subspace's error
    gain = max(np.abs(maps.loop_matrix(wmax * dirs)).max(), 1.0) * 1e3
    if n_unobs == 0:
        return "stable", -np.inf, np.zeros(3), (
            f"the {maps.n_obs} observed product combination(s) and the loop through w_dot make "
            "every rate and w_dot-bias error observable at every sampled rate: the filter "
            "corrects them (the array's outputs determine the rate locally)")
    if worst > _GROWTH_TOL * gain:
        return "unstable", float(worst), where, (
            f"an error direction the observed products do not see grows at {worst:.3g}/s "
            f"(at {np.linalg.norm(where):.3g} rad/s)")
    return "marginal", 0.0, where, (
        f"{n_unobs} error direction(s) are unobservable at some rates (neither growing nor "
        "decaying): there the filter integrates w_dot")


def rate_loop_stability(geometry: ArrayGeometry, strategy: str, max_rate_rad_s: float = 5.0,
                        dt_s: float = 0.01, n_directions: int = 400) -> LoopStability:
    """Stability of a rate strategy's error loop on an array (see :class:`LoopStability`).

    The loop: ``integrate`` and ``fused`` propagate w with the measured w_dot, which
    carries the confounded products of the predicted rate, d(w_dot) = A(w) dw with
    A(w) = -K_wd J(w) (K_wd: rows of the solver's K_pred); ``fused`` also sees
    dz = (B_o^T + K_z) J(w) dw through the observed combinations and is stable when
    every error of its state [w, w_dot bias] is observable (detectability of the frozen
    pair); ``sqrt``/``eigen`` solve each sample, dw_k = -G^+ K_z J(w) (I + dt A) dw_(k-1)
    with G = B_o^T J(w), stable when that map contracts. A is linear in w, so a loop
    unstable at some rate is unstable at every multiple of it; growth rates are quoted
    at ``max_rate_rad_s``. Rates are sampled on ``n_directions`` directions.
    """
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {sorted(STRATEGIES)}; got {strategy!r}")
    wmax = as_positive_scalar("max_rate_rad_s", max_rate_rad_s, "rad/s")
    dt = as_positive_scalar("dt_s", dt_s, "s")
    return _stability_cached(_geometry_key(geometry), strategy, float(wmax), float(dt),
                             int(n_directions))


def _geometry_key(geometry: ArrayGeometry):
    if not isinstance(geometry, ArrayGeometry):
        raise TypeError("geometry must be an ArrayGeometry (e.g. layout('qin9', 0.1))")
    return (geometry.u_m.tobytes(), geometry.theta.tobytes())


@functools.lru_cache(maxsize=256)
def _stability_cached(key, strategy, wmax, dt, n_dir) -> LoopStability:
    u = np.frombuffer(key[0]).reshape(-1, 3)
    t = np.frombuffer(key[1]).reshape(-1, 3)
    maps = solver_maps(ArrayGeometry(u, t))
    dirs = _fibonacci_sphere(n_dir)
    if strategy == "integrate":
        res = _integrate_stability(maps, dirs, wmax)
    elif strategy == "fused":
        res = _fused_stability(maps, dirs, wmax)
    else:
        model = rate_model(maps, strategy)
        if strategy == "eigen" and model != "full":
            res = ("not applicable", np.nan, np.zeros(3),
                   "'eigen' needs all of w w^T observed (6 combinations); this array observes "
                   f"{maps.n_obs}")
        else:
            res = _sqrt_stability(maps, dirs, wmax, dt, model)
    verdict, g, where, reason = res
    return LoopStability(strategy, verdict, float(g), np.asarray(where, float), reason)
