"""Error models of gyro-free navigation for any array layout, at rest or rotating, for the
``integrate``, ``sqrt`` and ``fused`` rate strategies (the ``eigen`` strategy is not
modelled): the linearised error dynamics of the rate loop (the one linearisation of
:mod:`gfins_fmi.gyrofree.stability`) feeding attitude, velocity and position errors, as
python-control systems (time-invariant at rest, :class:`TimeVaryingModel` rotating), and
the fused strategy's error standard deviations by a Kalman covariance recursion.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.analysis.covariance import ErrorStd, TimeVaryingModel
from gfins_fmi.gyrofree.geometry import fit_pinv, on_jacobian, rate_model, solver_maps
from gfins_fmi.nav.earth import quat_to_dcm, rotation_matrix, skew

__all__ = ["GYROFREE_OUTPUTS", "gyrofree_error_model", "gyrofree_fused_std"]

GYROFREE_OUTPUTS = ("phi_x", "phi_y", "phi_z", "dv_x", "dv_y", "dv_z", "dp_x", "dp_y", "dp_z")


@dataclass
class _ArrayMaps:
    ns: int
    n_est: int
    P: np.ndarray        # pseudo-inverse, n_est x ns: rows f, w_dot, observed combinations z
    K: np.ndarray        # dy / d(w_pred) through the confounded products taken from the rate
    W_obs: np.ndarray    # products W (as in x) per observed coordinate, 6 x n_obs
    maps: object         # gyrofree.SolverMaps
    w: np.ndarray
    g: float

    def S(self, idx):
        """Rows mapping the solved vector y (n_est) to the unknowns idx of x (0..5: f,
        w_dot; 6..11: the products W_jk, wholly observed ones only)."""
        rows = []
        for j in idx:
            r = np.zeros(self.n_est)
            if j < 6:
                r[j] = 1.0
            else:
                r[6:] = self.W_obs[j - 6]
            rows.append(r)
        return np.array(rows)


def _array_maps(geometry, gravity_m_s2, omega_b_rad_s, dt_s) -> _ArrayMaps:
    """The linear maps of an array's solver (from the C core) and checked parameters."""
    maps = solver_maps(geometry)
    g = float(gravity_m_s2)
    if not (np.isfinite(g) and g > 0):
        raise ValueError("gravity_m_s2 must be a positive finite number (m/s^2)")
    w = np.asarray(omega_b_rad_s, float)
    if w.shape != (3,) or not np.all(np.isfinite(w)):
        raise ValueError("omega_b_rad_s must be 3 finite numbers (rad/s)")
    if not dt_s > 0:
        raise ValueError("dt_s must be > 0 (s)")
    K = maps.K_pred @ on_jacobian(w)
    return _ArrayMaps(maps.pinv.shape[1], maps.pinv.shape[0], maps.pinv, K, maps.W_obs, maps, w, g)


def gyrofree_error_model(geometry, q_bn=(1.0, 0.0, 0.0, 0.0), gravity_m_s2: float = 9.8,
                         strategy: str = "integrate", omega_b_rad_s=(0.0, 0.0, 0.0),
                         dt_s: float = 0.01):
    """Error model of a gyro-free INS whose array rotates at a constant body rate
    (zero: at rest) about a point fixed in the flat frame of ``SinsConfig(earth="flat")``.

    The array solver's least-squares pseudo-inverse P (``gf_array_solver.pinv``) maps
    the accelerometer errors b (one per sensor, m/s^2) to errors of the estimated
    unknowns x; the products w w^T it cannot separate come from the predicted rate
    w_pred = w + dt w_dot (``gf_gfins``), so dx = P (b - H_F J(w) dw_pred) with H_F the
    array's columns of those products and J the Jacobian of w w^T. Rate error:

    * ``integrate``: dw' = dw_dot (a state; constant b gives dw ~ t at rest);
    * ``sqrt`` (seed 000 eq. 4): dw_k = d(w_k^2) / (2 w_k), an algebraic map (constant
      b gives a constant dw: attitude ~ t along the rotation, position ~ t^3); in
      general dw = G^+ dz, the linearised weighted least-squares fit of w to the
      observed product combinations z (G = B_o^T J(w)). It needs a rate the products determine (every w_k away from zero for
      Qin's array) -- near a zero crossing the linearisation fails.

    Navigation (C = C_b^n(t) = C0 exp([w x] t), f^n = [0, 0, g]):

        phi' = -C dw        dv' = f^n x phi + C df        dp' = dv

    Parameters
    ----------
    geometry : ArrayGeometry
    q_bn : (4,) attitude at t = 0
    gravity_m_s2 : the flat frame's gravity (SinsConfig.flat_gravity_m_s2)
    strategy : "integrate" or "sqrt"
    omega_b_rad_s : (3,) constant body rate (rad/s)
    dt_s : sampling interval of the navigator (enters w_pred; s)

    Returns
    -------
    control.StateSpace at rest, else ``TimeVaryingModel``. Outputs ``GYROFREE_OUTPUTS``
    (attitude rad, velocity m/s, position m); inputs ``b_0..b_{N-1}`` (m/s^2).
    """
    import control   # lazy: python-control (~0.8 s) off the start-up path
    lm = _array_maps(geometry, gravity_m_s2, omega_b_rad_s, dt_s)
    ns, n_est, P, K, S, w, g = lm.ns, lm.n_est, lm.P, lm.K, lm.S, lm.w, lm.g
    S_f, S_wd = S(range(3)), S(range(3, 6))
    if strategy == "integrate":
        # dw' = S_wd (P b - K dw): the rate error is a state
        n_x, off = 12, 3
        A_rate, B_rate = -S_wd @ K, S_wd @ P
        G_f_x, G_f_b = -S_f @ K, S_f @ P                  # df = G_f_x dw + G_f_b b
    elif strategy == "sqrt":
        model = rate_model(lm.maps, "sqrt")
        if model == "none":
            raise ValueError("strategy 'sqrt' needs an array whose observed products determine "
                             "the rate (at least 3 combinations, such as the diagonal of w w^T)")
        # the rate read from the observed combinations z: a least-squares fit of w weighted
        # by their noise covariance, whose linearisation is dw = G^+ dz, G = B_o^T J(w)
        # (seed 000 eq. 4 for Qin's array: dw_k = d(w_k^2) / (2 w_k))
        G = lm.maps.observed.T @ on_jacobian(w)
        if np.linalg.svd(G, compute_uv=False)[-1] < 2e-3:
            raise ValueError("strategy 'sqrt' is linearised about a rate that the observed products "
                             "determine, with every component away from zero (|w_k| >= 1e-3 rad/s "
                             "for Qin's array): d(w_k) = d(w_k^2) / 2 w_k")
        S_z = np.eye(n_est)[6:]
        Gz = fit_pinv(lm.maps, G, model) @ S_z
        M = Gz + dt_s * S_wd
        G_pred = np.linalg.solve(np.eye(3) + M @ K, M @ P)     # dw_pred = G_pred b
        dx = P - K @ G_pred
        n_x, off = 9, 0
        G_w = Gz @ dx
        G_f_b = S_f @ dx
    else:
        raise ValueError("strategy must be 'integrate' or 'sqrt' for the error model")
    C0 = quat_to_dcm(np.asarray(q_bn, float))
    fxn = skew(np.array([0.0, 0.0, g]))

    def A_of_t(t):
        C = C0 @ rotation_matrix(w * t)
        A = np.zeros((n_x, n_x))
        A[off + 3:off + 6, off:off + 3] = fxn
        A[off + 6:off + 9, off + 3:off + 6] = np.eye(3)
        if strategy == "integrate":
            A[0:3, 0:3] = A_rate
            A[3:6, 0:3] = -C
            A[6:9, 0:3] = C @ G_f_x
        return A

    def B_of_t(t):
        C = C0 @ rotation_matrix(w * t)
        B = np.zeros((n_x, ns))
        if strategy == "integrate":
            B[0:3] = B_rate
        else:
            B[0:3] = -C @ G_w
        B[off + 3:off + 6] = C @ G_f_b
        return B

    Cout = np.zeros((9, n_x))
    Cout[:, off:] = np.eye(9)
    states = (["dw_x", "dw_y", "dw_z"] if off else []) + list(GYROFREE_OUTPUTS)
    inputs = [f"b_{i}" for i in range(ns)]
    if not np.any(w):
        return control.ss(A_of_t(0.0), B_of_t(0.0), Cout, np.zeros((9, ns)), inputs=inputs,
                          outputs=list(GYROFREE_OUTPUTS), states=states)
    return TimeVaryingModel(A_of_t, B_of_t, Cout, states, inputs, list(GYROFREE_OUTPUTS))




def gyrofree_fused_std(geometry, t_s, bias_std_m_s2: float, noise_std_m_s2: float,
                       q_bn=(1.0, 0.0, 0.0, 0.0), gravity_m_s2: float = 9.8,
                       omega_b_rad_s=(1.0, 1.0, 1.0), dt_s: float = 0.01,
                       bias_walk_rad_s2_sqrt_s: float = 1e-6, init_std_rad_s: float = 1e-2,
                       init_bias_std_rad_s2: float = 1e-3) -> ErrorStd:
    """1-sigma navigation errors of the ``fused`` rate strategy (the EKF of ``gf_gfins``
    on [w, w_dot bias], measuring the products w w^T), rotating at a constant body rate.

    The filter is linear in its errors about the true rate; its gains follow from its
    own Riccati recursion (same F, Q, R, P0 as the C core, so they are the gains the
    filter uses), and the errors are propagated sample by sample: the estimated unknowns'
    errors dx_k = P (s_k - H_F J dw_pred) with s_k = b + n_k the sensor errors (a
    random constant plus white noise of ``noise_std_m_s2`` per sample); the prediction
    integrates dw_dot as the C core does (trapezoid, then third-order Adams-Moulton over
    three samples, so the noise of consecutive samples is correlated: the two previous
    dw_dot are states); the update uses the products of the same sample. Navigation as ``gyrofree_error_model``. The result is a discrete-time
    covariance recursion rather than a python-control system: the filter's gains vary
    with time until they settle.

    Returns
    -------
    ErrorStd with the outputs ``GYROFREE_OUTPUTS``.
    """
    lm = _array_maps(geometry, gravity_m_s2, omega_b_rad_s, dt_s)
    m = lm.maps.n_obs
    if m == 0:
        raise ValueError("strategy 'fused' needs an array that observes at least one product "
                         "combination of w w^T (see geometry_report)")
    ns, P, K, w, g, dt = lm.ns, lm.P, lm.K, lm.w, lm.g, float(dt_s)
    S_f, S_wd = lm.S(range(3)), lm.S(range(3, 6))
    S_z = np.eye(lm.n_est)[6:6 + m]
    sig2 = float(noise_std_m_s2) ** 2
    # the filter's own model (gf_gfins_init / rate_step): the observed rows measure
    # (B_o^T + K_z) p(w); the confounded products close a loop through w_dot
    R = sig2 * (S_z @ P) @ (S_z @ P).T
    Fk = np.eye(6)
    Fk[0:3, 3:6] = -dt * np.eye(3)
    Fk[0:3, 0:3] += dt * lm.maps.loop_matrix(w)
    Qk = np.zeros((6, 6))
    Qk[0:3, 0:3] = dt * dt * sig2 * (S_wd @ P) @ (S_wd @ P).T
    Qk[3:6, 3:6] = np.eye(3) * float(bias_walk_rad_s2_sqrt_s) ** 2 * dt
    Hk = np.zeros((m, 6))
    Hk[:, 0:3] = lm.maps.measurement_matrix() @ on_jacobian(w)
    Pf = np.diag([init_std_rad_s ** 2] * 3 + [init_bias_std_rad_s2 ** 2] * 3)
    C0 = quat_to_dcm(np.asarray(q_bn, float))
    fxn = skew(np.array([0.0, 0.0, g]))
    # error state z = [e_w, e_b, dwdot_prev, dwdot_prev2, phi, dv, dp, b (ns)]
    iw, ib, iwd, iwd2, iphi, iv, ip, ibias = 0, 3, 6, 9, 12, 15, 18, 21
    nz = 21 + ns

    def step(Z, N, k, t):
        """One sample, applied to columns: Z (nz, c) previous states, N (ns, c) noise.
        The w_dot integral and the prediction as gf_gfins (third-order Adams-Moulton
        and second-order Adams-Bashforth from the third sample on)."""
        nonlocal Pf
        s_k = Z[ibias:] + N
        first = k == 0
        wd1, wd2 = Z[iwd:iwd + 3], Z[iwd2:iwd2 + 3]
        if first:
            e_pred = Z[iw:iw + 3]
        elif k == 1:
            e_pred = Z[iw:iw + 3] + dt * wd1
        else:
            e_pred = Z[iw:iw + 3] + 0.5 * dt * (3.0 * wd1 - wd2)
        dx = P @ s_k - K @ e_pred
        wd = S_wd @ dx
        ew, eb = Z[iw:iw + 3], Z[ib:ib + 3]
        if k == 1:
            ew = ew + 0.5 * dt * (wd1 + wd) - dt * eb
        elif k > 1:
            ew = ew + dt / 12.0 * (5.0 * wd + 8.0 * wd1 - wd2) - dt * eb
        r = S_z @ (P @ s_k) - Hk[:, 0:3] @ ew
        Kg = Pf @ Hk.T @ np.linalg.inv(Hk @ Pf @ Hk.T + R)
        e = np.vstack([ew, eb]) + Kg @ r
        df = S_f @ (P @ s_k - K @ e[0:3])
        Zn = np.zeros_like(Z)
        Zn[iw:iw + 6] = e
        Zn[iwd:iwd + 3] = wd
        Zn[iwd2:iwd2 + 3] = wd1
        Zn[ibias:] = Z[ibias:]
        if not first:
            C = C0 @ rotation_matrix(w * t)
            Cm = C0 @ rotation_matrix(w * (t - 0.5 * dt))
            Zn[iphi:iphi + 3] = Z[iphi:iphi + 3] - Cm @ (0.5 * dt * (Z[iw:iw + 3] + e[0:3]))
            Zn[iv:iv + 3] = Z[iv:iv + 3] + dt * (fxn @ (0.5 * (Z[iphi:iphi + 3] + Zn[iphi:iphi + 3])) + C @ df)
            Zn[ip:ip + 3] = Z[ip:ip + 3] + 0.5 * dt * (Z[iv:iv + 3] + Zn[iv:iv + 3])
        return Zn, Kg

    t_s = np.atleast_1d(np.asarray(t_s, float))
    if np.any(np.diff(t_s) <= 0) or t_s[0] < 0:
        raise ValueError("t_s must be increasing and >= 0")
    targets = np.round(t_s / dt).astype(int)
    Pz = np.zeros((nz, nz))
    Pz[ibias:, ibias:] = np.eye(ns) * float(bias_std_m_s2) ** 2
    out = np.empty((t_s.size, 9))
    I_z, I_n = np.eye(nz), np.eye(ns)
    for k in range(int(targets[-1]) + 1):
        if k > 0:
            Pf = Fk @ Pf @ Fk.T + Qk
        F, Kg = step(I_z, np.zeros((ns, nz)), k, k * dt)
        G, _ = step(np.zeros((nz, ns)), I_n, k, k * dt)
        Pz = F @ Pz @ F.T + sig2 * G @ G.T
        Pf = (np.eye(6) - Kg @ Hk) @ Pf
        for j in np.flatnonzero(targets == k):
            out[j] = np.sqrt(np.maximum(np.diag(Pz)[iphi:iphi + 9], 0.0))
    return ErrorStd(t_s, out)
