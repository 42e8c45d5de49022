"""The continuous error model of the integrated-navigation filter, in numpy: the state
names of every configuration and F, G as the definition that the C filter
(``csrc/est/gf_ins_*.c``, ``gf_ins_model``) implements (the tests compare the two), and the
model as a python-control system for outage predictions and analysis.

Convention C_b^n(computed) = (I - [phi x]) C_b^n(true); position and velocity errors are
computed - true; sensor states are true - estimated (Titterton & Weston ch. 12.3).
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.nav.earth import WGS84, gravity, quat_to_dcm, radii, skew

__all__ = ["INS_STATES", "ins_state_names", "ins_error_matrices", "ins_error_model"]

INS_STATES = ("dv_E", "dv_N", "dv_U", "dL", "dlon", "dh", "phi_E", "phi_N", "phi_U",
              "bg_x", "bg_y", "bg_z", "ba_x", "ba_y", "ba_z")
"""Error states of the integrated navigation filter (seed 004 eq. 17, its order): velocity
(m/s), latitude and longitude (rad), height (m), attitude (rad), gyro bias (rad/s) and
accelerometer bias (m/s^2) not yet compensated; optional blocks follow (see
:func:`ins_state_names`)."""


def ins_state_names(scale_states: bool = False, baro_state: bool = False,
                    odo_state: bool = False, odo_mount_state: bool = False, *,
                    master_mount: bool = False, master_lever: bool = False,
                    master_time_offset: bool = False, flexure: bool = False) -> tuple:
    """State names of a filter configuration (15 to 38 states, gf_ins_gnss.h order); the
    transfer-alignment blocks (issue 24) last."""
    names = list(INS_STATES)
    if scale_states:
        names += ["sg_x", "sg_y", "sg_z", "sa_x", "sa_y", "sa_z"]
    if baro_state:
        names += ["b_baro"]
    if odo_state:
        names += ["k_odo"]
    if odo_mount_state:
        names += ["odo_pitch", "odo_heading"]
    if master_mount:
        names += ["mount_heading", "mount_pitch", "mount_roll"]
    if master_lever:
        names += ["lever_x", "lever_y", "lever_z"]
    if master_time_offset:
        names += ["time_offset"]
    if flexure:
        names += ["flex_heading", "flex_pitch", "flex_roll", "flex_heading_rate", "flex_pitch_rate",
                  "flex_roll_rate"]
    return tuple(names)


#: the flexure's b = FLEX_BETA_TAU / tau (1/s): the second-order Markov model of the
#: transfer-alignment literature (Kain & Cloutier 1989), gf_ins_gnss.h
FLEX_BETA_TAU = 2.146


def _transfer_flags(kwargs: dict) -> dict:
    return {k: bool(kwargs.get(k, False)) for k in ("master_mount", "master_lever",
                                                    "master_time_offset", "flexure")}


def ins_error_matrices(lat_rad: float, h_m: float, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s,
                       *, scale_states: bool = False, baro_state: bool = False,
                       odo_state: bool = False, odo_mount_state: bool = False, tau_s=None,
                       master_mount: bool = False, master_lever: bool = False,
                       master_time_offset: bool = False, flexure: bool = False):
    """The continuous error model of the integrated-navigation filter, x' = F x + G w:
    **the definition** that the C filter (csrc/est/gf_ins_*.c) implements; tests compare
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
        transfer alignment: mounting, lever arm, time offset random constants; flexure per
        axis f' = r, r' = -b^2 f - 2 b r + w, b = 2.146 / tau_s["flexure"]

    Parameters
    ----------
    lat_rad, h_m, v_enu_m_s, q_bn : the navigation state (rad, m, m/s, q_b^n)
    f_b_m_s2, w_ib_b_rad_s : specific force and angular rate, body axes
    scale_states, baro_state, odo_state, odo_mount_state : the optional blocks
    master_mount, master_lever, master_time_offset, flexure : the transfer-alignment blocks
    tau_s : dict of correlation times (s) by block name ("bg", "ba", "sg", "sa", "baro",
        "odo", "odo_mount"; missing or 0: random constant; "flexure": its correlation time,
        required with ``flexure``)

    Returns
    -------
    F : (n, n); G : (n, n - 3) with noise inputs [accelerometer white (3), gyro white (3),
    one driving noise per sensor state], in that order.
    """
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
    names = ins_state_names(scale_states, baro_state, odo_state, odo_mount_state,
                            master_mount=master_mount, master_lever=master_lever,
                            master_time_offset=master_time_offset, flexure=flexure)
    n = len(names)
    ix = {k: names.index(k) for k in names}
    V, P, A = slice(0, 3), slice(3, 6), slice(6, 9)
    F = np.zeros((n, n))
    # attitude
    F[A, A] = -skew(w_ie + w_en)
    F[A, V] = Jen_v
    F[A, P] = Jie_p + Jen_p
    F[A, 9:12] = -C
    # velocity
    F[V, A] = skew(C @ fb)
    F[V, V] = -skew(2 * w_ie + w_en) + skew(v) @ Jen_v
    F[V, P] = skew(v) @ (2 * Jie_p + Jen_p)
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
    if flexure:
        t = float(tau.pop("flexure", 0.0))
        if not (t > 0 and np.isfinite(t)):
            raise ValueError("flexure needs tau_s['flexure'] > 0 (its correlation time, s)")
        b = FLEX_BETA_TAU / t
        for k in range(3):
            a, r = ix["flex_heading"] + k, ix["flex_heading_rate"] + k
            F[a, r] = 1.0
            F[r, a] = -b * b
            F[r, r] = -2.0 * b
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
    import control   # lazy: python-control takes ~1 s to import (start-up of every command)
    F, G = ins_error_matrices(lat_rad, h_m, v_enu_m_s, q_bn, f_b_m_s2, w_ib_b_rad_s, **kwargs)
    names = ins_state_names(kwargs.get("scale_states", False), kwargs.get("baro_state", False),
                            kwargs.get("odo_state", False), kwargs.get("odo_mount_state", False),
                            **_transfer_flags(kwargs))
    n = len(names)
    inputs = ["w_a_x", "w_a_y", "w_a_z", "w_g_x", "w_g_y", "w_g_z"] + [f"w_{k}" for k in names[9:]]
    return control.ss(F, G, np.eye(n), np.zeros((n, n - 3)), inputs=inputs,
                      outputs=list(names), states=list(names))
