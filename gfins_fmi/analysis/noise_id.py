"""Noise identification from an Allan deviation: the standard terms of IEEE Std 952-1997
(Annex C) fitted per axis, and the result in the filter's units.

The model (per axis, y a rate in unit u: rad/s or m/s^2)::

    sigma^2(tau) = 3 Q^2 / tau^2        quantisation, Q in u s
                 + N^2 / tau            white rate: angle / velocity random walk, N in u sqrt(s)
                 + (2 ln 2 / pi) B^2    bias instability (flicker floor), B in u
                 + K^2 tau / 3          rate random walk, K in u / sqrt(s)
                 + R^2 tau^2 / 2        rate ramp, R in u / s

and, in place of the flicker floor where a bump shows one, a first-order Gauss-Markov
process of stationary std sigma and correlation time T (El-Sheimy, Hou and Niu 2008,
IEEE Trans. Instrum. Meas. 57(1))::

    sigma^2 T / tau [2 - T / tau (3 - 4 exp(-tau / T) + exp(-2 tau / T))].

Fit: non-negative weighted least squares on the Allan variance, weights edf / 2 /
model^2 (the variance of an estimate with edf degrees of freedom, divided by the taus
per octave: neighbouring taus of one record are correlated), iterated with the model's
own noise type at each tau; the Gauss-Markov time by a search over a log grid, refined.
The stated 1-sigma of a term is what the single most telling tau says about it (the
precision sqrt(2/edf) of the variance there over the term's share of the model), with,
for a Gauss-Markov model, the spread of the term over the Ts within chi-square + 1 of the
best (T's own uncertainty, from that profile); of a term fitted to zero, the size the
data could have hidden. The model with the Gauss-Markov bump is kept when it lowers the
weighted chi-square by more than 2 (one more parameter, Akaike).

For the filter (whose bias model is Gauss-Markov, no flicker): the bump's sigma and T
when one was found; otherwise the flicker floor converted the usual way, T = tau at the
minimum of the curve / 1.893 and sigma = B 0.664 / 0.617 (the Gauss-Markov curve of that
T peaks at 0.6174 sigma at 1.893 T, from the formula above; matching it to the floor
0.664 B), with a rate random walk folded in by the filter (``FilterConfig.noise_si``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi.analysis.allan import AllanDeviation, edf_overlapping

__all__ = ["NoiseTerms", "fit_noise_terms", "gm_avar_shape", "TERM_NAMES", "B_FACTOR",
           "GM_PEAK_FACTOR", "GM_PEAK_TAU"]

#: sigma(tau) of the flicker floor: sqrt(2 ln 2 / pi) B
B_FACTOR = float(np.sqrt(2.0 * np.log(2.0) / np.pi))
#: the Gauss-Markov Allan deviation peaks at GM_PEAK_FACTOR sigma at tau = GM_PEAK_TAU T
#: (the maximum of gm_avar_shape, computed: tests/analysis/test_noise_id.py)
GM_PEAK_TAU = 1.893
GM_PEAK_FACTOR = 0.6174
#: the terms, in the order of NoiseTerms.values
TERM_NAMES = ("quantisation", "white", "bias_instability", "rate_random_walk", "rate_ramp",
              "gm_sigma", "gm_tau_s")
_POWERS = (-2, -1, 0, 1, 2)
_COEF = (3.0, 1.0, B_FACTOR ** 2, 1.0 / 3.0, 0.5)     # sigma^2 = coef * term^2 * tau^power


def gm_avar_shape(tau, T) -> np.ndarray:
    """The Gauss-Markov Allan variance per unit stationary variance (the formula above),
    with its series 2x/3 - x^2/2 + 7x^3/30 for x = tau/T < 1e-3 (no cancellation)."""
    x = np.asarray(tau, dtype=float) / float(T)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        full = (2.0 - (-4.0 * np.expm1(-x) + np.expm1(-2.0 * x)) / x) / x
    series = 2.0 * x / 3.0 - x * x / 2.0 + 7.0 * x ** 3 / 30.0
    return np.where(x < 1e-3, series, full)


@dataclass
class NoiseTerms:
    """The fitted terms of one axis (units of the axis: see the module docstring).

    Attributes
    ----------
    values, stds : dict name -> float (TERM_NAMES); a term the fit set to zero has value
        0 and, as std, the size it could have had unseen (its 1-sigma bound)
    model : "flicker" or "gauss-markov": which floor the fit kept
    chi2 : weighted chi-square of the kept model, and ``n_taus`` the taus fitted
    tau_min_s, adev_min : the minimum of the measured curve (where the floor is read)
    """
    values: dict
    stds: dict
    model: str
    chi2: float
    n_taus: int
    tau_min_s: float
    adev_min: float
    alpha: np.ndarray = field(repr=False, default=None)

    def avar(self, tau) -> np.ndarray:
        """The fitted model's Allan variance at ``tau``."""
        tau = np.asarray(tau, dtype=float)
        v = self.values
        out = sum(c * v[n] ** 2 * tau ** p for c, n, p in
                  zip(_COEF, TERM_NAMES[:5], _POWERS) if not (n == "bias_instability" and
                                                             self.model == "gauss-markov"))
        if self.model == "gauss-markov":
            out = out + v["gm_sigma"] ** 2 * gm_avar_shape(tau, v["gm_tau_s"])
        return out

    def asymptotes(self, tau) -> dict:
        """Each term's own Allan deviation at ``tau`` (the straight lines of the figure)."""
        tau = np.asarray(tau, dtype=float)
        v = self.values
        out = {n: np.sqrt(c * v[n] ** 2 * tau ** p) for c, n, p in zip(_COEF, TERM_NAMES[:5], _POWERS)
               if v[n] > 0 and not (n == "bias_instability" and self.model == "gauss-markov")}
        if self.model == "gauss-markov":
            out["gauss_markov"] = v["gm_sigma"] * np.sqrt(gm_avar_shape(tau, v["gm_tau_s"]))
        return out

    def filter_bias(self) -> tuple[float, float]:
        """(sigma, T): the Gauss-Markov bias the filter is given (see the module
        docstring); (0, 0) if the curve shows no floor."""
        v = self.values
        if self.model == "gauss-markov":
            return v["gm_sigma"], v["gm_tau_s"]
        if v["bias_instability"] <= 0:
            return 0.0, 0.0
        return v["bias_instability"] * B_FACTOR / GM_PEAK_FACTOR, self.tau_min_s / GM_PEAK_TAU


def _design(tau, columns_gm=None):
    cols = [tau ** p for p in _POWERS]
    if columns_gm is not None:
        cols[2] = columns_gm               # the Gauss-Markov shape takes the floor's place
    return np.column_stack(cols)


def _nnls_fit(A, v, nu, per_octave, iterations=4):
    from scipy.optimize import nnls   # lazy: scipy.optimize is slow to import
    model = v.copy()
    c = np.zeros(A.shape[1])
    for _ in range(iterations):
        w = np.sqrt(nu / 2.0 / per_octave) / np.maximum(model, 1e-300)
        scale = np.maximum(np.max(np.abs(A * w[:, None]), axis=0), 1e-300)
        c_s, _ = nnls(A * w[:, None] / scale, v * w)
        c = c_s / scale
        model = np.maximum(A @ c, 1e-300 * np.max(v))
    r = (v - model) * w
    return c, float(r @ r), w


def _stds(A, w, c):
    """1-sigma of the coefficients from the weighted normal matrix; for a coefficient at
    0, the 1-sigma it would have alone (the size the data could not have hidden)."""
    Aw = A * w[:, None]
    active = c > 0
    out = np.zeros(c.size)
    if np.any(active):
        sub = Aw[:, active]
        cov = np.linalg.pinv(sub.T @ sub)
        out[active] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    for j in np.flatnonzero(~active):
        out[j] = 1.0 / max(np.linalg.norm(Aw[:, j]), 1e-300)
    return out


def fit_noise_terms(ad: AllanDeviation, column: int, gauss_markov: bool = True,
                    alpha=None) -> NoiseTerms:
    """Fit the terms to column ``column`` of ``ad`` (see the module docstring).

    Parameters
    ----------
    ad : AllanDeviation
    column : int
    gauss_markov : bool
        Try the Gauss-Markov bump in place of the flicker floor.
    alpha : array_like, optional
        Noise type per tau for the degrees of freedom (default: the fitted model's).

    Returns
    -------
    NoiseTerms
    """
    tau = ad.tau_s
    v = ad.avar[:, column]
    keep = v > 0
    if np.count_nonzero(keep) < 3:
        raise ValueError(f"column {ad.names[column] if ad.names else column}: fewer than 3 taus "
                         "with a non-zero Allan variance; a constant record has no noise to fit")
    tau, v, m, n_terms = tau[keep], v[keep], ad.m[keep], ad.n_terms[keep]
    per_octave = max(1.0, (len(tau) - 1) / max(np.log2(tau[-1] / tau[0]), 1.0))
    N_phase = n_terms + 2 * m

    def edf_for(c, gm_T=None):
        if alpha is not None:
            return edf_overlapping(N_phase, m, np.broadcast_to(alpha, tau.shape))
        parts = np.column_stack([c[j] * tau ** p for j, p in enumerate(_POWERS)])
        if gm_T is not None:
            parts[:, 2] = c[2] * gm_avar_shape(tau, gm_T)
            # the bump behaves as a random walk below T and as white noise above it
            a_of = np.array([2, 0, 0, -2, -2])
            a_bump = np.where(tau < gm_T, -2, 0)
        else:
            a_of = np.array([2, 0, -1, -2, -2])
            a_bump = None
        dom = np.argmax(parts, axis=1)
        a = a_of[dom]
        if a_bump is not None:
            a = np.where(dom == 2, a_bump, a)
        return edf_overlapping(N_phase, m, a), a

    # flicker floor model, with its degrees of freedom refined twice
    A = _design(tau)
    nu = edf_overlapping(N_phase, m, 0)
    for _ in range(3):
        c, chi2, w = _nnls_fit(A, v, nu, per_octave)
        nu, a = edf_for(c)
    best = ("flicker", c, chi2, w, A, None, a)
    if gauss_markov and len(tau) >= 6:
        grid = np.geomspace(tau[0] * 2, tau[-1] / 2, 60) if tau[-1] > 4 * tau[0] else []
        prof = []
        for T in grid:
            Ag = _design(tau, gm_avar_shape(tau, T))
            cg, chi2g, wg = _nnls_fit(Ag, v, nu, per_octave, 3)
            prof.append((chi2g, T, cg, wg, Ag))
        if prof:
            k = int(np.argmin([p[0] for p in prof]))
            from scipy.optimize import minimize_scalar   # lazy: scipy.optimize is slow to import
            lo_T, hi_T = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
            if hi_T > lo_T:   # refine T between the grid's neighbours of the best
                def chi2_of(logT):
                    return _nnls_fit(_design(tau, gm_avar_shape(tau, np.exp(logT))), v, nu, per_octave, 3)[1]
                r = minimize_scalar(chi2_of, bounds=(np.log(lo_T), np.log(hi_T)), method="bounded",
                                    options={"xatol": 1e-4})
                T = float(np.exp(r.x))
                Ag = _design(tau, gm_avar_shape(tau, T))
                cg, chi2g, wg = _nnls_fit(Ag, v, nu, per_octave, 3)
                prof[k] = (chi2g, T, cg, wg, Ag)
            chi2g, T, cg, wg, Ag = prof[k]
            if cg[2] > 0:
                nu_g, a_g = edf_for(cg, T)
                cg, chi2g, wg = _nnls_fit(Ag, v, nu_g, per_octave)
                if chi2g + 2.0 < best[2]:
                    # the profile over T: the Ts within chi-square + 1 of the best, and the
                    # spread of every coefficient over them (T's uncertainty carried into
                    # sigma, N and K)
                    chis = np.array([p[0] for p in prof])
                    near = chis <= chis.min() + 1.0
                    inside = grid[near]
                    T_std = 0.5 * (inside.max() - inside.min()) if inside.size > 1 else T * 0.1
                    cs = np.array([p[2] for p, ok in zip(prof, near) if ok] + [cg])
                    spread = 0.5 * (cs.max(axis=0) - cs.min(axis=0))
                    best = ("gauss-markov", cg, chi2g, wg, Ag, (T, T_std, spread), a_g)
    kind, c, chi2, w, A, gm, a = best
    sc = _stds(A, w, c)
    # the stated 1-sigma of a term found: what the single best tau says about it, the
    # relative precision sqrt(2 / edf) of the variance there divided by the term's share
    # of the model (overlapping estimates at neighbouring taus are too correlated to be
    # combined as independent: bench/study_noise_id.py measures the spread over seeds)
    nu_k = edf_overlapping(N_phase, m, a)
    parts = A * c
    total = np.maximum(parts.sum(axis=1), 1e-300)
    for j in np.flatnonzero(c > 0):
        share = parts[:, j] / total
        sc[j] = c[j] * np.min(np.sqrt(2.0 / nu_k) / np.maximum(share, 1e-300))
    if gm is not None:
        sc = np.hypot(sc, gm[2])
    values, stds = {}, {}
    for j, (name, coef) in enumerate(zip(TERM_NAMES[:5], _COEF)):
        if kind == "gauss-markov" and name == "bias_instability":
            values[name], stds[name] = 0.0, 0.0
            continue
        val = np.sqrt(max(c[j], 0.0) / coef)
        values[name] = float(val)
        # delta method: d sqrt(c/coef) = dc / (2 sqrt(c coef)); at 0, sqrt(std_c / coef)
        stds[name] = float(sc[j] / (2 * np.sqrt(c[j] * coef)) if c[j] > 0 else np.sqrt(sc[j] / coef))
    if kind == "gauss-markov":
        values["gm_sigma"], stds["gm_sigma"] = float(np.sqrt(c[2])), float(sc[2] / (2 * np.sqrt(c[2])))
        values["gm_tau_s"], stds["gm_tau_s"] = float(gm[0]), float(gm[1])
    else:
        values["gm_sigma"] = stds["gm_sigma"] = values["gm_tau_s"] = stds["gm_tau_s"] = 0.0
    i = int(np.argmin(v))
    return NoiseTerms(values, stds, kind, chi2, len(tau), float(tau[i]), float(np.sqrt(v[i])), a)
