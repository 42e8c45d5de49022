"""The strapdown error model at rest as a python-control system.

The strapdown model (``sins_error_model``) is the classic linearised error dynamics of
an ENU mechanization at rest with the height held (Titterton & Weston ch. 12; Savage
ch. 12), in the convention C_b^n(computed) = (I - [phi x]) C_b^n(true):

    phi'  = -w_ie x phi + d(w_in) - C_b^n dw          (attitude, rad)
    dv'   = f^n x phi - 2 w_ie x dv + C_b^n df        (horizontal velocity, m/s)
    dL'   = dv_N / R_M,  dlon' = dv_E / (R_N cos L)   (position, rad)
    d(w_in) = [-dv_N/R_M, dv_E/R_N - W sinL dL, dv_E tanL/R_N + W cosL dL]

with states [phi_E, phi_N, phi_U, dv_E, dv_N, dL, dlon] and inputs the gyro errors dw
(rad/s) and accelerometer errors df (m/s^2) in body axes. Its Schuler frequency
sqrt(g/R), Earth-rate and Foucault couplings come out of A. It is the integrated filter's
model (:func:`gfins_fmi.estimation.error_model.ins_error_matrices`) at zero velocity with
the height held; :mod:`gfins_fmi.analysis.covariance` propagates sensor errors through it.
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.estimation.error_model import ins_error_matrices
from gfins_fmi.nav.earth import gravity, quat_to_dcm, radii

__all__ = ["SINS_STATES", "sins_error_model"]

SINS_STATES = ("phi_E", "phi_N", "phi_U", "dv_E", "dv_N", "dL", "dlon")


def sins_error_model(lat_rad: float, q_bn, h_m: float = 0.0):
    """The strapdown error model at rest as a ``control.StateSpace``: the integrated
    filter's model (:func:`ins_error_matrices`) at zero velocity with the height held,
    reduced to attitude, horizontal velocity and position.

    Outputs: attitude errors (3, rad), horizontal velocity errors (2, m/s), north and
    east position errors (2, m). Inputs: gyro errors (3, rad/s), accelerometer errors
    (3, m/s^2), body axes, attitude ``q_bn``.
    """
    import control   # lazy: python-control takes ~1 s to import (start-up of every command)
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
