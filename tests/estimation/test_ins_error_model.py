"""The error model of the integrated navigator: its definition
(gfins_fmi.estimation.error_model.ins_error_matrices, numpy from Titterton & Weston ch.
12.3) against a numerical linearisation of the navigation equations, the C filter's
matrices against the definition (gf_ins_error_model), the shared navigation blocks of C
gf_ins_model against it at random moving states (1e-12 relative to each block's largest
entry: the same closed forms in different orders), and the strapdown model as its
reduction.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

import gfins_fmi as gf
from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.analysis.strapdown_errors import sins_error_model
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.error_model import ins_error_matrices
from gfins_fmi.nav import earth
from support.truth import E2, OMEGA, gravity, radii

DEG = np.pi / 180
UG = 9.80665e-6
DEG_H = DEG / 3600


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rot(v):
    return expm(skew(np.asarray(v, float)))


def nav_rates(C, v, L, h, f_b, w_b):
    """Continuous navigation equations (ENU, WGS-84): C', v', (L', lon', h')."""
    RM, RN = radii(L)
    w_ie = np.array([0, OMEGA * np.cos(L), OMEGA * np.sin(L)])
    w_en = np.array([-v[1] / (RM + h), v[0] / (RN + h), v[0] * np.tan(L) / (RN + h)])
    Cd = C @ skew(w_b) - skew(w_ie + w_en) @ C
    vd = C @ f_b - np.cross(2 * w_ie + w_en, v) + np.array([0, 0, -gravity(L, h)])
    pd = np.array([v[1] / (RM + h), v[0] / ((RN + h) * np.cos(L)), v[2]])
    return Cd, vd, pd


STATES = [  # (lat, h, v, euler heading/pitch/roll, f_b, w_b): several representative states
    (0.6, 120.0, (12.0, -7.0, 0.4), (0.3, 0.05, -0.02), (0.8, 1.5, 9.7), (0.01, -0.02, 0.15)),
    (-0.9, 2500.0, (-150.0, 80.0, -3.0), (2.5, -0.2, 0.3), (-2.0, 0.4, 11.0), (0.2, 0.1, -0.3)),
    (0.05, 0.0, (0.0, 0.0, 0.0), (5.0, 0.0, 0.0), (0.0, 0.0, 9.78), (0.0, 0.0, 0.0)),
]


def _filter_at(lat, h, v, euler, **cfg_kw):
    q = gf.euler_to_quat(np.array(euler))
    cfg = FilterConfig(imu=gf.ImuNoise(gyro_arw_deg_sqrt_h=0.1, accel_vrw_ug_sqrt_hz=50,
                                       gyro_bias_instability_deg_h=1, gyro_correlation_time_s=300,
                                       accel_bias_instability_ug=100, accel_correlation_time_s=600),
                       **cfg_kw)
    return IntegratedNavigator(cfg, InitialState(gf.NavState(q, np.array(v, float), lat, 0.3, h)))


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("opts", [{}, {"scale_factors": True, "baro_bias": True, "odometer_scale": True,
                                       "odometer_mount": True, "odometer_mount_tau_s": 900.0,
                                       "gyro_scale_tau_s": 5100.0, "accel_scale_std": 7e-4,
                                       "accel_scale_tau_s": 4700.0, "odometer_scale_tau_s": 6100.0},
                                  {"scale_factors": True, "baro_bias": True, "odometer_scale": True,
                                   "odometer_mount": True, "odometer_mount_tau_s": 900.0,
                                   "gyro_scale_tau_s": 5100.0, "accel_scale_std": 7e-4,
                                   "accel_scale_tau_s": 4700.0, "odometer_scale_tau_s": 6100.0,
                                   "master_mount": True, "master_lever": True, "master_time_offset": True,
                                   "flexure": True, "flexure_tau_s": 0.8, "flexure_std_rad": 2e-3}],
                         ids=["15", "25", "38"])
def test_c_error_model_is_the_definition(state, opts):
    """The C filter's F and G equal error_models.ins_error_matrices (the definition), the
    transfer-alignment blocks (random constants, the flexure's second-order Markov) too."""
    lat, h, v, euler, fb, wb = state
    nav = _filter_at(lat, h, v, euler, **opts)
    F_c, G_c, q_c = nav.error_model(fb, wb)
    tau = {"bg": 300.0, "ba": 600.0}
    if opts:
        tau.update({"baro": 3600.0, "odo_mount": 900.0, "sg": 5100.0, "sa": 4700.0, "odo": 6100.0})
    transfer = {k: bool(opts.get(k)) for k in ("master_mount", "master_lever", "master_time_offset",
                                               "flexure")}
    if transfer["flexure"]:
        tau["flexure"] = opts["flexure_tau_s"]
    F_py, G_py = ins_error_matrices(lat, h, v, list(nav._f.nav.q_bn), fb, wb,
                                    scale_states=bool(opts), baro_state=bool(opts),
                                    odo_state=bool(opts), odo_mount_state=bool(opts), tau_s=tau,
                                    **transfer)
    # same formulas evaluated in a different order: round-off relative to each entry's
    # terms (largest products ~ 1e1; entries as small as 1e-13 rad/(m s))
    scale = np.maximum(np.abs(F_py), 1e-300)
    assert np.all(np.abs(F_c - F_py) <= 1e-12 * scale + 1e-20), \
        np.argwhere(np.abs(F_c - F_py) > 1e-12 * scale + 1e-20)
    np.testing.assert_allclose(G_c, G_py, rtol=0, atol=1e-15)
    # noise intensities: ARW^2, VRW^2 (= ASD^2 / 2), 2 sigma^2 / tau
    arw, vrw = 0.1 * DEG / 60, 50 * UG / np.sqrt(2)
    np.testing.assert_allclose(q_c[:6], [vrw ** 2] * 3 + [arw ** 2] * 3, rtol=1e-12)
    np.testing.assert_allclose(q_c[6:9], 2 * (1 * DEG_H) ** 2 / 300, rtol=1e-12)
    np.testing.assert_allclose(q_c[9:12], 2 * (100 * UG) ** 2 / 600, rtol=1e-12)
    if opts:
        # every sensor state's own 2 sigma^2 / tau (0: a random constant, tau = 0), from
        # the configuration's values, which differ from block to block
        c = nav.config
        gm = [(c.gyro_scale_std, c.gyro_scale_tau_s)] * 3 + [(c.accel_scale_std, c.accel_scale_tau_s)] * 3 \
            + [(c.baro_bias_std_m, c.baro_bias_tau_s), (c.odometer_scale_std, c.odometer_scale_tau_s)] \
            + [(c.odometer_mount_std_rad, c.odometer_mount_tau_s)] * 2
        want = [2 * s * s / tau if tau > 0 else 0.0 for s, tau in gm]
        np.testing.assert_allclose(q_c[12:22], want, rtol=1e-12, atol=0)
    if transfer["flexure"]:   # E[w w] = 4 b^3 sigma^2 on the rates, none on the angles
        b = 2.146 / 0.8
        np.testing.assert_allclose(q_c[-6:], [0.0] * 3 + [4 * b ** 3 * 4e-6] * 3, rtol=1e-12)
        np.testing.assert_array_equal(q_c[-13:-6], 0.0)      # random constants


@pytest.mark.parametrize("state", STATES[:2])
def test_definition_matches_numerical_linearisation(state):
    """ins_error_matrices against finite differences of the navigation equations: perturb
    the truth by each error state, difference the rates of nominal and truth."""
    lat, h, v, euler, fb, wb = state
    v = np.array(v, float)
    fb, wb = np.array(fb, float), np.array(wb, float)
    C = gf.euler_to_quat(np.array(euler))
    Ct = np.array(earth.quat_to_dcm(C))
    F, _ = ins_error_matrices(lat, h, v, C, fb, wb)
    Cd0, vd0, pd0 = nav_rates(Ct, v, lat, h, fb, wb)

    def error_rate(dx):
        """d/dt of the error of a nominal = truth (+) dx, to first order (per unit dx)."""
        phi = dx[6:9]
        Cn = rot(-phi) @ Ct                      # C_nominal = (I - [phi x]) C_true
        vn, Ln, lonn_d, hn = v + dx[0:3], lat + dx[3], dx[4], h + dx[5]
        del lonn_d
        # the nominal's compensated sensors carry the bias residuals: w + b_g, f + b_a
        Cdn, vdn, pdn = nav_rates(Cn, vn, Ln, hn, fb + dx[12:15], wb + dx[9:12])
        # phi' from C_n C_t^T = exp(-[phi x]): d/dt = Cdn Ct^T + Cn Cd0^T = -[phi' x]
        M = Cdn @ Ct.T + Cn @ Cd0.T
        phid = -np.array([M[2, 1], M[0, 2], M[1, 0]])
        out = np.zeros(15)
        out[0:3] = vdn - vd0
        out[3:6] = pdn - pd0
        out[6:9] = phid
        return out

    scales = np.array([0.1] * 3 + [1e-6, 1e-6, 1.0] + [1e-4] * 3 + [1e-5] * 3 + [1e-3] * 3)
    Fn = np.zeros((15, 15))
    for j in range(15):
        d = np.zeros(15)
        d[j] = scales[j]
        Fn[:, j] = (error_rate(d) - error_rate(-d)) / (2 * scales[j])
    # neglected in the definition: derivatives of the radii (relative e^2 ~ 7e-3) and of
    # gravity with latitude (dg/dL ~ 0.05 m/s^2/rad), and second-order terms of the
    # central differences (scales^2); so entries agree to 1% or within those terms
    tol = 1e-2 * np.abs(F) + 1e-2 * np.abs(Fn)
    tol[2, 3] += 0.06                 # dg/dL
    # d(radius)/dL terms: |v| (dR/dL) / (R + h)^2 / cos L, dR/dL <= 3 R e^2 / 2
    RM, _ = radii(lat)
    tol[:, 3] += np.linalg.norm(v) * 1.5 * E2 * RM / (RM + h) ** 2 / np.cos(lat)
    bad = np.argwhere(np.abs(Fn - F) > tol + 1e-12)
    assert bad.size == 0, [(int(i), int(j), F[i, j], Fn[i, j]) for i, j in bad]


def test_sins_error_model_is_the_reduction():
    """The at-rest 7-state model is the 15-state model reduced (no second definition)."""
    q = gf.euler_to_quat(np.array([0.4, 0.02, -0.03]))
    sys = sins_error_model(0.7, q, 50.0)
    RM, RN = radii(0.7)
    g = gravity(0.7, 50.0)
    # the classical at-rest form, written out (Titterton & Weston eq. 12.x)
    A = np.zeros((7, 7))
    w_ie = np.array([0, OMEGA * np.cos(0.7), OMEGA * np.sin(0.7)])
    A[0:3, 0:3] = -skew(w_ie)
    A[0, 4] = -1 / (RM + 50)
    A[1, 3] = 1 / (RN + 50)
    A[1, 5] = -OMEGA * np.sin(0.7)
    A[2, 3] = np.tan(0.7) / (RN + 50)
    A[2, 5] = OMEGA * np.cos(0.7)
    A[3:5, 0:3] = skew([0, 0, g])[0:2]
    A[3:5, 3:5] = -2 * skew(w_ie)[0:2, 0:2]
    A[5, 4] = 1 / (RM + 50)
    A[6, 3] = 1 / ((RN + 50) * np.cos(0.7))
    # f^n = C C^T [0, 0, g] carries ~1e-16 g of horizontal round-off
    np.testing.assert_allclose(np.asarray(sys.A), A, rtol=1e-9, atol=1e-15)


def test_nav_blocks_equal_the_definition():
    rng = np.random.default_rng(11)
    for _ in range(25):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        v = rng.uniform(-250, 250, 3)
        lat, h = rng.uniform(-1.3, 1.3), rng.uniform(-100, 10000)
        fb = rng.uniform(-30, 30, 3)
        F_def, _ = ins_error_matrices(lat, h, v, q, fb, np.zeros(3))
        # definition order: dv 0-2, dp 3-5, phi 6-8; ours here: phi 0, dv 3, dp 6 in a 9 x 9
        F = np.full(81, np.nan)
        st = lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), lat, h, ptr(fb, 3), 9, 0, 3, 6,
                                        ptr(F, 81))
        assert st == lib.GF_OK
        F = F.reshape(9, 9)
        perm = [6, 7, 8, 0, 1, 2, 3, 4, 5]
        want = F_def[np.ix_(perm, perm)]
        for r in range(3):
            for c in range(3):
                blk, ref = F[3 * r:3 * r + 3, 3 * c:3 * c + 3], want[3 * r:3 * r + 3, 3 * c:3 * c + 3]
                scale = max(np.abs(ref).max(), 1e-300)
                np.testing.assert_allclose(blk, ref, rtol=0, atol=1e-12 * scale,
                                           err_msg=f"block ({r}, {c})")


def test_bad_arguments():
    q, v, f = np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([0, 0, 9.8])
    F = np.zeros(81)
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 2.0, 0.0, ptr(f, 3), 9, 0, 3, 6,
                                      ptr(F, 81)) == lib.GF_ERR_BAD_PARAMETER
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 0.2, 0.0, ptr(f, 3), 9, 0, 1, 6,
                                      ptr(F, 81)) == lib.GF_ERR_BAD_SIZE
    assert lib.gf_ins_nav_error_model(ptr(q, 4), ptr(v, 3), 0.2, 0.0, ffi.NULL, 9, 0, 3, 6,
                                      ptr(F, 81)) == lib.GF_ERR_NULL_POINTER


def test_definition_refuses_the_poles_and_decays_each_block_alone():
    """ins_error_matrices: a latitude at or beyond +-90 deg refused; each block's
    correlation time sets the decay -1/tau of its own states only (a block without one is
    a random constant: 0 on its diagonal), so a block cannot spill into its neighbour."""
    q, v, fb, wb = [1.0, 0, 0, 0], np.zeros(3), np.array([0.1, 0.2, 9.8]), np.array([0.01, 0.02, 0.03])
    for lat in (math.pi / 2, -1.6, 3.0):
        with pytest.raises(ValueError, match="lat_rad must be inside"):
            ins_error_matrices(lat, 0.0, v, q, fb, wb)
    names = ["bg", "ba", "sg", "sa", "baro", "odo", "odo_mount"]
    for given in names:
        F, _ = ins_error_matrices(0.6, 10.0, v, q, fb, wb, scale_states=True, baro_state=True,
                                  odo_state=True, odo_mount_state=True, tau_s={given: 50.0})
        diag = np.diag(F)[9:]
        k0 = {"bg": 0, "ba": 3, "sg": 6, "sa": 9, "baro": 12, "odo": 13, "odo_mount": 14}[given]
        k1 = k0 + {"baro": 1, "odo": 1, "odo_mount": 2}.get(given, 3)
        want = np.zeros(len(diag))
        want[k0:k1] = -1.0 / 50.0
        np.testing.assert_array_equal(diag, want, err_msg=given)
