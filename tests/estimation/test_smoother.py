"""The Rauch-Tung-Striebel smoother of the integrated navigator (gf_ins_smooth,
gfins_fmi.estimation.solution.smooth) against an independent computation.

Truth: a numpy RTS written here from the textbook recursion (Rauch, Tung & Striebel
1965; the form of filterpy's rts_smoother) over the epochs the forward run stored
(Phi, P-, P+, the fed-back corrections dx), with a general solver (LU, np.linalg.solve)
where the C code uses a Cholesky factorisation; and the covariance algebra the smoother
must obey whatever the data (smoothed variance in (0, filtered]). The smoothed NEES of a
Monte Carlo is checked in tests/estimation/test_evaluation.py.

Closed-loop bookkeeping (gf_ins_gnss.h): at every epoch the filter's error estimate is
fed back, so the posterior estimate about the posterior nominal is 0 and the prior
estimate of the next epoch about its prior nominal is 0; the error of the prior nominal
at epoch k+1 is that of its posterior nominal plus the correction dx_k+1 fed back there.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.nav.earth import radii
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver
from support.smoothing import c_smoother, unpack

T_S = 150.0


@pytest.fixture(scope="module")
def runs():
    """EKF and UKF over one seeded 150 s town drive with a 40 s GNSS outage, 21 states
    (scale factors), the smoother's epochs kept."""
    prof = town_drive(T_S)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.2, 2.0),
                      vel_std_m_s=(0.05, 0.06, 0.1), outages_s=((70.0, 110.0),))
    d = simulate_drive(prof, T_S, 0.01, imu=TACTICAL, gnss=rx, seed=5)
    init = InitialState(d.initial, position_std_m=(1.0, 1.5, 2.0), velocity_std_m_s=0.1,
                        attitude_std_rad=(0.005, 0.006, 0.02), gyro_scale_std=5e-4,
                        accel_scale_std=3e-4)
    out = {}
    for name in ("ekf", "ukf"):
        cfg = FilterConfig(imu=TACTICAL, filter=name, scale_factors=True)
        out[name] = IntegratedNavigator(cfg, init).run(d.imu, d.gnss, smoother=True)
    return out


def numpy_rts(ep: dict) -> tuple[np.ndarray, np.ndarray]:
    """The textbook RTS pass, written independently of the C code:
        G_k = P+_k Phi_k+1^T (P-_k+1)^-1
        x^s_k = x+_k + G_k (x^s_k+1 - x-_k+1)
        P^s_k = P+_k + G_k (P^s_k+1 - P-_k+1) G_k^T
    with, in the closed loop, x+_k = 0, x-_k+1 = 0 and x^s_k+1 taken about the prior
    nominal of k+1 (its smoothed error about the posterior nominal + dx_k+1). The gain is
    solved on the covariance scaled to unit diagonal (the states span 1e-14 rad^2 of
    latitude to 1e-2 (m/s)^2: without scaling LU would lose digits Cholesky keeps)."""
    n = ep["n_states"]
    Pp, Pm = unpack(ep["P_post"], n), unpack(ep["P_prior"], n)
    Phi = ep["Phi"].reshape(-1, n, n)
    dx = ep["dx"]
    E = len(ep["t_s"])
    xs, Ps = np.zeros((E, n)), np.zeros((E, n, n))
    Ps[-1] = Pp[-1]
    for k in range(E - 2, -1, -1):
        s = 1.0 / np.sqrt(np.diag(Pm[k + 1]))
        # G^T = (P-)^-1 Phi P+  ->  D (D P- D)^-1 D Phi P+  with D = diag(s)
        Gt = s[:, None] * np.linalg.solve(s[:, None] * Pm[k + 1] * s[None, :],
                                          s[:, None] * (Phi[k + 1] @ Pp[k]))
        G = Gt.T
        xs[k] = G @ (xs[k + 1] + dx[k + 1])
        Ps[k] = Pp[k] + G @ (Ps[k + 1] - Pm[k + 1]) @ G.T
    return xs, Ps


@pytest.mark.parametrize("name", ["ekf", "ukf"])
def test_c_smoother_equals_an_independent_rts(runs, name):
    """States and covariances of gf_ins_smooth = the numpy RTS at every epoch.

    Tolerance: each quantity is compared in units of its own smoothed std (errors) or
    of sqrt(P_ii P_jj) (covariances). One backward step solves a system whose scaled
    condition number is ~1e3 here (measured 1065: correlated position, velocity and
    attitude errors), so the two factorisations differ by ~1e3 eps ~ 2e-13 relative per
    step; the recursion is contractive (the gain's spectral radius < 1), so those do not
    grow over the 1611 epochs (measured: 1.6e-13 on the states, 1.4e-11 on the
    covariances). 1e-9 keeps a margin of 70 over that and is 1e9 below what a transition
    taken one epoch off does (measured: states off by up to 2.3 sigma, 170 smoothed
    variances negative)."""
    ep = runs[name].epochs
    xs_c, Ps_c = c_smoother(ep)
    xs_n, Ps_n = numpy_rts(ep)
    sd = np.sqrt(np.einsum("kii->ki", Ps_n))
    assert np.all(np.isfinite(sd)) and np.all(sd > 0)
    ex = np.abs(xs_c - xs_n) / sd
    eP = np.abs(Ps_c - Ps_n) / (sd[:, :, None] * sd[:, None, :])
    assert ex.max() < 1e-9, (ex.max(), np.unravel_index(ex.argmax(), ex.shape))
    assert eP.max() < 1e-9, (eP.max(), np.unravel_index(eP.argmax(), eP.shape))
    # the smoother did something: the outage's errors are corrected by many sigma-units
    assert np.abs(xs_n / sd).max() > 1.0


def test_epochs_hold_a_consistent_transition(runs):
    """EKF: between consecutive epochs the prior covariance is the posterior moved by the
    stored transition plus a process noise, Q_k = P-_k+1 - Phi_k+1 P+_k Phi_k+1^T, which
    must be symmetric positive semi-definite (the trapezoidal Qc T/2 terms of
    gf_ins_gnss.h): a transition stored at the wrong epoch or a covariance from another
    instant breaks this. Bound: eigenvalues of Q scaled to the unit diagonal of P- >=
    -1e-12 and its asymmetry < 1e-12 (round-off of the products, n eps ~ 5e-15 relative
    to entries of at most 1; measured -1.2e-20 and 1.3e-15; with each transition taken
    one epoch off the smallest eigenvalue is -0.074)."""
    ep = runs["ekf"].epochs
    n = ep["n_states"]
    Pp, Pm = unpack(ep["P_post"], n), unpack(ep["P_prior"], n)
    Phi = ep["Phi"].reshape(-1, n, n)
    worst = 0.0
    for k in range(len(Pp) - 1):
        s = 1.0 / np.sqrt(np.diag(Pm[k + 1]))
        Q = Pm[k + 1] - Phi[k + 1] @ Pp[k] @ Phi[k + 1].T
        Qs = s[:, None] * Q * s[None, :]
        assert np.abs(Qs - Qs.T).max() < 1e-12, k
        worst = min(worst, np.linalg.eigvalsh(0.5 * (Qs + Qs.T)).min())
    assert worst > -1e-12, worst


@pytest.mark.parametrize("name", ["ekf", "ukf"])
def test_smoothed_std_is_finite_and_below_the_filtered_in_every_column(runs, name):
    """At every epoch and for every one of the 21 states, 0 < P^s_ii <= P+_ii (P^s = P+ +
    G (P^s - P-) G^T with P^s_k+1 <= P-_k+1); the 9 std columns the solution reports
    (velocity, position in metres, attitude) finite and below the filter's at the epochs;
    at the IMU rows every smoothed std finite. Round-off allowance 1e-9 relative (the
    equality holds at the last epoch and where no later data inform a state)."""
    sol = runs[name]
    ep = sol.epochs
    n = ep["n_states"]
    _, Ps = c_smoother(ep)
    var_s = np.einsum("kii->ki", Ps)
    var_f = np.einsum("kii->ki", unpack(ep["P_post"], n))
    assert np.all(np.isfinite(var_s)) and np.all(var_s > 0)
    bad = np.argwhere(var_s > var_f * (1 + 1e-9))
    assert bad.size == 0, bad[:5]
    sm = sol.smooth()
    assert np.all(np.isfinite(sm.std)) and np.all(np.isfinite(sm.epoch_std))
    nav = ep["nav"]
    RM, RN, _, _ = radii(nav[:, 7])
    f9 = np.empty((len(nav), 9))
    f9[:, 0:3] = np.sqrt(var_f[:, 0:3])
    f9[:, 3] = np.sqrt(var_f[:, 4]) * (RN + nav[:, 9]) * np.cos(nav[:, 7])
    f9[:, 4] = np.sqrt(var_f[:, 3]) * (RM + nav[:, 9])
    f9[:, 5] = np.sqrt(var_f[:, 5])
    f9[:, 6:9] = np.sqrt(var_f[:, 6:9])
    bad = np.argwhere(sm.epoch_std > f9 * (1 + 1e-9))
    assert bad.size == 0, bad[:5]
    # and the reported std is the smoothed covariance (gf_ins_smooth, checked against the
    # numpy RTS above) in the solution's units, column by column: the same conversion
    # written here, so equal to round-off (1e-13 relative); the rows take it interpolated
    # linearly between the epochs
    s9 = np.empty_like(f9)
    s9[:, 0:3] = np.sqrt(var_s[:, 0:3])
    s9[:, 3] = np.sqrt(var_s[:, 4]) * (RN + nav[:, 9]) * np.cos(nav[:, 7])
    s9[:, 4] = np.sqrt(var_s[:, 3]) * (RM + nav[:, 9])
    s9[:, 5] = np.sqrt(var_s[:, 5])
    s9[:, 6:9] = np.sqrt(var_s[:, 6:9])
    np.testing.assert_allclose(sm.epoch_std, s9, rtol=1e-13, atol=0.0)
    assert sm.std.shape == (len(sol.t_s), 9)
    for i in range(9):
        np.testing.assert_allclose(sm.std[:, i], np.interp(sol.t_s, ep["t_s"], s9[:, i]),
                                   rtol=1e-13, atol=0.0)
    # the column order of the smoothed std is the filter's: east before north (the
    # north std of this drive's GNSS is 1.2 m against 1.0 m east, P0 1.5 m against 1.0 m)
    k = np.searchsorted(sm.epoch_t_s, 5.0)
    assert sm.epoch_std[k, 4] > sm.epoch_std[k, 3]


def test_rows_between_epochs_take_the_interpolated_correction(runs):
    """A row between epochs j and j+1 is corrected by (1 - u) x^s_j + u (x^s_j+1 +
    dx_j+1), u its fraction of the way (gf_ins_gnss.h, gf_ins_smooth_apply): the error of
    the posterior nominal of j, moving to that of the prior nominal of j+1 which the rows
    in between continue. Built here with numpy for every 19th row and applied with
    gf_ins_apply_error (the filter's correction): equal to the smoothed solution's rows to
    round-off (1e-12; the same operations in the same order)."""
    from gfins_fmi._lib import ffi, lib, ptr
    sol = runs["ekf"]
    ep = sol.epochs
    n = ep["n_states"]
    xs, _ = c_smoother(ep)
    sm = sol.smooth()
    et = ep["t_s"]
    lay = sol.config.layout()
    f = ffi.new("gf_ins_filter *")
    f.n_states = lay.n_states
    f.idx_sg, f.idx_sa, f.idx_baro = lay.idx_sg, lay.idx_sa, lay.idx_baro
    f.idx_odo, f.idx_mount = lay.idx_odo, lay.idx_mount
    checked = 0
    for k in range(3, len(sol) - 1, 19):
        t = sol.t_s[k]
        j = int(np.searchsorted(et, t + 1e-9, side="right")) - 1
        if j + 1 >= len(et) or t <= et[j] + 1e-9:
            continue
        u = (t - et[j]) / (et[j + 1] - et[j])
        e = (1.0 - u) * xs[j] + u * (xs[j + 1] + ep["dx"][j + 1])
        nav = np.r_[sol.q_bn[k], sol.v_n_m_s[k], sol.lat_rad[k], sol.lon_rad[k], sol.h_m[k]]
        assert lib.gf_ins_apply_error(f, ptr(e, n), ptr(nav, 10), ffi.NULL) == lib.GF_OK
        np.testing.assert_allclose(nav[:4], sm.q_bn[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(nav[4:7], sm.v_n_m_s[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(nav[7:9], [sm.lat_rad[k], sm.lon_rad[k]], rtol=0, atol=1e-15)
        assert abs(nav[9] - sm.h_m[k]) < 1e-9
        checked += 1
    assert checked > 500


def test_smoothing_refuses_a_configuration_of_another_layout(runs):
    """The epochs hold the run's 21 states; a solution handed a configuration with more or
    fewer states is refused, naming both counts (the C apply step reads the layout)."""
    sol = runs["ekf"]
    for other, m in ((FilterConfig(imu=TACTICAL, scale_factors=True, baro_bias=True), 22),
                     (FilterConfig(imu=TACTICAL), 15)):
        with pytest.raises(ValueError, match=f"the solution's epochs hold 21 states, its "
                                             f"configuration {m}"):
            dataclasses.replace(sol, config=other).smooth()
