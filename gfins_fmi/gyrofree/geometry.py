"""What an accelerometer array measures: the named layouts, the solver's linear maps read
from the C core (``gf_array_solver``), and the observed products of w w^T in words.

Each accelerometer output is linear in x = [f, w_dot, W] with W = w w^T (six products);
the solver separates f, w_dot and the observed product combinations, the rest of W comes
from the rate (confounded) or not at all (absent). Model: ``csrc/gyrofree/gf_gfins.h``; the
9-accelerometer closed forms of seed 000 are the special case ``layout("qin9")``
(:func:`gfins_fmi.gyrofree.array.solve_accel9` keeps the paper's own equations).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import as_positive_scalar, check_status, ffi, lib
from gfins_fmi.gyrofree.array import ArrayGeometry, accel9_geometry

__all__ = ["UNKNOWNS", "GROUPS", "PRODUCTS", "STRATEGIES", "layout", "SolverMaps", "solver_maps",
           "array_solver", "on_products", "on_jacobian", "rate_model", "fit_pinv",
           "combination_rows", "polynomial_text", "vector_text", "axes_text", "common_axes"]

#: names of the 12 unknowns of one sample, in the order of the C core
UNKNOWNS = ("f_x", "f_y", "f_z", "omega_dot_x", "omega_dot_y", "omega_dot_z",
            "W_xx", "W_yy", "W_zz", "W_xy", "W_xz", "W_yz")
#: groups of unknowns, as the C core's masks name them
GROUPS = {"f": lib.GF_GROUP_F, "omega_dot": lib.GF_GROUP_OMEGA_DOT,
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


def array_solver(geometry: ArrayGeometry):
    """The C core's solver of an array (``gf_array_solver``); an unsolvable array is
    refused with the unknowns it cannot separate."""
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
    s = array_solver(geometry)
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


def combination_rows(vectors) -> np.ndarray:
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


def polynomial_text(row) -> str:
    terms = []
    for c, m in zip(row, _MONO):
        if c == 0:
            continue
        mag = abs(c)
        coef = "" if abs(mag - 1) < 1e-9 else f"{mag:.3g} "
        terms.append(("- " if c < 0 else "+ ") + coef + m)
    text = " ".join(terms)
    return text[2:] if text.startswith("+ ") else "-" + text[1:]


def vector_text(v) -> str:
    return "[" + ", ".join(f"{0.0 if abs(x) < 1e-12 else x:.3g}" for x in v) + "]"


def axes_text(frame) -> str:
    return ", ".join(f"a{k + 1} = {vector_text(frame[:, k])}" for k in range(frame.shape[1]))


def common_axes(maps: SolverMaps):
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
    if maps.n_obs == 3 and common_axes(maps).shape[1] == 3:
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
