"""The rate solver: a record of array outputs -> specific force, angular rate and
angular acceleration with a chosen rate strategy (C core ``gf_gfins``), refusing a
strategy whose error loop is unstable on the array."""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_positive_scalar, as_rows,
                            as_scalar, as_vector3, check_status, done_before, ffi, first_nonfinite,
                            lib, ptr, status_text)
from gfins_fmi.gyrofree.array import ArrayGeometry
from gfins_fmi.gyrofree.geometry import STRATEGIES, array_solver, layout
from gfins_fmi.gyrofree.report import geometry_report
from gfins_fmi.gyrofree.stability import rate_loop_stability

__all__ = ["RateSolution", "RateSolver", "UnstableRateLoopWarning", "rate_config",
           "strategy_error", "init_error", "check_rate_loop", "MAX_ACCEL_NOISE_M_S2"]

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


def rate_config(strategy, accel_noise_m_s2, bias_walk, init_std, init_bias_std):
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {sorted(STRATEGIES)}; got {strategy!r}")
    c = ffi.new("gf_rate_config *")
    lib.gf_rate_config_default(c)
    c.strategy = STRATEGIES[strategy]
    # upper bounds: the physical limits of the navigators (|f| <= 1000 m/s^2, |w| <= 50
    # rad/s) bound any meaningful noise and prior; beyond ~1e153 m/s^2 the variances
    # overflow a double, which the C core refused as a bad strategy (issue 21)
    c.accel_noise_m_s2 = as_scalar("accel_noise_m_s2", accel_noise_m_s2, "m/s^2", above=0.0,
                                   at_most=MAX_ACCEL_NOISE_M_S2)
    c.bias_walk_rad_s2_sqrt_s = as_scalar("bias_walk_rad_s2_sqrt_s", bias_walk, "rad/s^2/sqrt(s)",
                                          at_least=0.0, at_most=1e3)
    c.init_std_rad_s = as_scalar("init_std_rad_s", init_std, "rad/s", above=0.0, at_most=50.0)
    c.init_bias_std_rad_s2 = as_scalar("init_bias_std_rad_s2", init_bias_std, "rad/s^2",
                                       at_least=0.0, at_most=1e3)
    return c


#: the largest accelerometer white-noise std a rate solver takes (m/s^2): the navigators'
#: specific-force limit
MAX_ACCEL_NOISE_M_S2 = 1000.0


def init_error(strategy: str, geometry: ArrayGeometry, cfg) -> str:
    """Why gf_gfins_init refused: the strategy on this array (:func:`strategy_error`) when
    the array cannot serve it, else the settings (their covariances)."""
    if strategy not in geometry_report(geometry).working_strategies:
        return strategy_error(strategy, geometry)
    return (f"the rate solver ({strategy!r}) refused its settings: accel_noise_m_s2 = "
            f"{cfg.accel_noise_m_s2:g} m/s^2, init_std_rad_s = {cfg.init_std_rad_s:g} rad/s, "
            f"init_bias_std_rad_s2 = {cfg.init_bias_std_rad_s2:g} rad/s^2, "
            f"bias_walk_rad_s2_sqrt_s = {cfg.bias_walk_rad_s2_sqrt_s:g}: the covariances they "
            "give on this array are not finite; give physical values")



#: what each rate strategy needs, in words
_NEEDS = {"sqrt": "at least 3 observed product combinations of w w^T",
          "fused": "at least one observed product combination of w w^T",
          "eigen": "all of w w^T observed (6 combinations)"}


class UnstableRateLoopWarning(UserWarning):
    """A rate strategy runs on an array where its error loop is unstable (allowed with
    ``allow_unstable=True``)."""


def strategy_error(strategy: str, geometry: ArrayGeometry) -> str:
    rep = geometry_report(geometry)
    ok = rep.working_strategies
    return (f"strategy {strategy!r} needs an array with {_NEEDS[strategy]}; this one observes "
            f"{len(rep.observed)} (" + ("; ".join(rep.observed) or "none") + "). Strategies that "
            "navigate it: " + (", ".join(repr(a) for a in ok) if ok else "none") + "; layouts "
            "that serve " + repr(strategy) + ": " + " or ".join(
                repr(a) for a in ("cube6", "qin9", "12")
                if geometry_report(layout(a, 0.1)).stability[strategy].verdict
                in ("stable", "marginal")))


def check_rate_loop(geometry: ArrayGeometry, strategy: str, allow_unstable: bool, dt_s=0.01) -> None:
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
        array_solver(geometry)  # geometry errors with their names first
        self.geometry = geometry
        self.strategy = strategy
        cfg = rate_config(strategy, accel_noise_m_s2, bias_walk_rad_s2_sqrt_s, init_std_rad_s,
                           init_bias_std_rad_s2)
        w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
        self._state = ffi.new("gf_gfins_state *")
        status = lib.gf_gfins_init(self._state, geometry._c, cfg, ptr(w0, 3), ffi.NULL)
        if status == lib.GF_ERR_BAD_PARAMETER:
            raise ValueError(init_error(strategy, geometry, cfg))
        check_status(status, "gf_gfins_init")
        check_rate_loop(geometry, strategy, allow_unstable)

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
