"""The two conventions of an IMU calibration (gfins_fmi.calibration.compensation): our
forward model (sensor = model(truth), gyro frame) and the compensation form (truth =
model^-1(sensor), accelerometer frame; PSINS's clbt fields).

Truth: the compensation form's *function* is written out here with numpy from its
definition (PSINS's CIMU::Update and imuclbt: w = Kg w_out - eb, f = Ka a - db -
Ka2 o a^2 - fL - tGA (w x f), fL_i = e_i^T ([w_dot x] + [w x]^2) r_i), independently of
the conversion under test; the frames by their definitions (a lower-triangular matrix:
x along the triad's x sensor, y in its x-y plane).
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.calibration import compensation as cmp
from gfins_fmi.calibration import syscal_filter
from gfins_fmi.nav.imu_errors import ImuErrors


def _forward(rng) -> ImuErrors:
    """A random forward model in a general frame (both misalignments full), with lever
    arms in all directions and a delay."""
    off = lambda s: (lambda m: (np.fill_diagonal(m, 0.0), m)[1])(rng.normal(0, s, (3, 3)))
    return ImuErrors(gyro_bias_deg_h=rng.normal(0, 0.3, 3), gyro_scale_ppm=rng.normal(0, 30, 3),
                     gyro_misalignment_arcsec=off(60), accel_bias_ug=rng.normal(0, 30, 3),
                     accel_scale_ppm=rng.normal(0, 30, 3), accel_misalignment_arcsec=off(60),
                     accel_k2_ug_g2=rng.normal(0, 30, 3), lever_arm_cm=rng.normal(0, 5, (3, 3)),
                     accel_delay_ms=rng.uniform(-2, 2))


def _params(e: ImuErrors) -> np.ndarray:
    c = e._c
    return np.concatenate([list(c.g_scale), list(c.g_misalign_rad), list(c.g_bias_rad_s), list(c.a_scale),
                           list(c.a_misalign_rad), list(c.a_bias_m_s2), list(c.a_k2_s2_m),
                           list(c.a_lever_pos_m), [c.a_delay_s]])


def test_round_trips_to_round_off():
    """Acceptance: forward <-> compensation form round-trips to <= 1e-12 relative. Forward
    (gyro frame) -> compensation -> forward (gyro frame): every SI parameter within 1e-12
    of the largest of its block (scale factors 1e-5 relative to the matrices' unit
    diagonal); compensation -> forward -> compensation element by element. Measured:
    1.4e-13 (the frame rotation through datasheet units)."""
    rng = np.random.default_rng(22)
    worst = 0.0
    for _ in range(50):
        e, _ = cmp.to_gyro_frame(_forward(rng))
        back = cmp.from_compensation(cmp.to_compensation(e))
        a, b = _params(e), _params(back)
        # relative to the quantities' own scale: matrices against their identity, the rest
        # against the largest value of the set
        worst = max(worst, float(np.max(np.abs(a - b)) / np.max(np.abs(a))))
        cf = cmp.to_compensation(e)
        cf2 = cmp.to_compensation(cmp.from_compensation(cf))
        worst = max(worst, float(np.max(np.abs(cf.to_array() - cf2.to_array()) /
                                        np.maximum(np.abs(cf.to_array()), 1e-300)
                                        * (np.abs(cf.to_array()) > 1e-30))))
    print(f"worst round trip: {worst:.3g}")
    assert worst <= 1e-12, worst


def test_frames_are_the_triads():
    """The compensation form's frame is the accelerometers' (Ka lower triangular); the
    forward model returned is in the gyros' (N_g lower triangular), and the two frames
    differ by the rotation the form carries (a few tens of arcsec here)."""
    e = _forward(np.random.default_rng(1))
    cf = cmp.to_compensation(e)
    assert np.all(cf.Ka[np.triu_indices(3, 1)] == 0.0)
    g = cmp.from_compensation(cf)
    assert np.all(np.abs(g.gyro_misalignment_arcsec[np.triu_indices(3, 1)]) < 1e-9)
    Q = cmp.frame_rotation(e, "accel")
    np.testing.assert_allclose(Q @ Q.T, np.eye(3), atol=1e-15)
    assert 1e-6 < np.linalg.norm(cf.rotation_rad) < 1e-3
    # imu_errors_to_params takes round-off above the diagonal as zero (issue 22: 1e-21 was refused)
    ok = ImuErrors(gyro_misalignment_arcsec=[[0, 1e-16, 0], [5, 0, 0], [1, 2, 0]])
    syscal_filter.imu_errors_to_params(ok)
    with pytest.raises(ValueError, match="to_gyro_frame"):
        syscal_filter.imu_errors_to_params(ImuErrors(gyro_misalignment_arcsec=[[0, 5, 0], [0, 0, 0], [0, 0, 0]]))


def _compensate_psins(cf: cmp.CompensationForm, w_out, a, w_dot):
    """The compensation form's definition, one sample (numpy, from the module docstring)."""
    w = cf.Kg @ w_out - cf.eb
    f = cf.Ka @ a - cf.db - cf.Ka2 * a * a
    W = np.array([[0, -w_dot[2], w_dot[1]], [w_dot[2], 0, -w_dot[0]], [-w_dot[1], w_dot[0], 0]]) + \
        np.outer(w, w) - (w @ w) * np.eye(3)
    fL = np.array([W[0] @ cf.rx, W[1] @ cf.ry, W[2] @ cf.rz])
    f = f - fL
    return w, f - cf.tGA * np.cross(w, f)


def test_the_two_functions_agree_to_first_order():
    """Our forward model's outputs, compensated by the compensation form's definition
    (written here), give back the truth to second order in the errors. Gyros: exact (Kg is
    the inverse of our linear gyro model), 1e-12 rad/s. Specific force: within the
    second-order budget of each sample, computed here: the lever terms W r_i act along
    the nominal axis in one form and through Ka in the other (|N| |W r|), the delay is
    inverted exactly in one and to first order in the other (d^2 |w|^2 |f|), K2 on the raw
    output against the scaled one (|K2| |f|^2 |s| and |K2| |f| |b|); 2x margin, 1e-12
    round-off. Turntable-like motion: |w| <= 0.5 rad/s, |w_dot| <= 2 rad/s^2."""
    rng = np.random.default_rng(5)
    e, _ = cmp.to_gyro_frame(_forward(rng))
    cf = cmp.to_compensation(e)
    ea = cmp.from_compensation(cf, frame="accel")          # the same IMU in the form's frame
    N = np.max(np.abs(ea.accel_misalignment_arcsec)) * np.pi / 648000.0
    pos = ea.lever_arm_matrix_cm * 0.01
    c = ea._c
    k2, s_a, b_a = np.abs(list(c.a_k2_s2_m)).max(), np.abs(list(c.a_scale)).max(), np.abs(list(c.a_bias_m_s2)).max()
    worst_w, worst_ratio = 0.0, 0.0
    for _ in range(300):
        w, wd, f = rng.uniform(-0.3, 0.3, 3), rng.uniform(-1.2, 1.2, 3), rng.uniform(-7, 7, 3)
        wo, fo = ea.apply([w], [f], omega_dot_rad_s2=[wd])
        wc, fc = _compensate_psins(cf, wo[0], fo[0], wd)
        W = np.array([[0, -wd[2], wd[1]], [wd[2], 0, -wd[0]], [-wd[1], wd[0], 0]]) + np.outer(w, w) - (w @ w) * np.eye(3)
        lever = max(np.linalg.norm(W @ pos[i]) for i in range(3))
        nf = np.linalg.norm(f)
        budget = 2 * (3 * N * lever + c.a_delay_s ** 2 * (w @ w) * nf + k2 * nf ** 2 * 3 * s_a +
                      2 * k2 * nf * b_a) + 1e-12
        worst_w = max(worst_w, float(np.max(np.abs(wc - w))))
        worst_ratio = max(worst_ratio, float(np.max(np.abs(fc - f))) / budget)
    print(f"compensation form on our forward model: gyro {worst_w:.3g} rad/s, specific force "
          f"{worst_ratio:.3g} of its second-order budget")
    assert worst_w < 1e-12 and worst_ratio <= 1.0, (worst_w, worst_ratio)


@pytest.mark.parametrize("suffix", [".json", ".toml", ".bin", ".txt"])
def test_files_round_trip(tmp_path, suffix):
    """JSON and TOML (field names, SI), PSINS's 37 float64 (.bin) and text: read = written
    (text: repr of doubles, exact)."""
    cf = cmp.to_compensation(_forward(np.random.default_rng(9)))
    path = cmp.write_compensation(cf, tmp_path / f"clbt{suffix}")
    back = cmp.read_compensation(path)
    np.testing.assert_array_equal(back.to_array(), cf.to_array())
    if suffix == ".bin":
        assert path.stat().st_size == 37 * 8
    with pytest.raises(ValueError, match="37 values"):
        cmp.CompensationForm.from_array(np.zeros(36))


def test_laboratory_example_is_psins_layout():
    """The laboratory example in PSINS's array layout: Kg row-major first, tGA last."""
    a = cmp.laboratory_example().to_array()
    assert a.size == 37 and a[36] == 1e-3
    assert a[0] == pytest.approx(1 - 10e-6) and a[1] == pytest.approx(10 * np.pi / 648000)
    assert np.all(a[27:30] == [0.01, 0.02, 0.03])
