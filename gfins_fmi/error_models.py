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

__all__ = ["SINS_STATES", "sins_error_model", "covariance", "SinsErrorStd"]

SINS_STATES = ("phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "dL", "dlon")
_OMEGA_IE = 7.292115e-5


def sins_error_model(lat_rad: float, q_bn, h_m: float = 0.0):
    """The strapdown error model at rest as a ``control.StateSpace``.

    Outputs: attitude errors (3, rad), horizontal velocity errors (2, m/s), north and
    east position errors (2, m). Inputs: gyro errors (3, rad/s), accelerometer errors
    (3, m/s^2), body axes, attitude ``q_bn``.
    """
    import control
    from gfins_fmi.trajectory import gravity, quat_to_dcm, radii
    L = float(lat_rad)
    if not abs(L) < np.pi / 2:
        raise ValueError("lat_rad must be inside (-pi/2, pi/2)")
    RM, RN, _, _ = radii(L)
    RM, RN = RM + h_m, RN + h_m
    g = float(gravity(L, h_m))
    sL, cL = np.sin(L), np.cos(L)
    W = _OMEGA_IE
    w_ie = np.array([0.0, W * cL, W * sL])
    C = quat_to_dcm(np.asarray(q_bn, float))
    A = np.zeros((7, 7))

    def skew(v):
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    A[0:3, 0:3] = -skew(w_ie)
    # d(w_in): columns dv_E (3), dv_N (4), dL (5)
    A[0, 4] = -1.0 / RM
    A[1, 3] = 1.0 / RN
    A[1, 5] = -W * sL
    A[2, 3] = sL / cL / RN
    A[2, 5] = W * cL
    f_n = np.array([0.0, 0.0, g])
    A[3:5, 0:3] = skew(f_n)[0:2]                      # (f^n x phi), horizontal rows
    A[3:5, 3:5] = -2 * skew(w_ie)[0:2, 0:2]           # -2 w_ie x dv, horizontal
    A[5, 4] = 1.0 / RM
    A[6, 3] = 1.0 / (RN * cL)
    B = np.zeros((7, 6))
    B[0:3, 0:3] = -C
    B[3:5, 3:6] = C[0:2]
    Cout = np.zeros((7, 7))
    Cout[0:5, 0:5] = np.eye(5)
    Cout[5, 5] = RM
    Cout[6, 6] = RN * cL
    return control.ss(A, B, Cout, np.zeros((7, 6)),
                      inputs=["dw_x", "dw_y", "dw_z", "df_x", "df_y", "df_z"],
                      outputs=["phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "d_north", "d_east"],
                      states=list(SINS_STATES))


@dataclass
class SinsErrorStd:
    """1-sigma of the outputs at the requested times: t_s (m,), std (m, 7) in the output
    order of ``sins_error_model`` (rad, m/s, m)."""
    t_s: np.ndarray
    std: np.ndarray


def covariance(sys, t_s, gyro_bias_std_rad_s=0.0, accel_bias_std_m_s2=0.0,
               gyro_white_rad_s_sqrt_hz=0.0, accel_white_m_s2_sqrt_hz=0.0,
               dt_s: float = 1.0) -> SinsErrorStd:
    """Covariance of a linear error model driven by random-constant biases and white
    noise, from zero initial error, by Van Loan's discretisation over steps of dt_s.

    White noise is given as the (two-sided) density q with E[w(t) w(s)] = q^2 delta(t-s):
    an angle random walk N (rad/sqrt(s)) is q = N for the gyro.
    """
    from scipy.linalg import expm
    A, B, C = np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)
    n, m = A.shape[0], B.shape[1]
    t_s = np.asarray(t_s, float)
    if np.any(np.diff(t_s) <= 0) or t_s[0] < 0:
        raise ValueError("t_s must be increasing and >= 0")
    # augmented state: [error (n), biases (m)], biases constant
    Aa = np.zeros((n + m, n + m))
    Aa[:n, :n] = A
    Aa[:n, n:] = B
    Ga = np.zeros((n + m, m))
    Ga[:n] = B
    q = np.r_[np.full(3, float(gyro_white_rad_s_sqrt_hz)), np.full(3, float(accel_white_m_s2_sqrt_hz))] ** 2
    Qc = Ga @ np.diag(q) @ Ga.T
    # Van Loan: exp([[-A, Q], [0, A^T]] dt) -> Phi, Qd
    N = n + m
    M = np.zeros((2 * N, 2 * N))
    M[:N, :N] = -Aa
    M[:N, N:] = Qc
    M[N:, N:] = Aa.T
    E = expm(M * dt_s)
    Phi = E[N:, N:].T
    Qd = Phi @ E[:N, N:]
    P = np.zeros((N, N))
    P[n:n + 3, n:n + 3] = np.eye(3) * float(gyro_bias_std_rad_s) ** 2
    P[n + 3:, n + 3:] = np.eye(3) * float(accel_bias_std_m_s2) ** 2
    Caug = np.zeros((C.shape[0], N))
    Caug[:, :n] = C
    out = np.empty((t_s.size, C.shape[0]))
    t = 0.0
    for k, tk in enumerate(t_s):
        steps = int(round((tk - t) / dt_s))
        for _ in range(steps):
            P = Phi @ P @ Phi.T + Qd
        t += steps * dt_s
        out[k] = np.sqrt(np.maximum(np.diag(Caug @ P @ Caug.T), 0.0))
    return SinsErrorStd(t_s, out)
