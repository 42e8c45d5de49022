"""IMU error model (C core gf_imu_error): apply against an independent numpy evaluation,
compensate as its exact inverse, parameter checks."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf

# Units of the datasheet, from their definitions (not from gfins_fmi.nav.imu_errors, the
# module under test): 1 arcsec = pi/648000 rad, 1 deg/h = pi/648000 rad/s, standard
# gravity 9.80665 m/s^2 (CGPM 1901), 1 ug = 1e-6 of it, 1 ppm = 1e-6.
ARCSEC = np.pi / 648000.0
DEG_H = np.pi / 648000.0
G0 = 9.80665
UG = 1e-6 * G0
PPM = 1e-6

DATASHEET = dict(gyro_bias_deg_h=10.0, gyro_scale_ppm=1000.0, gyro_misalignment_arcsec=100.0,
                 accel_bias_ug=1000.0, accel_scale_ppm=1000.0, accel_misalignment_arcsec=100.0,
                 accel_k2_ug_g2=50.0, lever_arm_cm=3.0)


def numpy_apply(e: gf.ImuErrors, w, f, temp):
    """The output equations of csrc/nav/gf_imu_error.h written out with numpy."""
    dt = temp - e.t0_C
    def poly(base, tc, unit):
        out = np.broadcast_to(np.asarray(base, float) * unit, (len(dt), 3)).copy()
        if tc is not None:
            for k, row in enumerate(np.asarray(tc)):
                out += np.outer(dt ** (k + 1), row * unit)
        return out
    gb = poly(e.gyro_bias_deg_h, e.gyro_bias_tc, DEG_H)
    gs = poly(e.gyro_scale_ppm, e.gyro_scale_tc, PPM)
    ab = poly(e.accel_bias_ug, e.accel_bias_tc, UG)
    as_ = poly(e.accel_scale_ppm, e.accel_scale_tc, PPM)
    Ng = np.asarray(e.gyro_misalignment_arcsec) * ARCSEC
    Na = np.asarray(e.accel_misalignment_arcsec) * ARCSEC
    w_out = (1 + gs) * (w @ (np.eye(3) + Ng).T) + gb
    cen = np.c_[w[:, 1] ** 2 + w[:, 2] ** 2, w[:, 0] ** 2 + w[:, 2] ** 2, w[:, 0] ** 2 + w[:, 1] ** 2]
    u = f @ (np.eye(3) + Na).T - np.asarray(e.lever_arm_cm) * 0.01 * cen
    k2 = np.asarray(e.accel_k2_ug_g2) * 1e-6 / G0
    return w_out, (1 + as_) * u + k2 * u ** 2 + ab


@pytest.mark.parametrize("seed", range(20))
def test_apply_matches_numpy_and_compensate_inverts_it(seed):
    """Random datasheet-level sets with second-order temperature terms. Bounds: apply vs
    numpy 64 eps of the output; compensate(apply(x)) vs x: 64 eps relative of the
    largest input plus the lever-arm/K2 terms' round-off (far below 1e-12)."""
    rng = np.random.default_rng(seed)
    e = gf.ImuErrors.random(rng, temp_order=2, **DATASHEET)
    n = 500
    w = rng.uniform(-3, 3, (n, 3))
    f = rng.uniform(-30, 30, (n, 3))
    temp = rng.uniform(-20, 60, n)
    w_out, f_out = e.apply(w, f, temp)
    rw, rf = numpy_apply(e, w, f, temp)
    eps = np.finfo(float).eps
    assert np.abs(w_out - rw).max() <= 64 * eps * np.abs(rw).max()
    assert np.abs(f_out - rf).max() <= 64 * eps * np.abs(rf).max()
    w2, f2 = e.compensate(w_out, f_out, temp)
    assert np.abs(w2 - w).max() <= 64 * eps * np.abs(w).max()
    assert np.abs(f2 - f).max() <= 64 * eps * np.abs(f).max()
    # the errors are real: without compensation the differences are of their size
    assert np.abs(f_out - f).max() > 100 * UG


def test_lever_arm_follows_seed_001():
    """seed 001: a_xb = a_xc + (w_y^2 + w_z^2) r_x, i.e. the sensor reads the centre's
    specific force minus the centripetal term of its offset."""
    e = gf.ImuErrors(lever_arm_cm=[3.0, 0.0, 0.0])
    w = np.array([[0.0, 2.0, 1.0]])
    _, f_out = e.apply(w, np.zeros((1, 3)))
    assert f_out[0, 0] == pytest.approx(-(4.0 + 1.0) * 0.03, rel=1e-15)


@pytest.mark.parametrize("kwargs, match", [
    (dict(gyro_scale_ppm=[6e5, 0, 0]), "gyro_scale_ppm"),
    (dict(accel_misalignment_arcsec=np.full((3, 3), 30000.0) * (1 - np.eye(3))), "accel_misalignment"),
    (dict(gyro_misalignment_arcsec=np.eye(3)), "zero diagonal"),
    (dict(lever_arm_cm=[150.0, 0, 0]), "lever_arm_cm"),
    (dict(accel_bias_ug=[np.nan, 0, 0]), "must be finite"),
    (dict(gyro_bias_tc=np.zeros((5, 3))), "at most 4"),
])
def test_out_of_range_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        gf.ImuErrors(**kwargs)


def test_nonfinite_sample_stops_with_partial():
    e = gf.ImuErrors(accel_bias_ug=[100.0, 0, 0])
    w = np.zeros((10, 3))
    f = np.zeros((10, 3))
    f[6, 2] = np.nan
    with pytest.raises(gf.NonFiniteInputError, match="sample 6") as exc:
        e.apply(w, f)
    assert exc.value.partial[1].shape == (6, 3)


def test_vehicle_run_compensation():
    """Seed 001's vehicle run, shortened to the alignment and the first minutes of motion
    (700 s): compensation with the true parameters equals the error-free run (exact
    inverse), with calibrated parameters it removes > 95% of the position error."""
    import sys
    from conftest import ROOT
    sys.path.insert(0, str(ROOT / "examples"))
    import imu_error_navigation as example
    res = example.run(duration_s=700.0)
    exact, ref = res["compensated, true parameters"], res["error-free sensors (reference)"]
    assert np.abs(exact["pos"] - ref["pos"]).max() < 1e-6
    unc = res["uncompensated"]["pos"].max()
    calib = res["compensated, calibrated parameters"]["pos"].max()
    print(f"vehicle run 700 s: uncompensated {unc:.3g} m, calibrated {calib:.3g} m")
    assert calib < 0.05 * unc


def test_noise_processes_statistics():
    """White, Gauss-Markov and random-walk parts against their closed forms
    (400k samples: std estimates good to ~0.2%; random-walk spread from 200 walks of
    2000 steps, std of a variance estimate ~10%): bounds 3% and 25%."""
    rng = np.random.default_rng(11)
    dt = 0.01
    g, a = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.1, accel_vrw_ug_sqrt_hz=50.0).sample(400_000, dt, rng)
    assert g.std() == pytest.approx(0.1 * np.pi / 180 / 60 / np.sqrt(dt), rel=0.03)
    assert a.std() == pytest.approx(50.0 * 9.80665e-6 * np.sqrt(0.5 / dt), rel=0.03)
    g, _ = gf.ImuNoise(gyro_bias_instability_deg_h=1.0, gyro_correlation_time_s=0.5).sample(400_000, dt, rng)
    assert g.std() == pytest.approx(np.pi / 180 / 3600, rel=0.03)
    r1 = np.mean(g[1:, 0] * g[:-1, 0]) / np.mean(g[:, 0] ** 2)
    assert r1 == pytest.approx(np.exp(-dt / 0.5), rel=0.01)
    ends = np.array([gf.ImuNoise(accel_rrw_ug_sqrt_s=10.0).sample(2000, dt, np.random.default_rng(s))[1][-1, 0]
                     for s in range(200)])
    assert ends.std() == pytest.approx(10.0 * 9.80665e-6 * np.sqrt(2000 * dt), rel=0.25)
    with pytest.raises(ValueError, match="gyro_arw_deg_sqrt_h must be finite and >= 0"):
        gf.ImuNoise(gyro_arw_deg_sqrt_h=-1.0)


def _rot(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    R = np.eye(3)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def test_seed001_misalignment_angles_are_small_rotations():
    """Row i of I + N is sensor axis i in m axes: compare with the axes actually turned by
    the rotations the seed describes (independent rotation matrices), to second order in
    the angles (1e-4 rad -> 1e-8)."""
    from gfins_fmi.nav.imu_errors import seed001_accel_misalignment, seed001_gyro_misalignment
    g = np.array([1.0, -2.0, 1.5]) * 1e-4          # gamma_yz, gamma_zy, gamma_zx
    N = seed001_gyro_misalignment(*g)
    e = np.eye(3)
    y_g = _rot(2, g[0]) @ e[1]
    z_g = _rot(1, g[1]) @ (_rot(0, g[2]) @ e[2])
    np.testing.assert_allclose((np.eye(3) + N)[1], y_g, atol=1e-8)
    np.testing.assert_allclose((np.eye(3) + N)[2], z_g, atol=1e-8)
    a = np.array([1.0, -1.0, 2.0, 0.5, -1.5, 1.2]) * 1e-4  # xz, xy, yz, yx, zy, zx
    Na = seed001_accel_misalignment(*a)
    rows = [_rot(1, a[1]) @ (_rot(2, a[0]) @ e[0]), _rot(0, a[3]) @ (_rot(2, a[2]) @ e[1]),
            _rot(0, a[5]) @ (_rot(1, a[4]) @ e[2])]
    np.testing.assert_allclose(np.eye(3) + Na, np.array(rows), atol=1e-8)


def test_band_limited_imu_noise():
    rng = np.random.default_rng(5)
    g, a = gf.ImuNoise(gyro_band_deg_h=2.0, accel_band_ug=30.0, band_hz=5.0).sample(300_000, 0.01, rng)
    assert g.std() == pytest.approx(2.0 * np.pi / 180 / 3600, rel=0.03)
    assert a.std() == pytest.approx(30.0 * 9.80665e-6, rel=0.03)
    r1 = np.mean(a[1:, 0] * a[:-1, 0]) / np.mean(a[:, 0] ** 2)
    assert r1 == pytest.approx(np.exp(-2 * np.pi * 5.0 * 0.01), rel=0.03)


def test_unit_constants_equal_their_definitions():
    """The datasheet units of gfins_fmi.nav.imu_errors against their definitions, typed in
    here (the reference of the other tests of this file must not come from the module
    under test: with ARCSEC set to an arcminute every test above still passed).
    1 arcsec = pi / 648000 rad = 4.8481368110953599e-06 rad; 1 deg/h = the same number in
    rad/s; g0 = 9.80665 m/s^2 (CGPM 1901); 1 ug = 1e-6 g0; 1 ppm = 1e-6."""
    from gfins_fmi.nav import imu_errors as ie
    assert ie.ARCSEC == pytest.approx(4.8481368110953599e-06, rel=1e-15)
    assert ie.DEG_H == pytest.approx(4.8481368110953599e-06, rel=1e-15)
    assert ie.G0 == 9.80665
    assert ie.UG == pytest.approx(9.80665e-6, rel=1e-15)
    assert ie.PPM == 1e-6


# ---- issue 22: lever arms across the sensing axes, the accelerometer delay -----------------

def test_general_lever_arms_and_delay_against_a_rigid_body():
    """Accelerometer i at r_i (row i of lever_arm_cm (3, 3)) senses along its axis the
    specific force of its own point, f + w_dot x r_i + w x (w x r_i) (a rigid body, written
    here with numpy cross products), of the force sampled d late, f + d (w x f) (first
    order). Scale, K2 and bias then act as in numpy_apply; misalignment 0 (the model puts
    the lever term after it: first order). Tolerance 1e-14 relative: round-off of sums of
    ~30 m/s^2 terms."""
    rng = np.random.default_rng(22)
    pos = rng.uniform(-6, 6, (3, 3))
    e = gf.ImuErrors(accel_bias_ug=[10, 20, 30], accel_scale_ppm=[-10, -20, -30],
                     accel_k2_ug_g2=[10, 20, 30], lever_arm_cm=pos, accel_delay_ms=1.0)
    assert e.has_transverse_lever_arms
    np.testing.assert_allclose(e.lever_arm_matrix_cm, pos, rtol=1e-15)   # cm -> m -> cm
    n = 200
    w, wd, f = rng.uniform(-2, 2, (n, 3)), rng.uniform(-5, 5, (n, 3)), rng.uniform(-20, 20, (n, 3))
    _, fo = e.apply(w, f, omega_dot_rad_s2=wd)
    fd = f + 1e-3 * np.cross(w, f)
    r = pos * 0.01
    want = np.empty((n, 3))
    for i in range(3):
        pt = fd + np.cross(wd, r[i]) + np.cross(w, np.cross(w, r[i]))
        u = pt[:, i]
        s, k2, b = [-10e-6, -20e-6, -30e-6][i], [10, 20, 30][i] * 1e-6 / G0, [10, 20, 30][i] * UG
        want[:, i] = (1 + s) * u + k2 * u * u + b
    np.testing.assert_allclose(fo, want, rtol=0, atol=1e-14 * 30)
    # compensate with the same w_dot inverts it (round-off)
    wo, fo = e.apply(w, f, omega_dot_rad_s2=wd)
    wc, fc = e.compensate(wo, fo, omega_dot_rad_s2=wd)
    np.testing.assert_allclose(fc, f, rtol=0, atol=1e-13 * 30)
    # along-axis arms (the seed's model): the angular acceleration does not enter
    e1 = gf.ImuErrors(lever_arm_cm=[3.0, -2.0, 1.0])
    assert not e1.has_transverse_lever_arms
    np.testing.assert_array_equal(e1.apply(w, f)[1], e1.apply(w, f, omega_dot_rad_s2=wd)[1])


def test_delay_sign_and_increments_round_trip():
    """The delay's sign, by hand: turning about z at w with f along x, an accelerometer
    frame that samples d late still sees the force where it was d ago, rotated by +w d
    about z relative to now: f_y = +d w f (f x is unchanged to first order). Increments:
    compensate_increments(apply_increments(x)) = x with lever arms across the axes (the
    angular acceleration of both from the backward difference of the rates)."""
    e = gf.ImuErrors(accel_delay_ms=2.0)
    _, fo = e.apply([[0.0, 0.0, 0.5]], [[9.8, 0.0, 0.0]])
    assert fo[0, 1] == pytest.approx(2e-3 * 0.5 * 9.8, rel=1e-12)
    rng = np.random.default_rng(3)
    e = gf.ImuErrors.random(rng, gyro_bias_deg_h=1, gyro_scale_ppm=100, accel_bias_ug=100,
                            accel_scale_ppm=100, accel_misalignment_arcsec=60, accel_k2_ug_g2=20)
    e = gf.ImuErrors(**{**{k: getattr(e, k) for k in ("gyro_bias_deg_h", "gyro_scale_ppm",
                                                      "accel_bias_ug", "accel_scale_ppm",
                                                      "accel_misalignment_arcsec", "accel_k2_ug_g2")},
                        "lever_arm_cm": [[1, 2, 3], [4, 5, 6], [0, 0, 0]], "accel_delay_ms": 1.0})
    t = np.arange(1, 501) * 0.01
    w = np.c_[0.3 * np.sin(t), 0.2 * np.cos(2 * t), 0.1 * t]
    dth, dv = w * 0.01, np.c_[np.cos(t), np.sin(t), 9.8 + 0 * t] * 0.01
    g, a = e.apply_increments(dth, dv, 0.01)
    gc, ac = e.compensate_increments(g, a, 0.01)
    np.testing.assert_allclose(gc, dth, rtol=0, atol=1e-15)
    np.testing.assert_allclose(ac, dv, rtol=0, atol=1e-15)
    p = e.fmu_parameters()
    assert p["lever_arm_transverse"] == pytest.approx([0.02, 0.03, 0.04, 0.06, 0.0, 0.0])
    assert p["lever_arm"] == pytest.approx([0.01, 0.05, 0.0]) and p["accel_delay"] == 1e-3
    with pytest.raises(ValueError, match="lever_arm_cm"):
        gf.ImuErrors(lever_arm_cm=np.full((3, 3), 150.0))
    with pytest.raises(ValueError, match="accel_delay_ms"):
        gf.ImuErrors(accel_delay_ms=2000.0)
