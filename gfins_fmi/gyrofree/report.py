"""The geometry report: what an array observes, how well (rank, condition number, noise
gains) and which rate strategies are stable on it, in words."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gfins_fmi.gyrofree.array import ArrayGeometry
from gfins_fmi.gyrofree.geometry import (GROUPS, STRATEGIES, UNKNOWNS, axes_text, combination_rows,
                                         common_axes, polynomial_text, rate_model, solver_maps,
                                         vector_text)
from gfins_fmi.gyrofree.stability import rate_loop_stability

__all__ = ["GeometryReport", "geometry_report"]

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
                    + axes_text(self.mirror_axes) if frame else "; ".join(self.observed))
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
                       "the sign of w.n for n = " + ", ".join(vector_text(n) for n in self.mirror_axes.T)
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
        return tuple(name for name, bit in GROUPS.items() if int(mask) & int(bit))
    gains = {UNKNOWNS[j]: float(maps.noise_gain[j]) for j in range(12)
             if j < 6 or maps.noise_gain[j] > 0}
    P = maps.pinv
    principal = {name: np.sqrt(np.maximum(np.linalg.eigvalsh(P[rows] @ P[rows].T), 0))[::-1]
                 for name, rows in (("f", slice(0, 3)), ("omega_dot", slice(3, 6)),
                                    ("products", slice(6, 6 + maps.n_obs)))}
    words = lambda V: tuple(polynomial_text(r) for r in combination_rows(V))
    model = rate_model(maps)
    axes = common_axes(maps)
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
