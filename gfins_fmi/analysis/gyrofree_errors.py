"""Error-propagation models as python-control systems, and their covariance.

The strapdown model (``sins_error_model``) is the classic linearised error dynamics of
an ENU mechanization at rest with the height held (Titterton & Weston ch. 12; Savage
ch. 12), in the convention C_b^n(computed) = (I - [phi x]) C_b^n(true):

    phi'  = -w_ie x phi + d(w_in) - C_b^n dw          (attitude, rad)
    dv'   = f^n x phi - 2 w_ie x dv + C_b^n df        (horizontal velocity, m/s)
    dL'   = dv_N / R_M,  dlon' = dv_E / (R_N cos L)   (position, rad)
    d(w_in) = [-dv_N/R_M, dv_E/R_N - W sinL dL, dv_E tanL/R_N + W cosL dL]

with states [phi_E, phi_N, phi_U, dv_E, dv_N, dL, dlon] and inputs the gyro errors dw
(rad/s) and accelerometer errors df (m/s^2) in body axes. Its Schuler frequency
sqrt(g/R), Earth-rate and Foucault couplings come out of A. ``covariance`` propagates
constant sensor biases (random constants) and white noise (angle / velocity random
walk) through it with the Van Loan discretisation (python-control's Gramians reject
unstable or marginally stable systems, so finite horizons are computed here).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SINS_STATES", "INS_STATES", "ins_state_names", "ins_error_matrices",
           "ins_error_model", "GYROFREE_OUTPUTS", "TimeVaryingModel", "sins_error_model", "gyrofree_error_model",
           "covariance", "propagate", "ErrorStd", "with_bias_states", "observability",
           "Observability", "frequency_response", "gyrofree_fused_std"]

SINS_STATES = ("phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "dL", "dlon")
GYROFREE_OUTPUTS = ("phi_x", "phi_y", "phi_z", "dv_x", "dv_y", "dv_z", "dp_x", "dp_y", "dp_z")
_OMEGA_IE = 7.292115e-5


INS_STATES = ("dv_E", "dv_N", "dv_U", "dL", "dlon", "dh", "phi_E", "phi_N", "phi_U",
              "bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z")
"""Error states of the integrated navigation filter (seed 004 eq. 17, its order): velocity
(m/s), latitude and longitude (rad), height (m), attitude (rad), gyro bias (rad/s) and
accelerometer bias (m/s^2) not yet compensated; optional blocks follow (see
:func:`ins_state_names`)."""


def ins_state_names(scale_states: bool = False, baro_state: bool = False,
                    odo_state: bool = False, odo_mount_state: bool = False) -> tuple:
    """State names of a filter configuration (15 to 25 states, gf_ins_gnss.h order)."""
    names = list(INS_STATES)
    if scale_states:
        names += ["sg_x", "sg_y", "sg_z", "sa_x", "sa_y", "sa_z"]
    if baro_state:
        names += ["b_baro"]
    if odo_state:
        names += ["k_odo"]
    if odo_mount_state:
        names += ["odo_pitch", "odo_heading"]
    return tuple(names)


def ins_error_matrices(lat_rad: float, h_m: float, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s,
                       *, scale_states: bool = False, baro_state: bool = False,
                       odo_state: bool = False, odo_mount_state: bool = False, tau_s=None):
    """The continuous error model of the integrated-navigation filter, x' = F x + G w:
    **the definition** that the C filter (csrc/gf_ins_gnss.c) implements; tests compare
    the two at several states, and this one with a numerical linearisation of the
    navigation equations.

    Convention C_b^n(computed) = (I - [phi x]) C_b^n(true); position, velocity errors are
    computed - true; sensor states are true - estimated. Titterton & Weston ch. 12.3
    (moving vehicle: transport-rate and gravity couplings included, derivatives of the
    radii and of gravity with latitude neglected):

        phi'  = -w_in x phi + d(w_in) - C dw_ib,        dw_ib = b_g + diag(w_ib) s_g
        dv'   = f^n x phi + C df + v x (2 d(w_ie) + d(w_en)) - (2 w_ie + w_en) x dv + dg
                                                         df = b_a + diag(f^b) s_a
        dL'   = dv_N / (R_M + h) - v_N dh / (R_M + h)^2
        dlon' = (dv_E + v_E tan L dL - v_E dh / (R_N + h)) / ((R_N + h) cos L)
        dh'   = dv_U,    dg_U = 2 g dh / (sqrt(R_M R_N) + h)
        sensor states: first-order Gauss-Markov x' = -x / tau (tau 0 or inf: constant)

    Parameters
    ----------
    lat_rad, h_m, v_enu_m_s, q_bn : the navigation state (rad, m, m/s, q_b^n)
    f_b_m_s2, w_ib_b_rad_s : specific force and angular rate, body axes
    scale_states, baro_state, odo_state : the optional blocks
    tau_s : dict of correlation times (s) by block name ("bg", "ba", "sg", "sa", "baro",
        "odo", "odo_mount"); missing or 0: random constant

    Returns
    -------
    F : (n, n); G : (n, n - 3) with noise inputs [accelerometer white (3), gyro white (3),
    one driving noise per sensor state], in that order.
    """
    from gfins_fmi.trajectory import WGS84, gravity, quat_to_dcm, radii
    L, h = float(lat_rad), float(h_m)
    if not abs(L) < np.pi / 2:
        raise ValueError("lat_rad must be inside (-pi/2, pi/2)")
    v = np.asarray(v_enu_m_s, float)
    C = quat_to_dcm(np.asarray(q_bn, float))
    fb, wb = np.asarray(f_b_m_s2, float), np.asarray(w_ib_b_rad_s, float)
    RM, RN, _, _ = radii(L)
    Rm, Rn, Re = RM + h, RN + h, np.sqrt(RM * RN) + h
    g = float(gravity(L, h))
    W = WGS84.omega_ie
    vE, vN, _ = v
    sL, cL, tL = np.sin(L), np.cos(L), np.tan(L)
    w_ie = np.array([0.0, W * cL, W * sL])
    w_en = np.array([-vN / Rm, vE / Rn, vE * tL / Rn])
    # Jacobians of the Earth and transport rates: columns (dv_E, dv_N, dv_U) and (dL, dlon, dh)
    Jie_p = np.zeros((3, 3))
    Jie_p[:, 0] = [0.0, -W * sL, W * cL]
    Jen_v = np.array([[0.0, -1.0 / Rm, 0.0], [1.0 / Rn, 0.0, 0.0], [tL / Rn, 0.0, 0.0]])
    Jen_p = np.zeros((3, 3))
    Jen_p[:, 0] = [0.0, 0.0, vE / (Rn * cL ** 2)]
    Jen_p[:, 2] = [vN / Rm ** 2, -vE / Rn ** 2, -vE * tL / Rn ** 2]
    names = ins_state_names(scale_states, baro_state, odo_state, odo_mount_state)
    n = len(names)
    ix = {k: names.index(k) for k in names}
    V, P, A = slice(0, 3), slice(3, 6), slice(6, 9)
    F = np.zeros((n, n))
    # attitude
    F[A, A] = -_skew(w_ie + w_en)
    F[A, V] = Jen_v
    F[A, P] = Jie_p + Jen_p
    F[A, 9:12] = -C
    # velocity
    F[V, A] = _skew(C @ fb)
    F[V, V] = -_skew(2 * w_ie + w_en) + _skew(v) @ Jen_v
    F[V, P] = _skew(v) @ (2 * Jie_p + Jen_p)
    F[2, 5] += 2 * g / Re
    F[V, 12:15] = C
    # position
    F[3, 1] = 1.0 / Rm
    F[3, 5] = -vN / Rm ** 2
    F[4, 0] = 1.0 / (Rn * cL)
    F[4, 3] = vE * tL / (Rn * cL)
    F[4, 5] = -vE / (Rn ** 2 * cL)
    F[5, 2] = 1.0
    if scale_states:
        F[A, ix["sg_x"]:ix["sg_x"] + 3] = -C @ np.diag(wb)
        F[V, ix["sa_x"]:ix["sa_x"] + 3] = C @ np.diag(fb)
    tau = dict(tau_s or {})
    blocks = {"bg": range(9, 12), "ba": range(12, 15)}
    if scale_states:
        blocks["sg"] = range(ix["sg_x"], ix["sg_x"] + 3)
        blocks["sa"] = range(ix["sa_x"], ix["sa_x"] + 3)
    if baro_state:
        blocks["baro"] = [ix["b_baro"]]
    if odo_state:
        blocks["odo"] = [ix["k_odo"]]
    if odo_mount_state:
        blocks["odo_mount"] = [ix["odo_pitch"], ix["odo_heading"]]
    unknown = set(tau) - set(blocks)
    if unknown:
        raise ValueError(f"tau_s has no block {sorted(unknown)}; blocks: {sorted(blocks)}")
    for k, idx in blocks.items():
        t = float(tau.get(k, 0.0))
        if t > 0 and np.isfinite(t):
            for i in idx:
                F[i, i] = -1.0 / t
    G = np.zeros((n, n - 3))
    G[V, 0:3] = C
    G[A, 3:6] = -C
    G[9:, 6:] = np.eye(n - 9)
    return F, G


def ins_error_model(lat_rad: float, h_m: float, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s,
                    **kwargs):
    """:func:`ins_error_matrices` as a ``control.StateSpace`` (outputs = states)."""
    import control
    F, G = ins_error_matrices(lat_rad, h_m, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s, **kwargs)
    names = ins_state_names(kwargs.get("scale_states", False), kwargs.get("baro_state", False),
                            kwargs.get("odo_state", False), kwargs.get("odo_mount_state", False))
    n = len(names)
    inputs = ["w_a_x", "w_a_y", "w_a_z", "w_g_x", "w_g_y", "w_g_z"] + [f"w_{k}" for k in names[9:]]
    return control.ss(F, G, np.eye(n), np.zeros((n, n - 3)), inputs=inputs,
                      outputs=list(names), states=list(names))


def sins_error_model(lat_rad: float, q_bn, h_m: float = 0.0):
    """The strapdown error model at rest as a ``control.StateSpace``: the integrated
    filter's model (:func:`ins_error_matrices`) at zero velocity with the height held,
    reduced to attitude, horizontal velocity and position.

    Outputs: attitude errors (3, rad), horizontal velocity errors (2, m/s), north and
    east position errors (2, m). Inputs: gyro errors (3, rad/s), accelerometer errors
    (3, m/s^2), body axes, attitude ``q_bn``.
    """
    import control
    from gfins_fmi.trajectory import gravity, quat_to_dcm, radii
    L = float(lat_rad)
    if not abs(L) < np.pi / 2:
        raise ValueError("lat_rad must be inside (-pi/2, pi/2)")
    C = quat_to_dcm(np.asarray(q_bn, float))
    f_b = C.T @ np.array([0.0, 0.0, float(gravity(L, h_m))])     # at rest: f^n = -g^n
    F, _ = ins_error_matrices(L, h_m, np.zeros(3), q_bn, f_b, np.zeros(3))
    sel = [6, 7, 8, 0, 1, 3, 4]                 # phi (3), dv_E, dv_N, dL, dlon
    A = F[np.ix_(sel, sel)]
    B = F[np.ix_(sel, range(9, 15))]            # the bias columns: gyro, accelerometer errors
    RM, RN, _, _ = radii(L)
    Cout = np.zeros((7, 7))
    Cout[0:5, 0:5] = np.eye(5)
    Cout[5, 5] = RM + h_m
    Cout[6, 6] = (RN + h_m) * np.cos(L)
    return control.ss(A, B, Cout, np.zeros((7, 6)),
                      inputs=["dw_x", "dw_y", "dw_z", "df_x", "df_y", "df_z"],
                      outputs=["phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "d_north", "d_east"],
                      states=list(SINS_STATES))


def _skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def _rotation(rotvec):
    """exp([v x]) by Rodrigues' formula."""
    v = np.asarray(rotvec, float)
    th = np.linalg.norm(v)
    K = _skew(v)
    if th < 1e-8:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + np.sin(th) / th * K + (1 - np.cos(th)) / th ** 2 * K @ K


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
    from gfins_fmi.gyrofree import on_jacobian, solver_maps
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


@dataclass
class TimeVaryingModel:
    """A linear time-varying error model x' = A(t) x + B(t) u, y = C x (the gyro-free
    INS under rotation: the body-to-frame matrix turns the body-fixed rate and force
    errors). ``propagate`` accepts it like a StateSpace; ``nlsys()`` gives the
    python-control system for simulation (``control.input_output_response``)."""
    A_of_t: object
    B_of_t: object
    C: np.ndarray
    state_labels: list
    input_labels: list
    output_labels: list

    def nlsys(self):
        import control
        return control.nlsys(lambda t, x, u, params: self.A_of_t(t) @ x + self.B_of_t(t) @ u,
                             lambda t, x, u, params: self.C @ x, states=self.state_labels,
                             inputs=self.input_labels, outputs=self.output_labels)


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
    import control
    from gfins_fmi.trajectory import quat_to_dcm
    lm = _array_maps(geometry, gravity_m_s2, omega_b_rad_s, dt_s)
    ns, n_est, P, K, S, w, g = lm.ns, lm.n_est, lm.P, lm.K, lm.S, lm.w, lm.g
    S_f, S_wd = S(range(3)), S(range(3, 6))
    if strategy == "integrate":
        # dw' = S_wd (P b - K dw): the rate error is a state
        n_x, off = 12, 3
        A_rate, B_rate = -S_wd @ K, S_wd @ P
        G_f_x, G_f_b = -S_f @ K, S_f @ P                  # df = G_f_x dw + G_f_b b
    elif strategy == "sqrt":
        from gfins_fmi.gyrofree import fit_pinv, on_jacobian, rate_model
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
    fxn = _skew(np.array([0.0, 0.0, g]))

    def A_of_t(t):
        C = C0 @ _rotation(w * t)
        A = np.zeros((n_x, n_x))
        A[off + 3:off + 6, off:off + 3] = fxn
        A[off + 6:off + 9, off + 3:off + 6] = np.eye(3)
        if strategy == "integrate":
            A[0:3, 0:3] = A_rate
            A[3:6, 0:3] = -C
            A[6:9, 0:3] = C @ G_f_x
        return A

    def B_of_t(t):
        C = C0 @ _rotation(w * t)
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


@dataclass
class ErrorStd:
    """1-sigma of a model's outputs at the requested times: t_s (m,), std (m, n_out) in
    the model's output order (rad, m/s, m)."""
    t_s: np.ndarray
    std: np.ndarray


def covariance(sys, t_s, gyro_bias_std_rad_s=0.0, accel_bias_std_m_s2=0.0,
               gyro_white_rad_s_sqrt_hz=0.0, accel_white_m_s2_sqrt_hz=0.0,
               dt_s: float = 1.0) -> ErrorStd:
    """``propagate`` for ``sins_error_model``: the same bias and white-noise level on
    the three gyros and on the three accelerometers.

    White noise is given as the (two-sided) density q with E[w(t) w(s)] = q^2 delta(t-s):
    an angle random walk N (rad/sqrt(s)) is q = N for the gyro.
    """
    return propagate(sys, t_s, np.r_[np.full(3, float(gyro_bias_std_rad_s)),
                                     np.full(3, float(accel_bias_std_m_s2))],
                     np.r_[np.full(3, float(gyro_white_rad_s_sqrt_hz)),
                           np.full(3, float(accel_white_m_s2_sqrt_hz))], dt_s)


def propagate(sys, t_s, bias_std, white_density, dt_s: float = 1.0) -> ErrorStd:
    """Covariance of a linear error model whose inputs are independent random-constant
    biases (std ``bias_std``, one per input) plus white noise (density
    ``white_density``, one per input: E[w(t) w(s)] = q^2 delta(t-s)), from zero initial
    error, by Van Loan's discretisation over steps of dt_s. A sampled white noise of
    std sigma at interval T has q = sigma sqrt(T).
    """
    from scipy.linalg import expm
    varying = isinstance(sys, TimeVaryingModel)
    A_of_t = sys.A_of_t if varying else (lambda t, A=np.asarray(sys.A): A)
    B_of_t = sys.B_of_t if varying else (lambda t, B=np.asarray(sys.B): B)
    C = np.asarray(sys.C)
    n, m = A_of_t(0.0).shape[0], B_of_t(0.0).shape[1]
    bias_std = np.broadcast_to(np.asarray(bias_std, float), (m,))
    q = np.broadcast_to(np.asarray(white_density, float), (m,)) ** 2
    if not (np.all(np.isfinite(bias_std)) and np.all(np.isfinite(q))):
        raise ValueError("bias_std and white_density must be finite")
    t_s = np.atleast_1d(np.asarray(t_s, float))
    if np.any(np.diff(t_s) <= 0) or t_s[0] < 0:
        raise ValueError("t_s must be increasing and >= 0")
    if not dt_s > 0:
        raise ValueError("dt_s must be > 0 (s)")
    N = n + m

    def van_loan(t):
        """Phi and Qd of the step starting at t, with the model at its midpoint (a
        time-varying model: second order in dt)."""
        A, B = A_of_t(t + 0.5 * dt_s), B_of_t(t + 0.5 * dt_s)
        # augmented state: [error (n), biases (m)], biases constant
        Aa = np.zeros((N, N))
        Aa[:n, :n], Aa[:n, n:] = A, B
        Ga = np.zeros((N, m))
        Ga[:n] = B
        Mv = np.zeros((2 * N, 2 * N))
        Mv[:N, :N] = -Aa
        Mv[:N, N:] = Ga @ np.diag(q) @ Ga.T
        Mv[N:, N:] = Aa.T
        E = expm(Mv * dt_s)
        Phi = E[N:, N:].T
        return Phi, Phi @ E[:N, N:]

    if not varying:
        fixed = van_loan(0.0)
    P = np.zeros((N, N))
    P[n:, n:] = np.diag(bias_std ** 2)
    Caug = np.zeros((C.shape[0], N))
    Caug[:, :n] = C
    out = np.empty((t_s.size, C.shape[0]))
    t = 0.0
    for k, tk in enumerate(t_s):
        steps = int(round((tk - t) / dt_s))
        for _ in range(steps):
            Phi, Qd = van_loan(t) if varying else fixed
            P = Phi @ P @ Phi.T + Qd
            t += dt_s
        out[k] = np.sqrt(np.maximum(np.diag(Caug @ P @ Caug.T), 0.0))
    return ErrorStd(t_s, out)


def with_bias_states(sys):
    """The model with its inputs turned into random-constant states (appended after the
    error states, named after the inputs): the form a Kalman filter or an
    observability study uses. The original inputs remain, entering the error states
    as before: they are now the white-noise parts of the sensor errors."""
    import control
    A, B, C = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)
    n, m = A.shape[0], B.shape[1]
    Aa = np.zeros((n + m, n + m))
    Aa[:n, :n], Aa[:n, n:] = A, B
    Ba = np.zeros((n + m, m))
    Ba[:n] = B
    Ca = np.zeros((C.shape[0], n + m))
    Ca[:, :n] = C
    return control.ss(Aa, Ba, Ca, np.zeros((C.shape[0], m)), inputs=list(sys.input_labels),
                      outputs=list(sys.output_labels),
                      states=list(sys.state_labels) + list(sys.input_labels))


@dataclass
class Observability:
    """Finite-horizon observability of the states of a model through some measurements.

    Attributes
    ----------
    gramian : (n, n) W = sum_k Phi_k^T H^T H Phi_k dt over the horizon
    singular_values : (n,) of W, descending
    rank : int, numerical rank (relative tolerance ``tol``)
    unobservable : (n, n - rank) unit vectors spanning the unobservable directions, in
        the states' units
    states : the model's state names
    scale : (n,) the normalisation 1 / sqrt(W_ii) (0 for states never seen)
    """
    gramian: np.ndarray
    singular_values: np.ndarray
    rank: int
    unobservable: np.ndarray
    states: tuple
    scale: np.ndarray

    def describe(self, threshold: float = 0.05) -> list[str]:
        """Each unobservable direction as a combination of states in their own units;
        a state is listed when its part of the direction, measured unit-free (times
        sqrt(W_ii)), exceeds ``threshold`` of the largest part."""
        out = []
        w = np.where(self.scale > 0, 1.0 / np.where(self.scale > 0, self.scale, 1.0), 1.0)
        for v in self.unobservable.T:
            weight = np.abs(v * w)
            v = v / v[np.argmax(weight)]
            out.append(" ".join(f"{c:+.3g} {name}" for c, name, wt in zip(v, self.states, weight)
                                if wt > threshold * weight.max()))
        return out


def observability(A, H, t_s, states=None, tol: float = 1e-9) -> Observability:
    """Observability Gramian over a finite horizon along a trajectory.

    Parameters
    ----------
    A : (n, n) array, or callable t -> (n, n)
        Error dynamics (constant, or evaluated along the trajectory: time-varying).
    H : (p, n) array, or callable t -> (p, n)
        Which combinations of states are measured (e.g. velocity of a zero-velocity
        update or of GNSS).
    t_s : (K,) increasing measurement times (s); the transition between them is
        exp(A dt) with A at the interval's start.
    states : names of the n states (default: ``x0..``).
    tol : relative rank tolerance on the singular values of the Gramian normalised
        by its diagonal (so the states' units do not matter).

    python-control's Gramians are infinite-horizon and need a stable system; an INS
    error model is marginally stable (Schuler, Earth rate) or unstable, hence this.
    """
    from scipy.linalg import expm, svd
    t_s = np.atleast_1d(np.asarray(t_s, float))
    if t_s.ndim != 1 or t_s.size < 1 or np.any(np.diff(t_s) <= 0):
        raise ValueError("t_s must be a non-empty increasing sequence of times (s)")
    At = A if callable(A) else (lambda t, A=np.asarray(A, float): A)
    Ht = H if callable(H) else (lambda t, H=np.asarray(H, float): H)
    n = np.asarray(At(t_s[0])).shape[0]
    if np.asarray(At(t_s[0])).shape != (n, n) or np.asarray(Ht(t_s[0])).shape[-1] != n:
        raise ValueError("A must be (n, n) and H (p, n)")
    W = np.zeros((n, n))
    Phi = np.eye(n)
    dts = np.diff(t_s, append=t_s[-1] + (t_s[-1] - t_s[-2] if t_s.size > 1 else 1.0))
    for k, t in enumerate(t_s):
        Hk = np.atleast_2d(np.asarray(Ht(t), float))
        M = Hk @ Phi
        W += M.T @ M * dts[k]
        Phi = expm(np.asarray(At(t), float) * dts[k]) @ Phi
    # unit-free: scale each state by its own observability (states never seen stay 0),
    # so rad, m/s and m/s^2 do not decide the rank between them
    d = np.sqrt(np.diag(W))
    scale = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    _, sv, vt = svd(W * np.outer(scale, scale))
    rank = int(np.sum(sv > tol * sv[0])) if sv[0] > 0 else 0
    basis = vt[rank:].T * scale[:, None]       # back to the states' own units
    never = np.flatnonzero(d == 0)              # states with no effect at all: there the
    keep = np.linalg.norm(basis, axis=0) > 0    # scaled vectors vanish; use unit vectors
    basis = np.column_stack([basis[:, keep]] + [np.eye(n)[:, j] for j in never])[:, :n - rank]
    basis = basis / np.linalg.norm(basis, axis=0)
    names = tuple(states) if states is not None else tuple(f"x{i}" for i in range(n))
    return Observability(W, sv, rank, basis, names, scale)


def frequency_response(sys, omega_rad_s, inputs=None, outputs=None):
    """Gain and phase from sensor errors to navigation errors at the angular
    frequencies ``omega_rad_s`` (rad/s): ``control.frequency_response`` of the selected
    input/output channels (names from the model's labels). Returns the
    ``control.FrequencyResponseData`` (``.magnitude``, ``.phase``, ``.plot()``)."""
    import control
    sub = sys
    if inputs is not None or outputs is not None:
        ins = list(sys.input_labels) if inputs is None else list(inputs)
        outs = list(sys.output_labels) if outputs is None else list(outputs)
        for name in ins + outs:
            if name not in sys.input_labels + sys.output_labels:
                raise ValueError(f"no channel {name!r}; inputs {sys.input_labels}, "
                                 f"outputs {sys.output_labels}")
        sub = sys[[sys.output_labels.index(o) for o in outs],
                  [sys.input_labels.index(i) for i in ins]]
    return control.frequency_response(sub, np.asarray(omega_rad_s, float))


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
    from gfins_fmi.trajectory import quat_to_dcm
    from gfins_fmi.gyrofree import on_jacobian
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
    fxn = _skew(np.array([0.0, 0.0, g]))
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
            C = C0 @ _rotation(w * t)
            Cm = C0 @ _rotation(w * (t - 0.5 * dt))
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
