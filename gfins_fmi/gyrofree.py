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
from dataclasses import dataclass

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_array, as_positive_scalar,
                            as_rows, as_scalar, as_vector3, check_status, ffi, first_nonfinite,
                            lib, ptr, status_text)
from gfins_fmi.accel_array import ArrayGeometry, accel9_geometry
from gfins_fmi.sins import NavSolution, NavState, SinsConfig

__all__ = ["UNKNOWNS", "STRATEGIES", "INTEGRATIONS", "hermite_increments", "layout", "GeometryReport", "geometry_report",
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


@dataclass(frozen=True)
class GeometryReport:
    """What an array measures, and how well.

    Attributes
    ----------
    n_sensors, rank : int
    condition_number : float
        Of the columns solved by least squares.
    present, estimated, from_rate : tuple of str
        Groups among ``f``, ``omega_dot``, ``W_diag``, ``W_offdiag``: those that affect
        the outputs; those solved linearly from them; those the solver must take from a
        predicted rate (the array cannot separate them).
    noise_gain : dict name -> float
        Std of each estimated unknown per unit (1 m/s^2) white noise on every output.
    """

    n_sensors: int
    rank: int
    condition_number: float
    present: tuple
    estimated: tuple
    from_rate: tuple
    noise_gain: dict

    @property
    def observable(self) -> dict:
        """Which quantities the array gives linearly: f, omega_dot, the diagonal of
        w w^T (omega_sq) and the full w w^T (omega_outer)."""
        est = set(self.estimated)
        return {"f": "f" in est, "omega_dot": "omega_dot" in est,
                "omega_sq": "W_diag" in est,
                "omega_outer": {"W_diag", "W_offdiag"} <= est}


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


def geometry_report(geometry: ArrayGeometry) -> GeometryReport:
    """Rank, conditioning and noise gains of an array (see :class:`GeometryReport`).

    Raises
    ------
    ValueError
        The array is unsolvable; the message names the unknowns it cannot separate.
    """
    s = _solver_c(geometry)

    def groups(mask):
        return tuple(name for name, bit in _GROUPS.items() if int(mask) & int(bit))
    gains = {UNKNOWNS[int(s.est[r])]: float(s.noise_gain[int(s.est[r])]) for r in range(int(s.n_est))}
    return GeometryReport(int(s.n_sensors), int(s.rank), float(s.cond), groups(s.present),
                          groups(s.estimated), groups(s.from_rate), gains)


@dataclass
class RateSolution:
    """Per-sample solution of an array record: f_m_s2, omega_rad_s, omega_dot_rad_s2
    (n, 3), W (n, 6: W_xx, W_yy, W_zz, W_xy, W_xz, W_yz, measured or predicted), flags
    (n,) with bits 1, 2, 4 (negative omega_k^2 / eigenvalue), 8 (sign unknown), 16
    (fused update skipped)."""

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


#: what each rate strategy needs the array to estimate, and the named layouts that do
_NEEDS = {"sqrt": ("the diagonal of w w^T (W_diag)", {"W_diag"}),
          "fused": ("the diagonal of w w^T (W_diag)", {"W_diag"}),
          "eigen": ("all of w w^T (W_diag and W_offdiag)", {"W_diag", "W_offdiag"})}


def _strategy_error(strategy: str, geometry: ArrayGeometry) -> str:
    rep = geometry_report(geometry)
    need, groups = _NEEDS[strategy]
    able = [name for name in ("cube6", "qin9", "12")
            if groups <= set(geometry_report(layout(name, 0.1)).estimated)]
    return (f"strategy {strategy!r} needs an array that measures {need}; this one estimates "
            f"{', '.join(rep.estimated)} (use 'integrate', or a layout such as "
            + " or ".join(repr(a) for a in able) + ")")


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
    """

    def __init__(self, geometry: ArrayGeometry, strategy: str = "integrate",
                 omega_init_rad_s=(0.0, 0.0, 0.0), accel_noise_m_s2: float = 1e-4,
                 bias_walk_rad_s2_sqrt_s: float = 1e-6, init_std_rad_s: float = 1e-2,
                 init_bias_std_rad_s2: float = 1e-3):
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
                                      f"is not finite; samples 0..{k - 1} are in .partial",
                                      k, col, out._head(k))
        if status != lib.GF_OK:
            raise SampleError(f"sample {k}: {status_text(status)}; samples before it are in .partial",
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
    """

    def __init__(self, geometry: ArrayGeometry, initial: NavState, strategy: str = "integrate",
                 omega_init_rad_s=(0.0, 0.0, 0.0), accel_noise_m_s2: float = 1e-4,
                 sins: SinsConfig | None = None, *, bias_walk_rad_s2_sqrt_s: float = 1e-6,
                 init_std_rad_s: float = 1e-2, init_bias_std_rad_s2: float = 1e-3,
                 integration: str = "hermite"):
        _solver_c(geometry)
        self.geometry = geometry
        cfg = _rate_config(strategy, accel_noise_m_s2, bias_walk_rad_s2_sqrt_s, init_std_rad_s,
                           init_bias_std_rad_s2)
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
        if self._flat:
            check_status(lib.gf_sins_set_flat_position(ffi.addressof(self._state, "nav"),
                                                       ptr(x0.pos_m, 3)), "flat position")
        if integration not in INTEGRATIONS:
            raise ValueError(f"integration must be one of {sorted(INTEGRATIONS)}; got {integration!r}")
        self.integration = integration
        check_status(lib.gf_gfnav_set_integration(self._state, INTEGRATIONS[integration]),
                     "gf_gfnav_set_integration")

    def run(self, A_m_s2, dt_s: float, h_ext_m=None) -> tuple[NavSolution, RateSolution]:
        """Navigate a record (n, n_sensors); row k = state at sample k (row 0: t0)."""
        ns = self.geometry.n_sensors
        A = as_rows("A_m_s2", A_m_s2, ns, "m/s^2")
        dt_s = as_positive_scalar("dt_s (sampling interval)", dt_s, "s")
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
                raise NonFiniteInputError(f"A_m_s2[{k}, {col}] = {A[k, col]} is not finite; "
                                          "the solution before it is in .partial", k, col, partial)
            raise SampleError(f"sample {k}: {status_text(status)}; the solution before it is in "
                              ".partial", int(status), k, partial)
        return sol, rates
