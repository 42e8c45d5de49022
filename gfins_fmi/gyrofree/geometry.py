"""Gyro-free navigation with any accelerometer array (C core ``gf_gfins``).

Each accelerometer output is linear in x = [f, w_dot, W] with W = w w^T (six products);
``geometry_report`` tells which of these an array separates, how well (rank, condition
number) and with what noise gain; ``RateSolver`` turns a record of array outputs into
specific force, angular rate and angular acceleration with a chosen rate strategy, and
``GyroFreeNavigator`` feeds them to the strapdown mechanization. Model and strategies:
``csrc/gf_gfins.h``; the 9-accelerometer closed forms of seed 000 are the special case
``layout("qin9")`` (``gfins_fmi.solve_accel9`` keeps the paper's own equations).
"""
from __future__ import annotations

import dataclasses
import functools
import warnings
from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_array, as_positive_scalar,
                            as_rows, as_scalar, as_start_index, as_vector3, check_status,
                            done_before, ffi, first_nonfinite, lib, ptr, status_text)
from gfins_fmi.accel_array import ArrayGeometry, accel9_geometry
from gfins_fmi.sins import NavSolution, NavState, SinsConfig

__all__ = ["UNKNOWNS", "PRODUCTS", "STRATEGIES", "LoopStability", "rate_loop_stability",
           "SolverMaps", "solver_maps", "on_products", "on_jacobian", "rate_model",
           "UnstableRateLoopWarning", "INTEGRATIONS", "hermite_increments", "layout", "GeometryReport", "geometry_report",
           "RateSolution", "RateSolver", "GyroFreeNavigator"]

#: names of the 12 unknowns of one sample, in the order of the C core
UNKNOWNS = ("f_x", "f_y", "f_z", "omega_dot_x", "omega_dot_y", "omega_dot_z",
            "W_xx", "W_yy", "W_zz", "W_xy", "W_xz", "W_yz")
_GROUPS = {"f": lib.GF_GROUP_F, "omega_dot": lib.GF_GROUP_OMEGA_DOT,
           "W_diag": lib.GF_GROUP_W_DIAG, "W_offdiag": lib.GF_GROUP_W_OFFDIAG}
#: rate strategies: integrate w_dot; sqrt of W_kk with sign from integrated w_dot (Qin);
#: dominant eigenpair of W; fused EKF on [w, w_dot bias]
STRATEGIES = {"integrate": lib.GF_RATE_INTEGRATE, "sqrt": lib.GF_RATE_SQRT,
              "eigen": lib.GF_RATE_EIGEN, "fused": lib.GF_RATE_FUSED}


def _geometry_from_c(c) -> ArrayGeometry:
    n = int(c.n_sensors)
    u = np.array([[c.u_m[i][k] for k in range(3)] for i in range(n)])
    t = np.array([[c.theta[i][k] for k in range(3)] for i in range(n)])
    return ArrayGeometry(u, t)


def layout(name: str, l_m: float) -> ArrayGeometry:
    """A named array layout with lever arm ``l_m`` (m).

    ``"cube6"`` (or ``"6"``): Tan & Park's cube, sensors at the face centres along face
    diagonals; ``"qin9"`` (``"9"``): seed 000; ``"12"``: Qin's nine plus three tangential
    sensors (l e_x along e_y, l e_y along e_z, l e_z along e_x), measuring all of w w^T.
    """
    l_m = as_positive_scalar("l_m (lever arm)", l_m, "m")
    key = {"6": "cube6", "9": "qin9", "qin": "qin9"}.get(str(name), str(name))
    if key == "qin9":
        return accel9_geometry(l_m)
    fn = {"cube6": lib.gf_layout_cube6, "12": lib.gf_layout_12}.get(key)
    if fn is None:
        raise ValueError(f"unknown layout {name!r}; choose 'cube6', 'qin9' or '12'")
    c = ffi.new("gf_array_geometry *")
    check_status(fn(l_m, c), f"layout {key}")
    return _geometry_from_c(c)


#: the six products of w w^T in the order of the C core (x[6:12])
PRODUCTS = ("W_xx", "W_yy", "W_zz", "W_xy", "W_xz", "W_yz")
_SQ2 = np.sqrt(2.0)


def on_products(w) -> np.ndarray:
    """w w^T in the orthonormal product coordinates of the solver, [W_xx, W_yy, W_zz,
    sqrt2 W_xy, sqrt2 W_xz, sqrt2 W_yz] (a rotation of the array acts on them by an
    orthogonal matrix); ``w`` (..., 3) -> (..., 6)."""
    w = np.asarray(w, float)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return np.stack([x * x, y * y, z * z, _SQ2 * x * y, _SQ2 * x * z, _SQ2 * y * z], axis=-1)


def on_jacobian(w) -> np.ndarray:
    """d on_products / d w: (..., 6, 3), linear in w."""
    w = np.asarray(w, float)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    o = np.zeros_like(x)
    r = _SQ2
    return np.stack([np.stack([2 * x, o, o], -1), np.stack([o, 2 * y, o], -1),
                     np.stack([o, o, 2 * z], -1), np.stack([r * y, r * x, o], -1),
                     np.stack([r * z, o, r * x], -1), np.stack([o, r * z, r * y], -1)], axis=-2)


def _sym(v) -> np.ndarray:
    """Symmetric 3x3 matrix of a vector in orthonormal product coordinates."""
    v = np.asarray(v, float)
    r = 1 / _SQ2
    return np.array([[v[0], r * v[3], r * v[4]], [r * v[3], v[1], r * v[5]],
                     [r * v[4], r * v[5], v[2]]])


@dataclass(frozen=True)
class SolverMaps:
    """The linear maps of an array's solver, read from the C core (gf_array_solver):
    y = pinv A (rows f, w_dot, the n_obs observed product combinations z), corrected by
    the confounded products of a rate, x = y - K_pred on_products(w).

    Attributes
    ----------
    H : (N, 12) model matrix (products W_jk as in x)
    pinv : (6 + n_obs, N)
    basis : (6, 6) orthonormal basis of the product space (columns): observed, then
        confounded, then absent
    n_obs, n_conf : int
    K_pred : (6 + n_obs, 6)
    W_obs : (6, n_obs) products W per observed coordinate
    """
    H: np.ndarray
    pinv: np.ndarray
    basis: np.ndarray
    n_obs: int
    n_conf: int
    K_pred: np.ndarray
    W_obs: np.ndarray
    cond: float
    masks: tuple
    noise_gain: np.ndarray

    @property
    def observed(self) -> np.ndarray:
        """(6, n_obs) observed basis vectors."""
        return self.basis[:, :self.n_obs]

    @property
    def confounded(self) -> np.ndarray:
        return self.basis[:, self.n_obs:self.n_obs + self.n_conf]

    @property
    def absent(self) -> np.ndarray:
        return self.basis[:, self.n_obs + self.n_conf:]

    def loop_matrix(self, w) -> np.ndarray:
        """A(w) = d(w_dot error)/d(rate error) through the confounded products,
        -K_wd J(w): (..., 3, 3). Zero when nothing is confounded."""
        return -np.einsum("ij,...jk->...ik", self.K_pred[3:6], on_jacobian(w))

    def measurement_matrix(self) -> np.ndarray:
        """What the observed rows of y measure, y_z = (B_o^T + K_z) on_products(w)
        (n_obs, 6)."""
        return self.observed.T + self.K_pred[6:]


def _solver_c(geometry: ArrayGeometry):
    if not isinstance(geometry, ArrayGeometry):
        raise TypeError("geometry must be an ArrayGeometry (e.g. layout('qin9', 0.1))")
    s = ffi.new("gf_array_solver *")
    bad = ffi.new("uint32_t *")
    status = lib.gf_array_solver_init(s, geometry._c, bad)
    if status == lib.GF_ERR_SINGULAR_GEOMETRY:
        names = [UNKNOWNS[j] for j in range(12) if int(bad[0]) >> j & 1]
        raise ValueError("the array cannot be solved: the outputs do not separate "
                         + (", ".join(names) if names else "its unknowns")
                         + " (rank-deficient geometry: coincident or parallel sensors, zero "
                           "lever arms, or too few sensors)")
    check_status(status, "gf_array_solver_init")
    return s


def solver_maps(geometry: ArrayGeometry) -> SolverMaps:
    """The solver's linear maps (:class:`SolverMaps`) for an array."""
    s = _solver_c(geometry)
    ns, ne, no = int(s.n_sensors), int(s.n_est), int(s.n_obs)
    stride = int(lib.GF_ARRAY_MAX_SENSORS)
    buf = lambda field, n: np.frombuffer(ffi.buffer(getattr(s, field)), dtype=np.float64)[:n].copy()
    pinv = buf("pinv", ne * stride).reshape(ne, stride)[:, :ns].copy()
    return SolverMaps(buf("H", ns * 12).reshape(ns, 12), pinv, buf("basis", 36).reshape(6, 6),
                      no, int(s.n_conf), buf("K_pred", ne * 6).reshape(ne, 6),
                      buf("W_obs", 36).reshape(6, 6)[:, :no].copy(), float(s.cond),
                      (int(s.present), int(s.estimated), int(s.from_rate)),
                      buf("noise_gain", 12))


# ---- the observed products in words ------------------------------------------------------

_MONO = ("w_x^2", "w_y^2", "w_z^2", "w_x w_y", "w_x w_z", "w_y w_z")


def _combination_rows(vectors) -> np.ndarray:
    """Functionals (columns, orthonormal coordinates) as coefficients of the monomials
    w_x^2 .. w_y w_z, in reduced row-echelon form (pivots 1): a readable basis."""
    V = np.asarray(vectors, float)
    if V.size == 0:
        return np.zeros((0, 6))
    C = V.T * np.array([1, 1, 1, _SQ2, _SQ2, _SQ2])
    C = C.copy()
    r = 0
    for c in range(6):
        if r >= C.shape[0]:
            break
        piv = r + int(np.argmax(np.abs(C[r:, c])))
        if abs(C[piv, c]) < 1e-9 * max(1.0, np.abs(C).max()):
            continue
        C[[r, piv]] = C[[piv, r]]
        C[r] /= C[r, c]
        for i in range(C.shape[0]):
            if i != r:
                C[i] -= C[i, c] * C[r]
        r += 1
    C[np.abs(C) < 1e-9] = 0.0
    return C[:r]


def _poly(row) -> str:
    terms = []
    for c, m in zip(row, _MONO):
        if c == 0:
            continue
        mag = abs(c)
        coef = "" if abs(mag - 1) < 1e-9 else f"{mag:.3g} "
        terms.append(("- " if c < 0 else "+ ") + coef + m)
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else "-" + text[1:]


def _vec_text(v) -> str:
    return "[" + ", ".join(f"{0.0 if abs(x) < 1e-12 else x:.3g}" for x in v) + "]"


def _axes_text(frame) -> str:
    return ", ".join(f"a{k + 1} = {_vec_text(frame[:, k])}" for k in range(frame.shape[1]))


def _common_axes(maps: SolverMaps):
    """Unit vectors n that are eigenvectors of every observed product combination: the
    outputs cannot tell the sign of w.n (reflection through the plane normal to n). For
    three such axes (Qin's layout in any mounting) the frame of the array."""
    Bs = [_sym(maps.observed[:, c]) for c in range(maps.n_obs)]
    if not Bs:
        return np.zeros((3, 0))
    mix = sum(np.sqrt(k + 2.0) * B for k, B in enumerate(Bs))
    _, V = np.linalg.eigh(mix)
    axes = [V[:, k] for k in range(3)
            if all(np.linalg.norm(B @ V[:, k] - (V[:, k] @ B @ V[:, k]) * V[:, k])
                   <= 1e-9 * max(np.linalg.norm(B), 1e-300) for B in Bs)]
    return np.array(axes).T if axes else np.zeros((3, 0))


def rate_model(maps: SolverMaps, strategy: str = "sqrt") -> str:
    """How a per-sample strategy reads the rate from the observed products, as the C
    core chooses it (gf_gfins.h, GF_RATE_MODEL_*): for ``"sqrt"``, ``"frame"`` (the
    squared rates along three orthogonal axes of the array: closed form) or ``"fit"``
    (3 to 6 other combinations: weighted Gauss-Newton fit); for ``"eigen"``, ``"full"``
    (all of w w^T: eigenpair); ``"none"`` when the strategy cannot run."""
    if strategy == "eigen":
        return "full" if maps.n_obs == 6 else "none"
    if maps.n_obs == 3 and _common_axes(maps).shape[1] == 3:
        return "frame"
    return "fit" if maps.n_obs >= 3 else "none"


def fit_pinv(maps: SolverMaps, G, model: str) -> np.ndarray:
    """The linearised per-sample rate solution, dw = fit_pinv dz (..., 3, n_obs) for the
    Jacobian G = B_o^T J(w) (..., n_obs, 3): the pseudo-inverse weighted by the observed
    combinations' noise covariance (P_z P_z^T) for ``fit``, plain otherwise (``frame``
    is exactly determined; ``full``, the eigenpair, is the unweighted rank-one fit)."""
    if model != "fit":
        return np.linalg.pinv(G)
    Pz = maps.pinv[6:]
    Rinv = np.linalg.inv(Pz @ Pz.T)
    GtR = np.swapaxes(G, -1, -2) @ Rinv
    return np.linalg.solve(GtR @ G, GtR)


# ---- stability of the rate loop ----------------------------------------------------------

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


# ---- the report ---------------------------------------------------------------------------

@dataclass(frozen=True)
class GeometryReport:
    """What an array measures, and how well.

    Attributes
    ----------
    n_sensors, rank : int
    condition_number : float
        Of the columns solved by least squares (f, w_dot and the observed combinations;
        the same in any mounting of the array).
    present, estimated, from_rate : tuple of str
        Body-axis groups among ``f``, ``omega_dot``, ``W_diag``, ``W_offdiag``: those that
        affect the outputs; those every component of which is solved linearly from them;
        those with components taken from a predicted rate.
    noise_gain : dict name -> float
        Std of each body-axis unknown wholly solved from the outputs (f, w_dot and the
        products W_jk that are observed) per unit (1 m/s^2) white noise on every output.
    observed, confounded, absent : tuple of str
        The product combinations (quadratic forms in w, body axes) that the outputs
        separate; that enter them only as f and w_dot do (taken from the predicted rate);
        that do not enter them.
    principal_noise_gains : dict
        Rotation-invariant noise gains: ``f``, ``omega_dot`` (3 each) and ``products``
        (n_obs, orthonormal coordinates): square roots of the eigenvalues of each block
        of the estimates' covariance per unit output noise, descending.
    mirror_axes : (3, k) array
        Axes n along which the outputs cannot tell the sign of w.n (the rate and its
        mirror image through the plane normal to n give the same outputs); the global
        sign of w is never observable.
    rate_model : str
        How ``sqrt`` reads the rate: ``frame``, ``fit`` or ``none`` (see :func:`rate_model`).
    stability : dict strategy -> LoopStability
        The rate loop of each strategy (:func:`rate_loop_stability`, |w| <= 5 rad/s, 100 Hz).
    """

    n_sensors: int
    rank: int
    condition_number: float
    present: tuple
    estimated: tuple
    from_rate: tuple
    noise_gain: dict
    observed: tuple = ()
    confounded: tuple = ()
    absent: tuple = ()
    principal_noise_gains: dict = dataclasses.field(default_factory=dict)
    mirror_axes: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 0)))
    rate_model: str = "none"
    stability: dict = dataclasses.field(default_factory=dict)

    @property
    def observable(self) -> dict:
        """Which quantities the array gives linearly: f, omega_dot, the diagonal of
        w w^T (omega_sq) and the full w w^T (omega_outer), in body axes."""
        est = set(self.estimated)
        return {"f": "f" in est, "omega_dot": "omega_dot" in est,
                "omega_sq": "W_diag" in est,
                "omega_outer": {"W_diag", "W_offdiag"} <= est}

    @property
    def working_strategies(self) -> tuple:
        """Strategies whose loop is stable or marginal here, best first (fused, sqrt,
        eigen, then integrate)."""
        order = ("fused", "sqrt", "eigen", "integrate")
        return tuple(s for s in order if self.stability.get(s) is not None
                     and self.stability[s].verdict in ("stable", "marginal")
                     and not (s == "integrate" and any(
                         self.stability[t].verdict == "stable" for t in order[:3]
                         if t in self.stability)))

    def describe(self) -> str:
        """The report in words."""
        n_obs = len(self.observed)
        lines = [f"{self.n_sensors} accelerometers; least-squares condition number "
                 f"{self.condition_number:.3g}."]
        frame = self.rate_model == "frame"
        observed = ("(w.a1)^2; (w.a2)^2; (w.a3)^2, the squared rates along the array's axes "
                    + _axes_text(self.mirror_axes) if frame else "; ".join(self.observed))
        lines.append("Measured linearly every sample: the specific force f and the angular "
                     "acceleration w_dot (3 axes each)"
                     + (f", and {n_obs} of the 6 products of w w^T: " + observed
                        if n_obs else ", and none of the products of w w^T") + ".")
        if self.confounded:
            lines.append("Confounded with f and w_dot (they enter the outputs as these do, so "
                         "they are taken from the predicted rate): " + "; ".join(self.confounded)
                         + ".")
        if self.absent:
            lines.append("Not in the outputs at all: " + ("the cross products (w.a_j)(w.a_k), j != k"
                                                         if frame and len(self.absent) == 3
                                                         else "; ".join(self.absent)) + ".")
        if self.rate_model == "none":
            lines.append("The products do not determine the rate sample by sample; it comes "
                         "from the w_dot integral (and, with 'fused', from what they do observe).")
        else:
            mirrors = ("the sign of w along each of these axes" if self.rate_model == "frame" else
                       "the sign of w.n for n = " + ", ".join(_vec_text(n) for n in self.mirror_axes.T)
                       if self.mirror_axes.shape[1] else "the global sign of w")
            lines.append("The observed products give the rate sample by sample up to mirror "
                         f"images ({mirrors}); the branch comes from the w_dot integral, and "
                         "samples where a mirror image is closer than the noise resolution are "
                         "flagged (GF_RATE_FLAG_AMBIGUOUS).")
        pg = self.principal_noise_gains
        lines.append("Noise gains per 1 m/s^2 on every output (principal values, the same in "
                      "any mounting): f " + ", ".join(f"{v:.3g}" for v in pg.get("f", ()))
                      + "; w_dot " + ", ".join(f"{v:.3g}" for v in pg.get("omega_dot", ()))
                      + ("; products " + ", ".join(f"{v:.3g}" for v in pg["products"])
                         if len(pg.get("products", ())) else "") + ".")
        for name, st in self.stability.items():
            g = ("" if not np.isfinite(st.growth_rate_s) or st.verdict != "unstable"
                 else f", growth {st.growth_rate_s:.3g}/s")
            lines.append(f"Strategy {name!r}: {st.verdict}{g}: {st.reason}.")
        ok = self.working_strategies
        lines.append("Strategies that navigate this array: " + (", ".join(repr(s) for s in ok)
                                                                   if ok else "none") + ".")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.describe()


def geometry_report(geometry: ArrayGeometry, max_rate_rad_s: float = 5.0,
                    dt_s: float = 0.01) -> GeometryReport:
    """What an array observes, how well, and which rate strategies are stable on it
    (see :class:`GeometryReport`; ``print(report)`` gives it in words).

    Raises
    ------
    ValueError
        The array is unsolvable; the message names the unknowns it cannot separate.
    """
    maps = solver_maps(geometry)
    present, estimated, from_rate = maps.masks

    def groups(mask):
        return tuple(name for name, bit in _GROUPS.items() if int(mask) & int(bit))
    gains = {UNKNOWNS[j]: float(maps.noise_gain[j]) for j in range(12)
             if j < 6 or maps.noise_gain[j] > 0}
    P = maps.pinv
    principal = {name: np.sqrt(np.maximum(np.linalg.eigvalsh(P[rows] @ P[rows].T), 0))[::-1]
                 for name, rows in (("f", slice(0, 3)), ("omega_dot", slice(3, 6)),
                                    ("products", slice(6, 6 + maps.n_obs)))}
    words = lambda V: tuple(_poly(r) for r in _combination_rows(V))
    model = rate_model(maps)
    axes = _common_axes(maps)
    if model == "frame":      # the array's axes in the C core's canonical order
        order = np.argmax(np.abs(axes), axis=0)
        if sorted(order) == [0, 1, 2]:
            axes = axes[:, np.argsort(order)]
        axes = axes * np.sign(axes[np.argmax(np.abs(axes), axis=0), range(3)])
    stab = {name: rate_loop_stability(geometry, name, max_rate_rad_s, dt_s) for name in STRATEGIES}
    return GeometryReport(geometry.n_sensors, int(6 + maps.n_obs),
                          maps.cond, groups(present), groups(estimated), groups(from_rate), gains,
                          words(maps.observed), words(maps.confounded), words(maps.absent),
                          principal, axes, model, stab)


@dataclass
class RateSolution:
    """Per-sample solution of an array record: f_m_s2, omega_rad_s, omega_dot_rad_s2
    (n, 3), W (n, 6: W_xx, W_yy, W_zz, W_xy, W_xz, W_yz: observed combinations from the
    outputs, the rest from the rate), flags (n,) with bits 1, 2, 4 (negative squared rate
    on that axis of the array's frame / eigenvalue / fit failed), 8 (sign reference
    exactly zero), 16 (fused update skipped), 32 (ambiguous: a mirror-image rate closer
    than the resolution; the branch is the w_dot integral's)."""

    f_m_s2: np.ndarray
    omega_rad_s: np.ndarray
    omega_dot_rad_s2: np.ndarray
    W: np.ndarray
    flags: np.ndarray

    def __len__(self) -> int:
        return int(self.flags.shape[0])

    def _head(self, n: int) -> "RateSolution":
        return RateSolution(*(a[:n].copy() for a in (self.f_m_s2, self.omega_rad_s,
                                                      self.omega_dot_rad_s2, self.W, self.flags)))


def _rate_config(strategy, accel_noise_m_s2, bias_walk, init_std, init_bias_std):
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {sorted(STRATEGIES)}; got {strategy!r}")
    c = ffi.new("gf_rate_config *")
    lib.gf_rate_config_default(c)
    c.strategy = STRATEGIES[strategy]
    c.accel_noise_m_s2 = as_scalar("accel_noise_m_s2", accel_noise_m_s2, "m/s^2", above=0.0)
    c.bias_walk_rad_s2_sqrt_s = as_scalar("bias_walk_rad_s2_sqrt_s", bias_walk, "rad/s^2/sqrt(s)",
                                          at_least=0.0)
    c.init_std_rad_s = as_scalar("init_std_rad_s", init_std, "rad/s", above=0.0)
    c.init_bias_std_rad_s2 = as_scalar("init_bias_std_rad_s2", init_bias_std, "rad/s^2",
                                       at_least=0.0)
    return c


#: attitude/velocity integration of the navigator over a sampling interval
INTEGRATIONS = {"linear": lib.GF_GFNAV_LINEAR, "hermite": lib.GF_GFNAV_HERMITE}


def hermite_increments(w0_rad_s, w_dot0_rad_s2, f0_m_s2, w1_rad_s, w_dot1_rad_s2, f1_m_s2,
                       T_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Rotation vector (rad) and body velocity increment (m/s) of one interval of length
    ``T_s`` under the cubic Hermite rate model through (w, w_dot) at both ends: what the
    navigator integrates (``integration="hermite"``; equations in csrc/gf_gfins.h).

    Returns
    -------
    phi_rad : (3,) rotation from the body frame at the start to the body frame at the end
    dv_b_m_s : (3,) specific force integrated over the interval, body frame at the start
    """
    vecs = [as_vector3(name, v, unit) for name, v, unit in (
        ("w0_rad_s", w0_rad_s, "rad/s"), ("w_dot0_rad_s2", w_dot0_rad_s2, "rad/s^2"),
        ("f0_m_s2", f0_m_s2, "m/s^2"), ("w1_rad_s", w1_rad_s, "rad/s"),
        ("w_dot1_rad_s2", w_dot1_rad_s2, "rad/s^2"), ("f1_m_s2", f1_m_s2, "m/s^2"))]
    T_s = as_positive_scalar("T_s (interval)", T_s, "s")
    phi, dv = np.empty(3), np.empty(3)
    check_status(lib.gf_hermite_increments(*(ptr(v, 3) for v in vecs), T_s, ptr(phi, 3),
                                           ptr(dv, 3)), "gf_hermite_increments")
    return phi, dv


#: what each rate strategy needs, in words
_NEEDS = {"sqrt": "at least 3 observed product combinations of w w^T",
          "fused": "at least one observed product combination of w w^T",
          "eigen": "all of w w^T observed (6 combinations)"}


class UnstableRateLoopWarning(UserWarning):
    """A rate strategy runs on an array where its error loop is unstable (allowed with
    ``allow_unstable=True``)."""


def _strategy_error(strategy: str, geometry: ArrayGeometry) -> str:
    rep = geometry_report(geometry)
    ok = rep.working_strategies
    return (f"strategy {strategy!r} needs an array with {_NEEDS[strategy]}; this one observes "
            f"{len(rep.observed)} (" + ("; ".join(rep.observed) or "none") + "). Strategies that "
            "navigate it: " + (", ".join(repr(a) for a in ok) if ok else "none") + "; layouts "
            "that serve " + repr(strategy) + ": " + " or ".join(
                repr(a) for a in ("cube6", "qin9", "12")
                if geometry_report(layout(a, 0.1)).stability[strategy].verdict
                in ("stable", "marginal")))


def _check_loop(geometry: ArrayGeometry, strategy: str, allow_unstable: bool, dt_s=0.01) -> None:
    """Refuses (or warns about) a strategy whose loop is unstable on the array."""
    st = rate_loop_stability(geometry, strategy, dt_s=dt_s)
    if st.verdict != "unstable":
        return
    ok = geometry_report(geometry).working_strategies
    msg = (f"strategy {strategy!r} is unstable on this array: {st.reason}; rate errors grow "
           f"at {st.growth_rate_s:.3g}/s near w = {np.round(st.worst_rate_rad_s, 3).tolist()} rad/s "
           "(gfins_fmi.geometry_report(geometry) explains). "
           + (f"Use {' or '.join(repr(a) for a in ok)}" if ok else
              "No strategy navigates this array: add sensors so that it observes more products of "
              "w w^T") + ", or pass allow_unstable=True to run it anyway.")
    if not allow_unstable:
        raise ValueError(msg)
    warnings.warn(msg, UnstableRateLoopWarning, stacklevel=3)


class RateSolver:
    """Streaming array solver: outputs -> f, w, w_dot per sample (one C call per record).

    Parameters
    ----------
    geometry : ArrayGeometry
    strategy : {"integrate", "sqrt", "eigen", "fused"}
    omega_init_rad_s : (3,)
        Rate at the first sample (signs, start of the w_dot integral, fused prior).
    accel_noise_m_s2 : float
        White-noise std of each accelerometer (the fused filter's noise model).
    bias_walk_rad_s2_sqrt_s, init_std_rad_s, init_bias_std_rad_s2 : float
        Fused filter tuning: random walk of the w_dot bias state, initial stds.
    allow_unstable : bool
        A strategy whose error loop is unstable on this array
        (:func:`rate_loop_stability`) is refused with the strategies that work; True runs
        it with an :class:`UnstableRateLoopWarning`.
    """

    def __init__(self, geometry: ArrayGeometry, strategy: str = "integrate",
                 omega_init_rad_s=(0.0, 0.0, 0.0), accel_noise_m_s2: float = 1e-4,
                 bias_walk_rad_s2_sqrt_s: float = 1e-6, init_std_rad_s: float = 1e-2,
                 init_bias_std_rad_s2: float = 1e-3, *, allow_unstable: bool = False):
        _solver_c(geometry)  # geometry errors with their names first
        self.geometry = geometry
        self.strategy = strategy
        cfg = _rate_config(strategy, accel_noise_m_s2, bias_walk_rad_s2_sqrt_s, init_std_rad_s,
                           init_bias_std_rad_s2)
        w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
        self._state = ffi.new("gf_gfins_state *")
        status = lib.gf_gfins_init(self._state, geometry._c, cfg, ptr(w0, 3), ffi.NULL)
        if status == lib.GF_ERR_BAD_PARAMETER:
            raise ValueError(_strategy_error(strategy, geometry))
        check_status(status, "gf_gfins_init")
        _check_loop(geometry, strategy, allow_unstable)

    def solve(self, A_m_s2, dt_s: float) -> RateSolution:
        """Solve a record (n, n_sensors) sampled every ``dt_s`` seconds."""
        ns = self.geometry.n_sensors
        A = as_rows("A_m_s2", A_m_s2, ns, "m/s^2")
        dt_s = as_positive_scalar("dt_s (sampling interval)", dt_s, "s")
        n = A.shape[0]
        out = RateSolution(np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                           np.empty((n, 6)), np.empty(n, dtype=np.uint8))
        done = ffi.new("size_t *")
        status = lib.gf_gfins_run(self._state, n, ptr(A, n * ns), dt_s, ptr(out.f_m_s2, 3 * n),
                                  ptr(out.omega_rad_s, 3 * n), ptr(out.omega_dot_rad_s2, 3 * n),
                                  ptr(out.W, 6 * n), ptr(out.flags, n, "uint8_t"), done)
        k = int(done[0])
        if status == lib.GF_ERR_NONFINITE_INPUT:
            col = first_nonfinite(A, k)
            raise NonFiniteInputError(f"A_m_s2[{k}, {col}] = {A[k, col]} (accelerometer {col + 1}) "
                                      f"is not finite; {done_before(k)}", k, col, out._head(k))
        if status != lib.GF_OK:
            raise SampleError(f"sample {k}: {status_text(status)}; {done_before(k)}",
                              int(status), k, out._head(k))
        return out


class GyroFreeNavigator:
    """Array outputs -> (w, f) -> strapdown mechanization (rate input): attitude,
    velocity, position, in one C call per record.

    Parameters
    ----------
    geometry : ArrayGeometry
    initial : NavState
        State at the first array sample.
    strategy, accel_noise_m_s2 : as :class:`RateSolver`
    omega_init_rad_s : (3,), optional
        Rate at the first sample (default: the Earth rate seen by the initial attitude
        would be a good prior; zero is used unless given).
    sins : SinsConfig, optional
        Mechanization options; ``input`` is forced to ``"rates"``.
    bias_walk_rad_s2_sqrt_s, init_std_rad_s, init_bias_std_rad_s2 : float
        Fused filter tuning, as :class:`RateSolver`.
    integration : {"hermite", "linear"}
        Attitude and velocity over a sampling interval: ``"hermite"`` (default) models
        the rate as the cubic through w and w_dot at both ends (sixth-order Magnus
        rotation vector) and integrates the specific force in the interval's start
        frame; ``"linear"`` feeds the rates to the mechanization, which takes them as
        linear between samples (second order, two-sample coning and sculling). See
        ``gf_hermite_increments`` in csrc/gf_gfins.h.
    allow_unstable : bool
        As :class:`RateSolver`.
    """

    def __init__(self, geometry: ArrayGeometry, initial: NavState, strategy: str = "integrate",
                 omega_init_rad_s=(0.0, 0.0, 0.0), accel_noise_m_s2: float = 1e-4,
                 sins: SinsConfig | None = None, *, bias_walk_rad_s2_sqrt_s: float = 1e-6,
                 init_std_rad_s: float = 1e-2, init_bias_std_rad_s2: float = 1e-3,
                 integration: str = "hermite", allow_unstable: bool = False):
        _solver_c(geometry)
        self.geometry = geometry
        cfg = _rate_config(strategy, accel_noise_m_s2, bias_walk_rad_s2_sqrt_s, init_std_rad_s,
                           init_bias_std_rad_s2)
        if sins is not None and sins.subsamples != 1:
            raise ValueError(f"sins.subsamples = {sins.subsamples!r}: the gyro-free navigator "
                             "makes one update per array sample (its rates are solved sample by "
                             "sample); use subsamples=1")
        sc = dataclasses.replace(sins or SinsConfig(), input="rates")
        self._flat = sc.earth == "flat"
        x0 = initial.checked(self._flat)
        w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
        self._state = ffi.new("gf_gfnav_state *")
        status = lib.gf_gfnav_init(self._state, geometry._c, cfg, ptr(w0, 3), sc._c(x0.h_m),
                                   ptr(x0.q_bn, 4), ptr(x0.v_n_m_s, 3), x0.lat_rad, x0.lon_rad,
                                   x0.h_m, x0.t_s, ffi.NULL)
        if status == lib.GF_ERR_BAD_PARAMETER:   # everything else was checked above
            raise ValueError(_strategy_error(strategy, geometry))
        check_status(status, "gf_gfnav_init")
        _check_loop(geometry, strategy, allow_unstable)
        if self._flat:
            check_status(lib.gf_sins_set_flat_position(ffi.addressof(self._state, "nav"),
                                                       ptr(x0.pos_m, 3)), "flat position")
        if integration not in INTEGRATIONS:
            raise ValueError(f"integration must be one of {sorted(INTEGRATIONS)}; got {integration!r}")
        self.integration = integration
        check_status(lib.gf_gfnav_set_integration(self._state, INTEGRATIONS[integration]),
                     "gf_gfnav_set_integration")

    def run(self, A_m_s2, dt_s: float, h_ext_m=None, *,
            start_index: int = 0) -> tuple[NavSolution, RateSolution]:
        """Navigate a record (n, n_sensors); row k = state at sample k (row 0: t0). Each
        call continues the last.

        Parameters
        ----------
        A_m_s2 : array_like (n, n_sensors)
            Array outputs (m/s^2).
        dt_s : float
            Sampling interval (s).
        h_ext_m : array_like (n,), optional
            External height (m) for ``vertical="baro"`` (NaN where there is none).
        start_index : int
            When a record is navigated in pieces: the index of this piece's first
            sample in the record, so that error messages and ``index`` count from the
            record's start.

        Raises
        ------
        NonFiniteInputError, SampleError
            With ``index`` of the bad sample, ``partial`` (the navigation solution of
            this call's samples before it) and ``partial_rates`` (their
            :class:`RateSolution`: omega, f and flags; omega_dot and W are NaN).
        """
        ns = self.geometry.n_sensors
        A = as_rows("A_m_s2", A_m_s2, ns, "m/s^2")
        dt_s = as_positive_scalar("dt_s (sampling interval)", dt_s, "s")
        s0 = as_start_index(start_index)
        n = A.shape[0]
        he = None if h_ext_m is None else as_array("h_ext_m", h_ext_m, (n,), "m", finite=False)
        q, v, pos = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
        rates = RateSolution(np.empty((n, 3)), np.empty((n, 3)), np.full((n, 3), np.nan),
                             np.full((n, 6), np.nan), np.empty(n, dtype=np.uint8))
        t0 = float(self._state.nav.time_s)
        first = 0 if int(self._state.nav.n_samples) == 0 else 1  # a fresh run starts at t0
        done = ffi.new("size_t *")
        status = lib.gf_gfnav_run(self._state, n, ptr(A, n * ns), dt_s,
                                  ptr(he, n) if he is not None else ffi.NULL, ptr(q, 4 * n),
                                  ptr(v, 3 * n), ptr(pos, 3 * n), ptr(rates.omega_rad_s, 3 * n),
                                  ptr(rates.f_m_s2, 3 * n), ptr(rates.flags, n, "uint8_t"), done)
        k = int(done[0])
        t = t0 + (np.arange(n) + first) * dt_s
        sol = NavSolution._from_pos(t, q, v, pos, self._flat)
        if status != lib.GF_OK:
            partial = sol._rows(slice(0, k))
            if status == lib.GF_ERR_NONFINITE_INPUT:
                col = first_nonfinite(A, k)
                exc = NonFiniteInputError(f"A_m_s2[{s0 + k}, {col}] = {A[k, col]} is not finite; "
                                          + done_before(k, s0, "navigated"), s0 + k, col, partial)
            else:
                exc = SampleError(f"sample {s0 + k}: {status_text(status)}; "
                                  + done_before(k, s0, "navigated"), int(status), s0 + k, partial)
            exc.partial_rates = rates._head(k)
            raise exc
        return sol, rates
