"""Calibration at unknown poses (gfins_fmi.calibration.poses, still, the simulated hand-
turned record) against truths that are not its code: the simulator's rates are the
derivative of its attitude (second-order convergence of central differences), the
frame convention's truth by the LQ decomposition (checked to reproduce the sensor), the
fit on seeded consumer-MEMS records (the reduced version of the 50-set study,
bench/study_pose_calibration.py): every parameter within 3.5 of its stated sigma, the
residuals at their noise floors; noise-free records give the truth to the integration's
truncation; the refusals name what is wrong."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.calibration.poses import PoseRefused, calibrate_poses, pose_frame_truth
from gfins_fmi.calibration.still import StillDetector, detect_still
from gfins_fmi.nav.earth import WGS84, quat_to_dcm
from gfins_fmi.nav.imu_errors import ARCSEC, PPM, ImuErrors, ImuNoise
from gfins_fmi.sim.hand_poses import CONSUMER_MEMS_ERRORS, hand_turned_record

NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.6, accel_vrw_ug_sqrt_hz=150.0)


def test_simulated_rates_are_the_derivative_of_the_attitude():
    """C^T dC/dt by central differences equals the simulator's omega_nb (omega_ib less the
    Earth's rate): the difference falls ~100x for 10x finer sampling (second order: the
    closed form is right, not merely close)."""
    errs = []
    for hz in (100.0, 1000.0):
        r = hand_turned_record(ImuErrors(), ImuNoise(), n_poses=5, seed=1, lever_m=0.0, rate_hz=hz)
        C = quat_to_dcm(r.q_bn)
        dt = 1 / hz
        W = np.einsum("nji,njk->nik", C[1:-1], (C[2:] - C[:-2]) / (2 * dt))
        w_fd = np.c_[W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]]
        w_ie = np.einsum("nji,j->ni", C, WGS84.omega_ie * np.array([0, np.cos(r.lat_rad), np.sin(r.lat_rad)]))
        errs.append(np.abs(w_fd - (r.omega_ib_rad_s - w_ie)[1:-1]).max())
    assert errs[1] < errs[0] / 50, errs


def test_pose_frame_truth_reproduces_the_sensor():
    """The truth in the accelerometer-defined frame: (I+S)(I+N_lower) Q = the sensor's
    accelerometer matrix, (I+S_g)(I+N_g) Q = its gyro matrix, for a rotation Q (1e-12)."""
    e = ImuErrors.random(np.random.default_rng(3), **CONSUMER_MEMS_ERRORS)
    p = pose_frame_truth(e)
    L = np.diag(1 + p[0:3]) @ (np.eye(3) + np.array([[0, 0, 0], [p[3], 0, 0], [p[4], p[5], 0]]))
    M_a = np.diag(1 + e.accel_scale_ppm * PPM) @ (np.eye(3) + e.accel_misalignment_arcsec * ARCSEC)
    Q = np.linalg.solve(L, M_a)
    np.testing.assert_allclose(Q @ Q.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(Q) > 0
    Ng = np.zeros((3, 3))
    for (i, j), v in zip(((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)), p[12:18]):
        Ng[i, j] = v
    M_g = np.diag(1 + e.gyro_scale_ppm * PPM) @ (np.eye(3) + e.gyro_misalignment_arcsec * ARCSEC)
    np.testing.assert_allclose(np.diag(1 + p[9:12]) @ (np.eye(3) + Ng) @ Q, M_g, atol=1e-12)


@pytest.fixture(scope="module")
def runs():
    out = []
    for seed in range(3):
        errs = ImuErrors.random(np.random.default_rng(100 + seed), **CONSUMER_MEMS_ERRORS)
        rec = hand_turned_record(errs, NOISE, n_poses=36, seed=seed)
        out.append((errs, rec, calibrate_poses(rec.imu, lat_rad=rec.lat_rad, h_m=rec.h_m)))
    return out


def test_every_parameter_within_its_stated_sigma(runs):
    """3 seeded error sets x 21 parameters: every |estimate - truth| / sigma < 3.5 (for 63
    Gaussian pairs P(max > 3.5) = 3%; the 50-set study gives the distribution), and the
    RMS of z between 0.6 and 1.4 (an honest sigma: neither inflated nor optimistic)."""
    Z = np.array([(cal.values - pose_frame_truth(e)) / cal.std for e, _, cal in runs])
    assert np.abs(Z).max() < 3.5, Z
    assert 0.6 < np.sqrt(np.mean(Z ** 2)) < 1.4


def test_residuals_at_the_noise_floor(runs):
    """The pose-mean |f| - g after calibration is at the noise of a pose mean (RMS ratio
    in 0.6..1.4; nominal conversion: ~500x above), and the gyro fit's gravity-direction
    residual at its noise (ARW over the turn and the directions' noise: ratio 0.5..1.4)."""
    for _, _, cal in runs:
        p, t = cal.pose_table, cal.turn_table
        ratio = np.sqrt(np.mean(p["norm_minus_g_m_s2"] ** 2) / np.mean(p["sigma_m_s2"] ** 2))
        assert 0.6 < ratio < 1.4, ratio
        assert np.sqrt(np.mean(p["norm_minus_g_nominal_m_s2"] ** 2)) > 50 * np.sqrt(np.mean(p["sigma_m_s2"] ** 2))
        ratio_g = np.sqrt(np.mean(t["residual_rad"] ** 2) / np.mean(2 * t["sigma_rad"] ** 2))
        assert 0.5 < ratio_g < 1.4, ratio_g


def test_still_detector_finds_every_pose(runs):
    """The 36 simulated poses are found, each inside its true still span."""
    for _, rec, cal in runs:
        assert len(cal.still) == 36
        for (s, e), (ts, te) in zip(cal.still.ranges, rec.poses):
            assert ts <= s < e <= te


def test_model_errors_far_below_the_consumer_floor():
    """With 1/100 of the consumer noise, every parameter is still within 4 of its (100x
    smaller) sigma: the two-sample integration of 100 Hz hand turns, the Earth's rate
    model and the frame convention are exact to better than 1% of the consumer-MEMS
    uncertainty."""
    errs = ImuErrors.random(np.random.default_rng(7), **CONSUMER_MEMS_ERRORS)
    quiet = ImuNoise(gyro_arw_deg_sqrt_h=0.006, accel_vrw_ug_sqrt_hz=1.5)
    rec = hand_turned_record(errs, quiet, n_poses=30, seed=7)
    cal = calibrate_poses(rec.imu, lat_rad=rec.lat_rad, h_m=rec.h_m)
    z = (cal.values - pose_frame_truth(errs)) / cal.std
    assert np.abs(z).max() < 4, dict(zip(cal.names, np.round(z, 2)))


def test_refusals_name_the_problem():
    errs = ImuErrors.random(np.random.default_rng(1), **CONSUMER_MEMS_ERRORS)
    few = hand_turned_record(errs, NOISE, n_poses=8, seed=1)
    with pytest.raises(PoseRefused, match=r"8 still poses found; the accelerometer fit has 9 parameters"):
        calibrate_poses(few.imu, lat_rad=few.lat_rad, h_m=few.h_m)
    with pytest.raises(ValueError, match="give the gravity"):
        calibrate_poses(few.imu)
    # a pose with motion the detector lets through (loose thresholds): a slow 3 deg/s drift
    rec = hand_turned_record(errs, NOISE, n_poses=16, seed=2)
    s, e = rec.poses[5]
    gyro = rec.imu.gyro.copy()
    gyro[s + 100:e - 100, 2] += np.radians(3.0)
    moved = type(rec.imu)(rec.imu.t_s, gyro, rec.imu.accel, "rates")
    with pytest.raises(PoseRefused, match="motion inside a detected pose"):
        calibrate_poses(moved, lat_rad=rec.lat_rad, h_m=rec.h_m,
                        detector=StillDetector(gyro_factor=100.0, gyro_floor_deg_s=5.0))


def test_poses_too_alike_are_refused():
    """Turns about the vertical only (z always up): the z accelerometer's scale and bias
    (and the gyro axes the turns never excite) cannot be separated; refused by name."""
    from gfins_fmi.sim import hand_poses
    errs = ImuErrors.random(np.random.default_rng(1), **CONSUMER_MEMS_ERRORS)
    orig = hand_poses.random_orientation

    def heading_only(rng):
        h = rng.uniform(0, 2 * np.pi)
        tilt = rng.normal(0, 0.02, 2)
        q = np.array([np.cos(h / 2), tilt[0] / 2, tilt[1] / 2, np.sin(h / 2)])
        return q / np.linalg.norm(q)
    hand_poses.random_orientation = heading_only
    try:
        rec = hand_turned_record(errs, NOISE, n_poses=20, seed=4)
    finally:
        hand_poses.random_orientation = orig
    with pytest.raises(PoseRefused, match="too alike to separate.*accel_(bias|scale)_z"):
        calibrate_poses(rec.imu, lat_rad=rec.lat_rad, h_m=rec.h_m)


def test_detector_refuses_a_moving_start():
    errs = ImuErrors()
    rec = hand_turned_record(errs, NOISE, n_poses=12, seed=3, first_still_s=5.0)
    with pytest.raises(ValueError, match="moves during its first 20 s"):
        detect_still(rec.imu)
