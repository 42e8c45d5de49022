"""Alignment, smoother, UKF/EKF agreement, consistency, the covariance prediction of outage
drift, the CLI and the real recording (gfins_fmi.estimation: alignment, evaluation,
scenarios, cli).

Truth: closed-form first-order alignment errors, the simulated drives' known errors,
chi-square statistics of seeded runs, and the RTK positions of the real recording.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.nav import earth
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator, integrate
from gfins_fmi.estimation.evaluation import navigation_errors
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive
from gfins_fmi.sim.vehicle import GnssReceiver
from support.drives import drive_start, town_drive_with_outage


@pytest.fixture(scope="module")
def drive():
    return town_drive_with_outage()


_init = drive_start


def test_smoother_and_ukf(drive):
    """On one seeded drive with a 60 s outage: the smoother's errors and stds are below the
    filter's in the outage; the UKF agrees with the EKF well inside their sigma."""
    prof, T, rx, truth = drive
    d = simulate_drive(prof, T, 0.01, imu=TACTICAL, gnss=rx, seed=3, truth=truth)
    sol = IntegratedNavigator(FilterConfig(imu=TACTICAL), _init(d)).run(d.imu, d.gnss, smoother=True)
    sm = sol.smooth()
    ef, es = navigation_errors(sol, d.truth), navigation_errors(sm, d.truth)
    out = (sol.t_s >= 200) & (sol.t_s < 260)
    assert np.max(es.horizontal_m[out]) < 0.5 * np.max(ef.horizontal_m[out])
    # at the epochs the smoothed variance never exceeds the filtered one (P_s = P + A(...)A^T
    # with P_s,k+1 <= P_prior,k+1); rows between epochs interpolate, so compare there
    n = sol.epochs["n_states"]
    iu = np.triu_indices(n)
    diag = np.flatnonzero(iu[0] == iu[1])
    nav = sol.epochs["nav"]
    RN = 6378137.0 / np.sqrt(1 - 0.00669437999014 * np.sin(nav[:, 7]) ** 2)
    f_east = np.sqrt(sol.epochs["P_post"][:, diag][:, 4]) * (RN + nav[:, 9]) * np.cos(nav[:, 7])
    assert np.all(sm.epoch_std[:, 3] <= f_east * (1 + 1e-9) + 1e-12)
    assert np.mean(sm.std[out, 3]) < 0.5 * np.mean(sol.std[out, 3])
    uk = IntegratedNavigator(FilterConfig(imu=TACTICAL, filter="ukf"), _init(d)).run(d.imu, d.gnss)
    eu = navigation_errors(uk, d.truth)
    settled = sol.t_s > 60
    # both filters see the same data: their difference is a small fraction of their sigma
    diff = np.abs(eu.pos_enu_m[settled, :2] - ef.pos_enu_m[settled, :2]) / sol.std[settled, 3:5]
    assert np.percentile(diff, 99) < 0.2, np.percentile(diff, 99)


def test_integrate_function_and_bad_config(drive):
    prof, T, rx, truth = drive
    d = simulate_drive(prof, 60.0, 0.01, imu=TACTICAL, gnss=GnssReceiver(rate_hz=1.0), seed=1)
    sm = integrate(d.imu, d.gnss, config=FilterConfig(imu=TACTICAL), initial=_init(d), smooth=True)
    assert len(sm) == len(d.imu.t_s) and sm.epoch_t_s is not None
    # the messages name the field, the value with its unit and the bounds (settings table)
    with pytest.raises(ValueError, match="FilterConfig.filter = 'kalman': must be one of 'ekf', 'ukf'"):
        FilterConfig(filter="kalman")
    with pytest.raises(ValueError, match="FilterConfig.gate_reset_count = -1: must be an integer >= 0"):
        FilterConfig(gate_reset_count=-1)
    with pytest.raises(ValueError, match="FilterConfig.propagation_interval_s = -0.1 s: must be finite"):
        FilterConfig(propagation_interval_s=-0.1)
    with pytest.raises(ValueError, match="InitialState.gyro_bias_std_rad_s = .* give InitialState.gyro_bias"):
        InitialState(d.initial).covariance(FilterConfig(imu=gf.ImuNoise()))


def test_barometer_and_odometer_states(drive):
    """Simulated barometer with a 4 m bias and odometer with a 2% scale error (gf_aiding_sim):
    the filter's bias and scale states find them within 3 sigma; during a GNSS outage the
    barometer holds the height and the odometer the speed (the heading error, which no
    odometer sees, still turns the travel into cross-track drift)."""
    from gfins_fmi.sim.vehicle import Barometer, Odometer
    prof, T, rx, truth = drive
    # a wheel contact point beside and below the IMU: the truth vehicle's IMU point moves
    # along its heading, so a point ahead or behind it would slip sideways in turns
    lever = (-0.8, 0.0, -0.5)
    d = simulate_drive(prof, T, 0.01, imu=TACTICAL, gnss=rx, seed=11,
                       baro=Barometer(rate_hz=10.0, std_m=0.5, bias0_m=4.0),
                       odometer=Odometer(rate_hz=10.0, lever_arm_m=lever, scale_error=0.02, std_m_s=0.05))
    cfg = FilterConfig(imu=TACTICAL, baro_bias=True, baro_bias_std_m=10.0, baro_bias_tau_s=0.0,
                       odometer_scale=True, odometer_scale_std=0.05, odometer_lever_arm_m=lever, nhc=True)
    init = _init(d, baro_bias_std_m=10.0, odometer_scale_std=0.05)
    nav = IntegratedNavigator(cfg, init)
    sol = nav.run(d.imu, d.gnss, d.baro, d.odometer)
    assert cfg.n_states == 17
    P = nav.covariance
    b, k = sol.sensors[-1, 12], sol.sensors[-1, 13]
    assert abs(b - 4.0) < 3 * np.sqrt(P[15, 15]) and np.sqrt(P[15, 15]) < 0.5
    assert abs(k - 0.02) < 3 * np.sqrt(P[16, 16]) and np.sqrt(P[16, 16]) < 0.005
    # the constraints agree with the truth: few gate rejections
    assert np.mean(sol.innovations_of("nhc")["status"] != 0) < 0.01
    free = IntegratedNavigator(FilterConfig(imu=TACTICAL), _init(d)).run(d.imu, d.gnss)
    out = (sol.t_s >= 200) & (sol.t_s < 260)
    ea, ef = navigation_errors(sol, d.truth), navigation_errors(free, d.truth)
    speed = np.hypot(*d.truth.v_n_m_s[1:, :2].T)

    def speed_err(s):
        return np.abs(np.hypot(*s.v_n_m_s[:, :2].T) - speed)[out]
    assert np.max(speed_err(sol)) < 0.5 * np.max(speed_err(free))
    # height: free inertial grows (0.07 -> 0.58 m over this outage, measured); the barometer
    # keeps it at its bias uncertainty (0.16-0.3 m)
    end = np.flatnonzero(out)[-1]
    assert abs(ea.pos_enu_m[end, 2]) < 0.5 * abs(ef.pos_enu_m[end, 2])


def test_odometer_mount_states(drive):
    """An IMU mounted 1 deg nose-up and 1.5 deg to the left of the vehicle's axes (the
    simulation's truth), odometer (2% scale error) and NHC: with the boresight states the
    filter finds both angles within 3 sigma; its drift in the 60 s GNSS outage is smaller
    than that of the same filter with the boresight fixed at zero, whose NHC residuals carry
    the bias (lateral ~ speed x sin 1.5 deg)."""
    from gfins_fmi.sim.vehicle import Odometer
    prof, T, rx, truth = drive
    mount = np.radians([1.0, -1.5])
    lever_m = np.array([-0.8, 0.0, -0.5])            # wheel point, vehicle axes (see above)
    d = simulate_drive(prof, T, 0.01, imu=TACTICAL, gnss=rx, seed=11, imu_mount_rad=mount,
                       odometer=Odometer(rate_hz=10.0, lever_arm_m=tuple(lever_m), scale_error=0.02,
                                         std_m_s=0.05))
    lever_b = earth.quat_to_dcm(earth.euler_to_quat(mount[1], mount[0], 0.0)) @ lever_m   # IMU axes
    out = (d.imu.t_s >= 200) & (d.imu.t_s < 260)
    res = {}
    for on in (False, True):
        cfg = FilterConfig(imu=TACTICAL, odometer_scale=True, odometer_scale_std=0.05,
                           odometer_lever_arm_m=tuple(lever_b), nhc=True, odometer_mount=on,
                           odometer_mount_std_rad=np.radians(3.0))
        nav = IntegratedNavigator(cfg, _init(d, odometer_scale_std=0.05))
        sol = nav.run(d.imu, d.gnss, None, d.odometer)
        res[on] = (sol, nav.covariance, navigation_errors(sol, d.truth))
    sol, P, err = res[True]
    from gfins_fmi.estimation import state_names
    assert sol.config.n_states == 18 and state_names(sol.config)[16:] == ("odo_pitch", "odo_heading")
    est, std = sol.sensors[-1, 14:16], np.sqrt(np.diag(P)[16:18])
    # measured: 0.9975 +- 0.0048 deg, -1.5003 +- 0.0081 deg
    assert np.all(np.abs(est - mount) < 3 * std), (np.degrees(est), np.degrees(std))
    assert np.all(std < np.radians(0.05))
    # outage drift: measured 1.7 m with the states, 4.3 m with the boresight fixed at zero
    drift_on, drift_off = np.max(err.horizontal_m[out]), np.max(res[False][2].horizontal_m[out])
    assert drift_on < 0.6 * drift_off, (drift_on, drift_off)
    # NHC residuals: biased without the states (mean lateral measured -0.094 m/s, 11% of
    # the updates gated out), centred with them (measured -0.0014 m/s, none gated)
    n_off, n_on = res[False][0].innovations_of("nhc"), sol.innovations_of("nhc")
    assert abs(np.mean(n_off["r"][:, 0])) > 0.05 and abs(np.mean(n_on["r"][:, 0])) < 0.01
    assert np.mean(n_on["status"] != 0) < 0.01
