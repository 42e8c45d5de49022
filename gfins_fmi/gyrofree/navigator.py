"""The gyro-free navigator: array outputs -> (w, f) by the rate solver -> the strapdown
mechanization (rate input), in one C call per record (``gf_gfnav``), with the cubic
Hermite attitude and velocity increments (seed 000)."""
from __future__ import annotations

import dataclasses

import numpy as np

from gfins_fmi._lib import (NonFiniteInputError, SampleError, as_array, as_positive_scalar,
                            as_rows, as_start_index, as_vector3, check_status, done_before, ffi,
                            first_nonfinite, lib, ptr, status_text)
from gfins_fmi.gyrofree.array import ArrayGeometry
from gfins_fmi.gyrofree.geometry import array_solver
from gfins_fmi.gyrofree.rate_solver import RateSolution, check_rate_loop, init_error, rate_config
from gfins_fmi.nav.strapdown import NavSolution, NavState, SinsConfig

__all__ = ["INTEGRATIONS", "hermite_increments", "GyroFreeNavigator"]

#: attitude/velocity integration of the navigator over a sampling interval
INTEGRATIONS = {"linear": lib.GF_GFNAV_LINEAR, "hermite": lib.GF_GFNAV_HERMITE}


def hermite_increments(w0_rad_s, w_dot0_rad_s2, f0_m_s2, w1_rad_s, w_dot1_rad_s2, f1_m_s2,
                       T_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Rotation vector (rad) and body velocity increment (m/s) of one interval of length
    ``T_s`` under the cubic Hermite rate model through (w, w_dot) at both ends: what the
    navigator integrates (``integration="hermite"``; equations in csrc/gyrofree/gf_gfins.h).

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
        ``gf_hermite_increments`` in csrc/gyrofree/gf_gfins.h.
    allow_unstable : bool
        As :class:`RateSolver`.
    """

    def __init__(self, geometry: ArrayGeometry, initial: NavState, strategy: str = "integrate",
                 omega_init_rad_s=(0.0, 0.0, 0.0), accel_noise_m_s2: float = 1e-4,
                 sins: SinsConfig | None = None, *, bias_walk_rad_s2_sqrt_s: float = 1e-6,
                 init_std_rad_s: float = 1e-2, init_bias_std_rad_s2: float = 1e-3,
                 integration: str = "hermite", allow_unstable: bool = False):
        array_solver(geometry)
        self.geometry = geometry
        cfg = rate_config(strategy, accel_noise_m_s2, bias_walk_rad_s2_sqrt_s, init_std_rad_s,
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
            raise ValueError(init_error(strategy, geometry, cfg))
        check_status(status, "gf_gfnav_init")
        check_rate_loop(geometry, strategy, allow_unstable)
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
