"""System-level calibration (gfins_fmi.calibration.system over C gf_syscal).

Truth: the forward model is gf_rotation's exact increments (checked against closed
forms in tests/c/test_rotation.c) through the IMU error model gf_imu_error (checked in
tests/c/test_imu_error.c) with seed 001's angles as gfins_fmi.nav.imu_errors defines them;
the filter is never its own reference. The Monte Carlo of the acceptance criteria (50
random error sets on the seed's path) is bench/study_syscal.py; here single seeded runs
on short paths, each with the tolerance it needs stated.
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.sim import rotation as rot
from gfins_fmi.calibration import system as c36
from gfins_fmi.calibration import segmentation, syscal_filter
from gfins_fmi.nav import imu_errors
from gfins_fmi.nav.imu_errors import (ARCSEC, ImuErrors, ImuNoise, seed001_accel_misalignment,
                                      seed001_gyro_misalignment)
from gfins_fmi.io.records import ImuRecord

LAT, H = np.radians(40.0), 50.0
NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
CFG = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0, vel_std_m_s=1e-5,
                                 model="seed", estimate_delay=False)


def _short_path(axes=("m", "i", "m", "i", "m", "i"), angles=(90, 90, 180, 180, 90, 90), dwell=40.0):
    turns = [rot.rest(120.0)] + [(rot.middle if a == "m" else rot.inner)(g, dwell)
                                 for a, g in zip(axes, angles)]
    return rot.RotationSchedule(tuple(turns))


def test_parameter_mapping_matches_the_seed_angle_functions():
    rng = np.random.default_rng(5)
    p = c36.random_params(rng)
    e = syscal_filter.params_to_imu_errors(p)
    g = p[3:6] / ARCSEC
    a = p[12:18] / ARCSEC
    np.testing.assert_allclose(e.gyro_misalignment_arcsec, seed001_gyro_misalignment(*g), atol=1e-9)
    np.testing.assert_allclose(e.accel_misalignment_arcsec, seed001_accel_misalignment(*a), atol=1e-9)
    np.testing.assert_allclose(syscal_filter.imu_errors_to_params(e), p, rtol=1e-12, atol=1e-20)
    with pytest.raises(ValueError, match="lower-triangular"):
        syscal_filter.imu_errors_to_params(ImuErrors(gyro_misalignment_arcsec=[[0, 5, 0], [0, 0, 0], [0, 0, 0]]))


def test_segmentation_finds_the_positions_and_turns():
    s = rot.seed001_path(repeats=1, align_s=60.0, dwell_s=20.0)
    tr = rot.simulate_static(s, s.duration_s, 0.01, LAT, H)
    segs = segmentation.segment_record(tr.t_s, tr.dtheta_rad)
    turns = [x for x in segs if x.kind == "turn"]
    static = [x for x in segs if x.kind == "static"]
    assert len(turns) == 18 and len(static) == 19
    want = [a for _, a, _ in rot.SEED001_TABLE[1:]]
    # the turn's angle includes the Earth rate over it and the static margins: 0.2 deg
    np.testing.assert_allclose([x.angle_deg for x in turns], want, atol=0.2)
    # first turn about the middle axis = x_m (IMU at position 0)
    assert np.allclose(turns[0].axis, [1, 0, 0], atol=1e-2)
    assert turns[0].describe().startswith("turn 90.0 deg about +x")


def test_short_path_recovers_biases_and_lever_arms_within_3_sigma():
    """Six turns on a 600 s record, seed-grade noise, biases and lever arms at the seed's
    prior level: the observed parameters within 3 sigma (probability 0.9973 each for a
    consistent filter; the seed is fixed), their sigmas a small fraction of the prior."""
    rng = np.random.default_rng(21)
    p = np.zeros(27)
    p[6:9] = rng.normal(0, 0.01, 3) * imu_errors.DEG_H
    p[18:21] = rng.normal(0, 1000, 3) * imu_errors.UG
    p[24:27] = rng.normal(0, 3, 3) * 0.01
    rec, _ = c36.simulate_record(_short_path(), p, LAT, H, noise=NOISE, seed=4)
    rep = c36.calibrate(rec, LAT, H, config=CFG)
    z = (rep.estimate - p) / rep.std
    idx = [18, 19, 20, 24, 25, 26]
    assert np.all(np.abs(z[idx]) < 3), dict(zip([rep.names[k] for k in idx], z[idx]))
    assert np.all(rep.ratio[idx] < 0.1), rep.ratio[idx]        # measured: 0.002-0.004, 0.05-0.06
    assert np.all(np.abs(z) < 4), "no parameter, observed or not, far outside its reported sigma"
    assert len(rep.positions) == 7 and all(np.isfinite(x["rms_residual_m_s"]) for x in rep.positions)


def test_a_path_that_turns_only_the_inner_axis_cannot_see_everything():
    """Turns about z_m only (z stays up): the z accelerometer never changes its input, so
    its scale factor, K2 and bias cannot be separated, nor the z lever arm (no rate about
    x or y), and the report says so instead of returning a number."""
    s = _short_path(axes=("i",) * 4, angles=(90, 90, 90, 90))
    cov = c36.covariance_study(s, LAT, H, CFG, dt_s=0.05)
    r = dict(zip(cov["names"], cov["ratio"]))
    for name in ("accel_scale_z", "accel_k2_z", "lever_arm_z"):
        assert r[name] > 0.9, (name, r[name])
    rec, _ = c36.simulate_record(s, np.zeros(27), LAT, H, noise=NOISE, seed=3)
    rep = c36.calibrate(rec, LAT, H, config=CFG, passes=1)
    assert {"accel_scale_z", "accel_k2_z", "lever_arm_z"} <= set(rep.unobservable)
    assert "not observed" in rep.table()


def test_estimate_delay_37_states():
    """A 2 ms accelerometer delay: the 37th state finds it within 3 sigma (sigma < 0.05 ms)."""
    s = _short_path()
    p = np.zeros(28)
    p[27] = 2e-3
    rec, _ = c36.simulate_record(s, p, LAT, H, noise=NOISE, seed=8)
    cfg = syscal_filter.SyscalConfig(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0, vel_std_m_s=1e-5,
                                     estimate_delay=True, model="seed")
    rep = c36.calibrate(rec, LAT, H, config=cfg)
    assert rep.std[27] < 5e-5
    assert abs(rep.accel_delay_s - 2e-3) < 3 * rep.std[27], (rep.accel_delay_s, rep.std[27])


def _rec(t, th, dv, kind="increments"):
    return ImuRecord(t, th, dv, kind, "test")


def test_bad_records_are_refused_with_what_to_change():
    s = _short_path(dwell=10.0)
    rec, tr = c36.simulate_record(s, np.zeros(27), LAT, H)
    t, th, dv = rec.t_s, np.asarray(rec.gyro), np.asarray(rec.accel)
    with pytest.raises(syscal_filter.CalibrationInputError, match="specific force in m/s\\^2"):
        c36.calibrate(_rec(t, th, dv / 0.01), LAT, H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="degrees"):
        c36.calibrate(_rec(t, np.degrees(th), dv), LAT, H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="89 deg"):
        c36.calibrate(rec, np.radians(89.5), H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="ft/s"):
        c36.calibrate(_rec(t, th, dv / 0.3048), LAT, H)
    # continuously turning: no rest
    cont = rot.continuous_scheme(inner_rate_deg_s=6.0, middle_rate_deg_s=3.0, half_cycle_s=120.0)
    tr2 = rot.simulate_static(cont, 200.0, 0.01, LAT, H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="no static interval"):
        c36.calibrate(tr2.imu_record(), LAT, H)
    # a turn of 90 deg within 0.1 s at 10 Hz: 45 deg per sample
    fast = rot.RotationSchedule((rot.rest(60.0), rot.middle(90.0, 30.0, rate_deg_s=450.0, ramp_s=0.0)))
    tr3 = rot.simulate_static(fast, fast.duration_s, 0.1, LAT, H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="faster than the sample rate"):
        c36.calibrate(tr3.imu_record(), LAT, H)
    with pytest.raises(syscal_filter.CalibrationInputError, match="first static interval lasts"):
        c36.calibrate(rec, LAT, H, min_align_s=500.0)


def test_passes_relinearise_but_keep_the_prior():
    """A second pass is linearised about the first pass's estimates; its prior must stay
    the prior (centred on params0), or the data are counted twice where the prior matters.
    Noise-free record, gyro biases at 2 prior sigma, on a 600 s path that sees them weakly
    (std/prior r = 0.63-0.75). Truth for a weakly observed parameter, from the linear-
    Gaussian posterior (not from the filter): noise-free data say x, the prior says
    0 +- s_p, so the posterior mean is (1 - r^2) x, i.e. z = (estimate - x) / std = -r x / s_p.
    Measured within 0.07 sigma of that (the biases are not exactly uncorrelated with the
    other states); with the data counted twice z would be -r^3 x / s_p (0.65 sigma off
    here). Passes 2 and 3 must agree to round-off (a fixed point: measured 0.000 sigma)."""
    s = _short_path()
    p = np.zeros(27)
    p[6:9] = 2.0 * CFG.prior.params_std()[6:9] * np.array([1.0, -1.0, 1.0])
    rec, _ = c36.simulate_record(s, p, LAT, H)
    r2 = c36.calibrate(rec, LAT, H, config=CFG, passes=2)
    r3 = c36.calibrate(rec, LAT, H, config=CFG, passes=3)
    b = slice(6, 9)
    assert np.all((r2.ratio[b] > 0.5) & (r2.ratio[b] < 0.9)), r2.ratio[b]      # weakly observed
    z = (r2.estimate - p) / r2.std
    want = -r2.ratio[b] * p[b] / r2.prior_std[b]
    np.testing.assert_allclose(z[b], want, atol=0.2, err_msg="weak parameters: not the Bayesian posterior")
    # passes 2 and 3: the same estimates (0.01 sigma: iteration round-off; measured 0.000)
    np.testing.assert_array_less(np.abs(r3.estimate - r2.estimate) / r2.std, 0.01)
