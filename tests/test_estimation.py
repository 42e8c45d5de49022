"""Integrated navigation (csrc/gf_ins_gnss, gfins_fmi.estimation) and the Kalman-engine
pieces it added (structured predict, unscented transform, RTS step, chi-square gate).

Truth: numpy re-derivations of each formula (not the code under test), a numerical
linearisation of the navigation equations for the error model's definition, exact sensor
outputs of the closed-form vehicle (gf_vehicle, checked against the independent Python
trajectory generator in test_vehicle.py) and statistics of seeded noise.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.stats import chi2

import gfins_fmi as gf
from gfins_fmi.nav import earth
from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.estimation.error_model import ins_error_matrices, ins_state_names
from gfins_fmi.analysis.strapdown_errors import sins_error_model
from gfins_fmi.estimation import FilterConfig, FilterError, InitialState, IntegratedNavigator

DEG = np.pi / 180
UG = 9.80665e-6
DEG_H = DEG / 3600
OMEGA = 7.292115e-5


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rot(v):
    return expm(skew(np.asarray(v, float)))


def dcm_to_quat(C):
    """q_b^n of C_b^n (Shepperd), numpy."""
    t = np.trace(C)
    q0 = 0.5 * np.sqrt(max(1 + t, 0))
    return np.array([q0, (C[2, 1] - C[1, 2]) / (4 * q0), (C[0, 2] - C[2, 0]) / (4 * q0),
                     (C[1, 0] - C[0, 1]) / (4 * q0)])


# ---- WGS-84, written out here (the references below must not come from the code) ------
A_WGS, F_WGS = 6378137.0, 1 / 298.257223563
E2 = F_WGS * (2 - F_WGS)


def radii(L):
    q = 1 - E2 * np.sin(L) ** 2
    return A_WGS * (1 - E2) / q ** 1.5, A_WGS / np.sqrt(q)


def gravity(L, h):
    s2 = np.sin(L) ** 2
    g0 = 9.7803253359 * (1 + 0.00193185265241 * s2) / np.sqrt(1 - E2 * s2)
    m = OMEGA ** 2 * A_WGS ** 2 * A_WGS * (1 - F_WGS) / 3.986004418e14
    return g0 * (1 - 2 / A_WGS * (1 + F_WGS + m - 2 * F_WGS * s2) * h + 3 / A_WGS ** 2 * h * h)


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
                                       "odometer_mount": True, "odometer_mount_tau_s": 900.0}])
def test_c_error_model_is_the_definition(state, opts):
    """The C filter's F and G equal error_models.ins_error_matrices (the definition)."""
    lat, h, v, euler, fb, wb = state
    nav = _filter_at(lat, h, v, euler, **opts)
    F_c, G_c, q_c = nav.error_model(fb, wb)
    tau = {"bg": 300.0, "ba": 600.0}
    if opts:
        tau.update({"baro": 3600.0, "odo_mount": 900.0})
    F_py, G_py = ins_error_matrices(lat, h, v, list(nav._f.nav.q_bn), fb, wb,
                                    scale_states=bool(opts), baro_state=bool(opts),
                                    odo_state=bool(opts), odo_mount_state=bool(opts), tau_s=tau)
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


# ---- the Kalman engine ---------------------------------------------------------------------

def _kf(P):
    n = P.shape[0]
    kf = ffi.new("gf_kalman *")
    x0 = np.zeros(n)
    assert lib.gf_kalman_init(kf, n, ptr(x0), ptr(np.ascontiguousarray(P))) == lib.GF_OK
    return kf


def _P(kf, n):
    return np.frombuffer(ffi.buffer(kf.P), dtype=float)[:n * n].reshape(n, n).copy()


def _random_spd(rng, n):
    B = rng.normal(size=(n, n))
    return B @ B.T + n * np.eye(n)


def test_structured_predict_equals_dense(rng):
    n = 15
    P = _random_spd(rng, n)
    A = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.3)
    q1, q2 = rng.random(n), rng.random(n)
    kf = _kf(P)
    assert lib.gf_kalman_predict_sparse(kf, ptr(np.ascontiguousarray(A)), ptr(q1), ptr(q2)) == lib.GF_OK
    Phi = np.eye(n) + A
    ref = Phi @ (P + np.diag(q1)) @ Phi.T + np.diag(q2)
    np.testing.assert_allclose(_P(kf, n), ref, rtol=1e-13, atol=1e-12 * np.abs(ref).max())
    A[2, 3] = np.inf
    before = _P(kf, n)
    assert lib.gf_kalman_predict_sparse(kf, ptr(np.ascontiguousarray(A)), ptr(q1), ptr(q2)) == \
        lib.GF_ERR_NONFINITE_INPUT
    assert np.array_equal(_P(kf, n), before)


def test_joseph_update_and_gate(rng):
    """The factored Joseph update equals the textbook product form; a gated update
    leaves the filter unchanged."""
    n, m = 15, 3
    P = _random_spd(rng, n)
    H = rng.normal(size=(m, n))
    R = np.diag(rng.random(m) + 0.5)
    r = rng.normal(size=m)
    kf = _kf(P)
    nis = ffi.new("double *")
    acc = ffi.new("int *")
    assert lib.gf_kalman_update_gated(kf, m, ptr(r), ptr(np.ascontiguousarray(H)), ptr(R), 0.0, nis, acc) == lib.GF_OK
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    IKH = np.eye(n) - K @ H
    ref = IKH @ P @ IKH.T + K @ R @ K.T
    np.testing.assert_allclose(_P(kf, n), ref, rtol=1e-11, atol=1e-11 * np.abs(ref).max())
    np.testing.assert_allclose(np.frombuffer(ffi.buffer(kf.x), float)[:n], K @ r, rtol=1e-11, atol=1e-13)
    assert acc[0] == 1 and nis[0] == pytest.approx(r @ np.linalg.solve(S, r), rel=1e-12)
    kf2 = _kf(P)
    assert lib.gf_kalman_update_gated(kf2, m, ptr(r * 100), ptr(np.ascontiguousarray(H)), ptr(R), 5.0, nis, acc) == lib.GF_OK
    assert acc[0] == 0 and nis[0] > 5.0
    assert np.array_equal(_P(kf2, n), P)


def test_unscented_transform_against_numpy(rng):
    n = 6
    P = _random_spd(rng, n) * 1e-2
    w = ffi.new("gf_ukf_weights *")
    alpha, beta, kappa = 0.5, 2.0, 0.0
    assert lib.gf_ukf_weights_init(w, n, alpha, beta, kappa) == lib.GF_OK
    lam = alpha ** 2 * (n + kappa) - n                      # seed 004 below eq. 28
    assert w.gamma == pytest.approx(np.sqrt(n + lam))
    assert w.wm0 == pytest.approx(lam / (n + lam))
    assert w.wc0 == pytest.approx(lam / (n + lam) + 1 - alpha ** 2 + beta)
    assert w.wi == pytest.approx(1 / (2 * (n + lam)))
    kf = _kf(P)
    X = np.empty((2 * n + 1, n))
    assert lib.gf_ukf_sigma_points(kf, w, ptr(X)) == lib.GF_OK
    # the points reproduce mean and covariance exactly (any square root of P)
    Wm = np.r_[w.wm0, np.full(2 * n, w.wi)]
    Wc = np.r_[w.wc0, np.full(2 * n, w.wi)]
    np.testing.assert_allclose(Wm @ X, 0, atol=1e-15)
    np.testing.assert_allclose((X * Wc[:, None]).T @ X - (1 - alpha ** 2 + beta) * 0, P, rtol=1e-12)
    # a linear measurement: the UKF update equals the Kalman update
    H = rng.normal(size=(2, n))
    R = np.diag([0.3, 0.2])
    z = rng.normal(size=2)
    Z = X @ H.T
    nis = ffi.new("double *")
    acc = ffi.new("int *")
    assert lib.gf_ukf_update(kf, w, ptr(X), 2, ptr(Z), ptr(z), ptr(R), 0.0, nis, acc) == lib.GF_OK
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    np.testing.assert_allclose(_P(kf, n), P - K @ S @ K.T, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(np.frombuffer(ffi.buffer(kf.x), float)[:n], K @ z, rtol=1e-10, atol=1e-14)
    # a nonlinear time update: mean and covariance of y = x + 0.5 x0^2 e0 through the points
    kf3 = _kf(P)
    Y = X.copy()
    Y[:, 0] += 0.5 * X[:, 0] ** 2
    assert lib.gf_ukf_predict(kf3, w, ptr(Y), ffi.NULL) == lib.GF_OK
    x3 = np.frombuffer(ffi.buffer(kf3.x), float)[:n]
    assert x3[0] == pytest.approx(0.5 * P[0, 0], rel=1e-12)     # E[x0^2]/2, exact for Gaussians


def test_rts_step_against_numpy(rng):
    n = 5
    Pp, Ps_next = _random_spd(rng, n), _random_spd(rng, n)
    Phi = np.eye(n) + 0.1 * rng.normal(size=(n, n))
    Q = np.diag(rng.random(n))
    Pprior = Phi @ Pp @ Phi.T + Q
    xp, xprior, xs_next = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    xs, Ps = np.empty(n), np.empty((n, n))
    assert lib.gf_kalman_rts_step(n, ptr(Pp), ptr(xp), ptr(np.ascontiguousarray(Phi)), ptr(Pprior), ptr(xprior),
                                  ptr(Ps_next), ptr(xs_next), ptr(xs), ptr(Ps)) == lib.GF_OK
    Ag = Pp @ Phi.T @ np.linalg.inv(Pprior)
    np.testing.assert_allclose(xs, xp + Ag @ (xs_next - xprior), rtol=1e-12)
    np.testing.assert_allclose(Ps, Pp + Ag @ (Ps_next - Pprior) @ Ag.T, rtol=1e-11)


@pytest.mark.parametrize("m", [1, 2, 3, 6])
@pytest.mark.parametrize("p", [0.9, 0.99, 0.9999])
def test_chi2_gate_quantile(m, p):
    q = ffi.new("double *")
    assert lib.gf_chi2_quantile(m, p, q) == lib.GF_OK
    # Newton on the closed-form distribution: converged to round-off
    assert q[0] == pytest.approx(chi2.ppf(p, m), rel=1e-10)


# ---- the filter on a simulated vehicle -------------------------------------------------------

class Rec:
    """A minimal record (the io records have the same fields)."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


def drive(duration_s=120.0, fine=0.001, step=10, seed_profile=0):
    """Exact truth at `fine` and IMU increments summed over `step` fine intervals."""
    from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle
    prof = VehicleProfile(lat0_rad=0.52, speed0_m_s=8.0, segments=[
        Segment(10), Segment(15, dspeed_m_s=4, dheading_rad=np.pi / 2), Segment(20),
        Segment(10, dheading_rad=-np.pi), Segment(25, dspeed_m_s=-3), Segment(12, dheading_rad=1.0)])
    tr = simulate_vehicle(prof, duration_s, fine)
    n = (len(tr.t_s) - 1) // step
    dth = tr.dtheta_rad[:n * step].reshape(n, step, 3).sum(1)
    dv = tr.dv_m_s[:n * step].reshape(n, step, 3).sum(1)
    imu = Rec(t_s=tr.t_s[step::step][:n].copy(), gyro=dth, accel=dv, kind="increments")
    return tr, imu


def antenna(tr, k, lever):
    """Antenna position (lat, lon, h) and velocity (ENU) of the truth rows k, numpy."""
    lat, h = tr.lat_rad[k], tr.h_m[k]
    C = np.array(earth.quat_to_dcm(tr.q_bn[k]))
    cl = C @ lever
    RM, RN = radii(lat)
    pos = np.c_[lat + cl[:, 1] / (RM + h), tr.lon_rad[k] + cl[:, 0] / ((RN + h) * np.cos(lat)), h + cl[:, 2]]
    w_ie = np.c_[np.zeros_like(lat), OMEGA * np.cos(lat), OMEGA * np.sin(lat)]
    w_eb = tr.gyro_rad_s[k] - np.einsum("kji,kj->ki", C, w_ie)
    vel = tr.v_n_m_s[k] + np.einsum("kij,kj->ki", C, np.cross(w_eb, lever))
    return pos, vel


def gnss_record(tr, k, lever=np.zeros(3), std=(0.01, 0.01, 0.02), vstd=0.005):
    pos, vel = antenna(tr, k, lever)
    m = len(k)
    return Rec(t_s=tr.t_s[k].copy(), lat_rad=pos[:, 0].copy(), lon_rad=pos[:, 1].copy(), h_m=pos[:, 2].copy(),
               pos_std_m=np.tile(std, (m, 1)), vel_enu_m_s=vel, vel_std_m_s=np.full((m, 3), vstd))


def quiet_config(**kw):
    noise = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.01, accel_vrw_ug_sqrt_hz=10, gyro_bias_instability_deg_h=0.1,
                        gyro_correlation_time_s=3600, accel_bias_instability_ug=20,
                        accel_correlation_time_s=3600)
    return FilterConfig(imu=noise, **kw)


def start(tr, config, **kw):
    return IntegratedNavigator(config, InitialState(gf.NavState.from_trajectory(tr, 0), **kw))


def pos_error_m(sol_lat, sol_lon, sol_h, lat, lon, h):
    RM, RN = radii(lat)
    return np.c_[(sol_lon - lon) * (RN + h) * np.cos(lat), (sol_lat - lat) * (RM + h), sol_h - h]


@pytest.fixture(scope="module")
def exact_drive():
    return drive()


@pytest.mark.parametrize("filt", ["ekf", "ukf"])
def test_exact_sensors_at_odd_times(exact_drive, filt):
    """Exact IMU, exact GNSS valid 3 ms after IMU samples (not on the IMU grid), with a
    lever arm: every residual is at the mechanization's truncation level (the IMU interval
    is split at the time of validity). Using the next IMU sample instead would leave
    |v| * 7 ms ~ 7 cm."""
    tr, imu = exact_drive
    lever = np.array([0.4, 1.2, 1.6])
    k = np.arange(1003, len(tr.t_s), 1000)          # 1 Hz, 3 ms after every 10 ms IMU sample
    gnss = gnss_record(tr, k, lever)
    nav = start(tr, quiet_config(filter=filt, gnss_lever_arm_m=lever), position_std_m=0.05,
                velocity_std_m_s=0.01, attitude_std_rad=1e-4)
    sol = nav.run(imu, gnss)
    inn = sol.innovations
    assert len(inn) == 2 * len(k) and np.all(inn["status"] == 0)
    pos_r = inn[inn["type"] == lib.GF_INS_MEAS_GNSS_POS]["r"]
    vel_r = inn[inn["type"] == lib.GF_INS_MEAS_GNSS_VEL]["r"]
    # mechanization of exact increments at 100 Hz during turns: ~1e-4 m, 1e-4 m/s
    assert np.abs(pos_r).max() < 2e-3, np.abs(pos_r).max()
    assert np.abs(vel_r).max() < 1e-3, np.abs(vel_r).max()
    e = pos_error_m(sol.lat_rad, sol.lon_rad, sol.h_m, tr.lat_rad[10::10], tr.lon_rad[10::10], tr.h_m[10::10])
    assert np.abs(e).max() < 5e-3



@pytest.mark.parametrize("m", [2, 4])
def test_subsample_groups_exact_drive(exact_drive, m):
    """subsamples = m: the mechanization takes groups of m increments between measurement
    and propagation instants (one output row per navigation update). Truth is the exact
    drive: the rows fall on IMU sample times and every GNSS instant still splits its
    interval (residuals at the mechanization's truncation level, as sample by sample);
    the result does not depend on how the record is cut into C calls (chunks are rounded
    to multiples of m, groups follow the filter's sample count); and grouping changes the
    solution by less than the mechanization error itself."""
    tr, imu = exact_drive
    lever = np.array([0.4, 1.2, 1.6])
    k = np.arange(1003, len(tr.t_s), 1000)          # 1 Hz, 3 ms after every 10 ms IMU sample
    gnss = gnss_record(tr, k, lever)

    prop_s = 0.2          # 20 samples: a multiple of m, so propagation ends a group

    def run(sub, chunk=200_000):
        nav = start(tr, quiet_config(gnss_lever_arm_m=lever, subsamples=sub, propagation_interval_s=prop_s),
                    position_std_m=0.05, velocity_std_m_s=0.01, attitude_std_rad=1e-4)
        return nav.run(imu, gnss, chunk=chunk)

    one, grouped, chunked = run(1), run(m), run(m, chunk=777)
    n = len(imu.t_s)
    # one row per group of m, except the group holding a GNSS instant: its m samples are
    # stepped one by one (m rows instead of 1)
    assert len(grouped.t_s) == n // m + (m - 1) * len(k)
    assert np.all(np.diff(grouped.t_s) > 0) and np.all(np.isin(grouped.t_s, imu.t_s))
    inn = grouped.innovations
    assert len(inn) == 2 * len(k) and np.all(inn["status"] == 0)
    # mechanization truncation during the turns grows with the update interval (10, 20,
    # 40 ms): measured max position residual 0.38 / 0.89 / 3.02 mm, velocity 0.48 / 0.49 /
    # 1.12 mm/s, position error against the truth 0.38 / 0.89 / 3.03 mm for m = 1 / 2 / 4;
    # bounds 1.5x the measured
    pos_bound, vel_bound = {2: (1.4e-3, 0.8e-3), 4: (4.5e-3, 1.7e-3)}[m]
    assert np.abs(inn[inn["type"] == lib.GF_INS_MEAS_GNSS_POS]["r"]).max() < pos_bound
    assert np.abs(inn[inn["type"] == lib.GF_INS_MEAS_GNSS_VEL]["r"]).max() < vel_bound
    row = np.rint(grouped.t_s / 0.001).astype(int)   # truth rows at the solution's times
    e = pos_error_m(grouped.lat_rad, grouped.lon_rad, grouped.h_m, tr.lat_rad[row], tr.lon_rad[row], tr.h_m[row])
    assert np.abs(e).max() < pos_bound
    # the same rows of the sample-by-sample solution differ by that truncation too
    idx = np.searchsorted(one.t_s, grouped.t_s)
    assert np.array_equal(one.t_s[idx], grouped.t_s)
    d = pos_error_m(grouped.lat_rad, grouped.lon_rad, grouped.h_m, one.lat_rad[idx], one.lon_rad[idx], one.h_m[idx])
    assert np.abs(d).max() < pos_bound
    # chunked equals whole, bit for bit
    for name in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors"):
        np.testing.assert_array_equal(getattr(chunked, name), getattr(grouped, name), err_msg=name)
    # ZUPT needs the detector per sample: the samples are stepped one by one
    zu = start(tr, quiet_config(subsamples=m, zupt=True)).run(imu)
    assert len(zu.t_s) == n
    # a NaN in the second sample of a group: reported at its own index; the partial
    # solution holds the groups before it and the group's first sample, stepped alone
    acc = imu.accel.copy()
    acc[1001, 2] = np.nan
    with pytest.raises(FilterError, match="IMU sample 1001") as ei:
        start(tr, quiet_config(subsamples=m, propagation_interval_s=prop_s)).run(
            Rec(t_s=imu.t_s, gyro=imu.gyro, accel=acc, kind="increments"), chunk=600)
    assert ei.value.index == 1001 and len(ei.value.partial) == 1000 // m + 1
    assert ei.value.partial.t_s[-1] == imu.t_s[1000]


def test_subsamples_config_is_checked():
    with pytest.raises(ValueError, match="subsamples must be an integer in 1..4"):
        quiet_config(subsamples=5)
    with pytest.raises(ValueError, match="needs input='increments'"):
        quiet_config(subsamples=2, input="rates")


def test_reported_position_std_is_in_metres_on_both_axes(exact_drive):
    """The output's position std (east, north, up in m) converts the latitude and
    longitude variances with the meridian and prime-vertical radii; at the first rows,
    before the first covariance propagation, it is the initial std itself on every axis.
    Measured: equal to the last bit; tolerance 1e-9 relative (the conversions to rad and
    back are a few roundings). R_N for R_M would put the north std 0.51 % off here."""
    tr, imu = exact_drive
    nav = start(tr, quiet_config(), position_std_m=0.05, velocity_std_m_s=0.01,
                attitude_std_rad=1e-4)
    sol = nav.run(imu)
    np.testing.assert_allclose(sol.std[:3, 3:6], 0.05, rtol=1e-9, atol=0)


def test_velocity_variance_grows_by_the_vrw_between_propagations(exact_drive):
    """Between two covariance propagations (T = 0.1 s) the velocity variance of each
    axis grows by VRW^2 T (the discrete white-noise integral; the trapezoidal rule gives
    exactly that for a state with negligible dynamics over T). VRW from the one-sided
    ASD: 10 ug/sqrt(Hz) -> 10e-6 * 9.80665 / sqrt(2) m/s/sqrt(s). The other inputs of the
    velocity variance are made negligible: attitude std 1e-7 rad (g T sigma = 1e-7 m/s),
    biases 1e-12. Measured: the ratio is 1 within 1.8e-4 over the first five propagations
    (it drifts by the dynamics' cross terms, ~4e-5 a step); bound 1e-3, a 5x margin (a
    doubled Q gives 2)."""
    tr, imu = exact_drive
    T = 0.1
    cfg = FilterConfig(imu=gf.ImuNoise(accel_vrw_ug_sqrt_hz=10.0), propagation_interval_s=T)
    nav = start(tr, cfg, position_std_m=0.05, velocity_std_m_s=1e-4, attitude_std_rad=1e-7,
                gyro_bias_std_rad_s=1e-12, accel_bias_std_m_s2=1e-12)
    sol = nav.run(imu)
    var = sol.std[:, 0:3] ** 2
    rows = [np.searchsorted(sol.t_s, T * j - 1e-9) for j in range(1, 6)]   # first rows after
    steps = np.diff(np.vstack([np.full(3, 1e-8), var[rows]]), axis=0)      # each propagation
    vrw = 10e-6 * 9.80665 / np.sqrt(2.0)
    ratio = steps / (vrw ** 2 * T)
    assert np.all(np.abs(ratio - 1.0) < 1e-3), ratio

def test_lever_arm_ignored_is_seen(exact_drive):
    """The same data with the lever arm left out: the position residuals show it."""
    tr, imu = exact_drive
    lever = np.array([0.4, 1.2, 1.6])
    k = np.arange(1003, len(tr.t_s), 1000)
    sol = start(tr, quiet_config(gate_probability=None), position_std_m=0.05, velocity_std_m_s=0.01,
                attitude_std_rad=1e-4).run(imu, gnss_record(tr, k, lever))
    r = sol.innovations_of("gnss_pos")["r"]
    # first epoch: predicted (IMU) - measured (antenna) = -C l, to the mechanization's mm
    C = np.array(earth.quat_to_dcm(tr.q_bn[k[0]]))
    np.testing.assert_allclose(r[0], -C @ lever, atol=2e-3)


def test_odometer_and_nhc_exact(exact_drive):
    """Exact odometer speed at a wheel lever arm and the non-holonomic constraint of a level
    vehicle: residuals at truncation level."""
    tr, imu = exact_drive
    # the truth vehicle's IMU point moves along its heading (like a rear-axle centre): a
    # wheel point beside it (x) and below it (z) has no lateral velocity either
    lever = np.array([-0.7, 0.0, -0.4])
    k = np.arange(105, len(tr.t_s), 100)               # 10 Hz, 5 ms after IMU samples
    C = np.array(earth.quat_to_dcm(tr.q_bn[k]))
    w_ie = np.c_[np.zeros(len(k)), OMEGA * np.cos(tr.lat_rad[k]), OMEGA * np.sin(tr.lat_rad[k])]
    w_eb = tr.gyro_rad_s[k] - np.einsum("kji,kj->ki", C, w_ie)
    u = np.einsum("kji,kj->ki", C, tr.v_n_m_s[k]) + np.cross(w_eb, lever)
    odo = Rec(t_s=tr.t_s[k].copy(), speed_m_s=u[:, 1].copy(), std_m_s=np.full(len(k), 0.01))
    gnss = gnss_record(tr, np.arange(1003, len(tr.t_s), 1000))
    cfg = quiet_config(odometer_lever_arm_m=lever, nhc=True, nhc_std_m_s=0.01)
    sol = start(tr, cfg, position_std_m=0.05, velocity_std_m_s=0.01, attitude_std_rad=1e-4).run(imu, gnss, odometer=odo)
    ro, rn = sol.innovations_of("odometer"), sol.innovations_of("nhc")
    assert len(ro) == len(k) and len(rn) > 100
    # the rate in w x l is the interval's mean rate, not the rate at the instant: peak yaw
    # acceleration 2 pi^2 / 10^2 ~ 0.2 rad/s^2 x half an interval (5 ms) x |l| 1.7 m
    # = 1.7 mm/s; with margin 4 mm/s
    assert np.abs(ro["r"][:, 0]).max() < 4e-3
    assert np.abs(rn["r"][:, :2]).max() < 4e-3
    u0 = np.einsum("kji,kj->ki", C, tr.v_n_m_s[k])
    assert np.abs(u0[:, 1] - u[:, 1]).max() > 0.1   # the lever arm matters in this drive


def test_bad_input_is_refused(exact_drive):
    tr, imu = exact_drive
    k = np.arange(1003, len(tr.t_s), 1000)
    g = gnss_record(tr, k)
    nav = start(tr, quiet_config())
    g.pos_std_m = g.pos_std_m.copy()
    g.pos_std_m[2, 1] = 0.0
    with pytest.raises(ValueError, match="standard deviation <= 0"):
        nav.run(imu, g)
    g = gnss_record(tr, k)
    g.lat_rad[4] = np.nan
    with pytest.raises(ValueError, match="NaN or Inf"):
        nav.run(imu, g)
    # time going backwards at IMU sample 500: stop there, keep what came before
    t = imu.t_s.copy()
    t[500] = t[498]
    bad = Rec(t_s=t, gyro=imu.gyro, accel=imu.accel, kind="increments")
    with pytest.raises(FilterError, match="IMU sample 500") as ei:
        start(tr, quiet_config()).run(bad, gnss_record(tr, k))
    assert ei.value.index == 500 and len(ei.value.partial) == 500
    assert np.all(np.isfinite(ei.value.partial.lat_rad))
    # a gap longer than max_imu_gap_s
    t = imu.t_s.copy()
    t[700:] += 1.0
    with pytest.raises(FilterError, match="IMU gap"):
        start(tr, quiet_config()).run(Rec(t_s=t, gyro=imu.gyro, accel=imu.accel, kind="increments"))
    with pytest.raises(ValueError, match="rates"):
        start(tr, quiet_config(input="rates")).run(imu)


def test_stale_measurement_is_logged(exact_drive):
    """A measurement valid before the filter's time is not used, and reported."""
    tr, imu = exact_drive
    nav = start(tr, quiet_config())
    nav.run(Rec(t_s=imu.t_s[:300], gyro=imu.gyro[:300], accel=imu.accel[:300], kind="increments"))
    g = gnss_record(tr, np.array([1003, 4003]))             # 1.003 s is already past
    sol = nav.run(Rec(t_s=imu.t_s[300:], gyro=imu.gyro[300:], accel=imu.accel[300:], kind="increments"), g)
    st = sol.innovations["status"]
    assert list(st[:2]) == [lib.GF_INS_REJECTED_STALE] * 2 and np.all(st[2:] == 0)
    assert len(sol.rejected()) == 2



def _step_all(nav, imu, meas_at):
    """Drive the filter sample by sample (as an FMU does): meas_at(k) -> measurements
    handed in with sample k."""
    from gfins_fmi.estimation.measurements import INNOVATION_DTYPE
    log_arr = np.zeros(4096, INNOVATION_DTYPE)
    log = ffi.new("gf_ins_log *")
    log.capacity = len(log_arr)
    log.entries = ffi.cast("gf_ins_innovation *", ffi.from_buffer(log_arr))
    for k in range(len(imu.t_s)):
        ms = meas_at(k)
        mp = ffi.cast("gf_ins_meas *", ffi.from_buffer(ms)) if len(ms) else ffi.NULL
        st = lib.gf_ins_step(nav._f, float(imu.t_s[k]), ptr(np.ascontiguousarray(imu.gyro[k])),
                             ptr(np.ascontiguousarray(imu.accel[k])), len(ms), mp, ffi.NULL, log)
        assert st == lib.GF_OK, (k, st)
    return log_arr[:log.count]


@pytest.mark.parametrize("latency_s", [0.0, 0.2])
def test_delayed_measurements(exact_drive, latency_s):
    """GNSS valid 3 ms after a sample but handed in 0.2 s later: with max_latency_s the
    update uses the nominal of its time of validity (residuals at truncation level, as
    without delay); without it the epochs are stale."""
    from gfins_fmi.estimation.measurements import gather_measurements
    tr, imu = exact_drive
    k = np.arange(1003, 60000, 1000)
    meas = gather_measurements(gnss_record(tr, k), None, None, True)
    deliver = meas["t_s"] + 0.2                       # delivered 0.2 s late
    which = np.searchsorted(imu.t_s, deliver - 1e-9)  # the first sample at or after delivery
    nav = start(tr, quiet_config(max_latency_s=latency_s), position_std_m=0.05,
                velocity_std_m_s=0.01, attitude_std_rad=1e-4)
    sub = Rec(t_s=imu.t_s[:6000], gyro=imu.gyro[:6000], accel=imu.accel[:6000])
    log = _step_all(nav, sub, lambda j: meas[which == j])
    if latency_s == 0:
        assert len(log) == len(meas) and np.all(log["status"] == lib.GF_INS_REJECTED_STALE)
        return
    assert np.all(log["status"] == 0)
    # the error state is taken as constant over the delay; with exact data it stays ~0
    assert np.abs(log["r"][log["type"] == lib.GF_INS_MEAS_GNSS_POS]).max() < 2e-3
    assert np.abs(log["r"][log["type"] == lib.GF_INS_MEAS_GNSS_VEL]).max() < 2e-3
