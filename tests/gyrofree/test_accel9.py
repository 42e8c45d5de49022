"""9-accelerometer solver and forward model through the Python API (cffi -> C core)."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.gyrofree import array as accel_array
from support.truth import EPS, W0, numpy_outputs, paper_layout, smooth_motion


def test_geometry_is_the_papers_table():
    u, th = paper_layout(0.1)
    g = gf.accel9_geometry(0.1)
    # the C core builds u as l * integer entries and theta from 1/sqrt(2): exact to 1 ulp
    np.testing.assert_allclose(g.u_m, u, rtol=0, atol=1e-17)
    np.testing.assert_allclose(g.theta, th, rtol=0, atol=2e-16)


def test_forward_model_equals_independent_numpy(rng):
    n_sensors, n = 23, 400
    u = rng.uniform(-0.3, 0.3, (n_sensors, 3))
    th = rng.normal(size=(n_sensors, 3))
    th /= np.linalg.norm(th, axis=1, keepdims=True)
    f, w, wd = rng.uniform(-20, 20, (n, 3)), rng.uniform(-5, 5, (n, 3)), rng.uniform(-10, 10, (n, 3))
    A = gf.forward_model(gf.ArrayGeometry(u, th), f, w, wd)
    ref = numpy_outputs(u, th, f, w, wd)
    # terms are below 20 + 10*0.52 + 25*0.52*2 ~ 52 m/s^2; the two evaluations order the
    # sums differently, so they differ by a few ulp of that: allow 64 ulp
    assert np.max(np.abs(A - ref)) <= 64 * EPS * 52


def test_solver_recovers_random_motions(rng):
    """f, omega^2, omega_dot to round-off for random (f, omega, omega_dot) per sample.

    Each is a sum of <= 6 outputs (|A| <= S) over <= 2 l, so its rounding error is
    below ~16 eps S / l; we allow 64 eps S / l. omega = sqrt(omega^2) divides that
    error by 2|omega|. The signs come from omega_init (first sample) and then from the
    previous solution, so random independent samples are given the true rate's sign
    at each sample by solving them one per call with that sign as omega_init.
    """
    l, n = 0.1, 2000
    u, th = paper_layout(l)
    f = rng.uniform(-30, 30, (n, 3))
    w = rng.uniform(-6, 6, (n, 3))
    wd = rng.uniform(-20, 20, (n, 3))
    A = numpy_outputs(u, th, f, w, wd)
    S = np.abs(A).max(axis=1, keepdims=True)
    sol = gf.solve_accel9(A, 0.01, l, omega_init_rad_s=np.sign(w[0]))
    assert np.all(np.abs(sol.f_m_s2 - f) <= 64 * EPS * S)
    assert np.all(np.abs(sol.omega_sq_rad2_s2 - w**2) <= 64 * EPS * S / l)
    assert np.all(np.abs(sol.omega_dot_rad_s2 - wd) <= 64 * EPS * S / l)
    # magnitudes: independent of the sign logic
    big = np.abs(w) > 1e-3
    tol_w = 64 * EPS * S / l / (2 * np.abs(w)) + 1e-15
    assert np.all((np.abs(np.abs(sol.omega_rad_s) - np.abs(w)) <= tol_w)[big])
    # signs: one sample per solver, sign given by omega_init
    for k in range(0, n, 97):
        s = gf.solve_accel9(A[k:k + 1], 0.01, l, omega_init_rad_s=np.sign(w[k]))
        assert np.all(np.abs(s.omega_rad_s[0] - w[k]) <= tol_w[k]), k


def test_sign_follows_integrated_omega_dot_through_zero_crossings():
    """A smooth motion whose omega_x and omega_z cross zero: the trapezoidal integral of
    omega_dot from omega_init carries the sign across each crossing."""
    l, dt, n = 0.1, 0.01, 4000
    u, th = paper_layout(l)
    t, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    sol = gf.solve_accel9(A, dt, l, omega_init_rad_s=W0)
    S = np.abs(A).max(axis=1, keepdims=True)
    tol = 64 * EPS * S / l / (2 * np.maximum(np.abs(w), 1e-3)) + 1e-15
    ok = np.abs(sol.omega_rad_s - w) <= tol
    # within 1e-6 rad/s of a crossing omega^2 ~ 1e-12 is at round-off level and the
    # solution may be flagged; everywhere else it must be exact
    near_zero = np.abs(w) < 1e-6
    assert np.all(ok | near_zero), np.argwhere(~(ok | near_zero))[:5]
    assert np.count_nonzero(np.sign(np.diff(np.sign(w[:, 0])))) >= 2  # crossings happened


def test_streaming_equals_one_call():
    l, dt, n = 0.1, 0.01, 3000
    u, th = paper_layout(l)
    _, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    one = gf.solve_accel9(A, dt, l, W0)
    solver = gf.Accel9Solver(l, W0)
    parts = [solver.solve(A[a:b], dt) for a, b in ((0, 1), (1, 777), (777, 2000), (2000, n))]
    assert solver.n_samples == n
    for name in ("f_m_s2", "omega_rad_s", "omega_dot_rad_s2", "omega_sq_rad2_s2", "flags"):
        joined = np.concatenate([getattr(p, name) for p in parts])
        assert np.array_equal(joined, getattr(one, name)), name


def test_negative_omega_sq_is_flagged_never_nan(rng):
    """Noise at zero rate makes omega_x^2 negative about half the time: those samples
    are flagged and carry the propagated rate (finite), never NaN."""
    l, dt, n = 0.1, 0.01, 5000
    u, th = paper_layout(l)
    w = np.tile([0.0, 1.0, 2.0], (n, 1))
    A = numpy_outputs(u, th, np.tile([0, 0, 9.8], (n, 1)), w, np.zeros((n, 3)))
    A += rng.normal(0, 1e-3, A.shape)
    sol = gf.solve_accel9(A, dt, l, [0.0, 1.0, 2.0])
    assert np.all(np.isfinite(sol.omega_rad_s))
    neg = sol.omega_sq_rad2_s2[:, 0] < 0
    flagged = (sol.flags & gf.FLAG_NEG_OMEGA_SQ[0]) != 0
    assert np.array_equal(neg, flagged)
    assert 0.3 * n < neg.sum() < 0.7 * n  # symmetric noise around omega_x^2 = 0
    assert sol.flag_counts()["neg_omega_sq_x"] == neg.sum()
    assert not np.any(sol.flags & (gf.FLAG_NEG_OMEGA_SQ[1] | gf.FLAG_NEG_OMEGA_SQ[2]))


# ---- bad input --------------------------------------------------------------------

def test_nonfinite_sample_names_index_and_keeps_partial():
    l, dt, n = 0.1, 0.01, 100
    u, th = paper_layout(l)
    _, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    good = gf.solve_accel9(A, dt, l, W0)
    A[37, 5] = np.inf
    with pytest.raises(gf.NonFiniteInputError, match=r"A_m_s2\[37, 5\].*accelerometer 6") as exc:
        gf.solve_accel9(A, dt, l, W0)
    assert exc.value.index == 37 and exc.value.column == 5
    assert len(exc.value.partial) == 37
    assert np.array_equal(exc.value.partial.omega_rad_s, good.omega_rad_s[:37])
    assert isinstance(exc.value, ValueError)


@pytest.mark.parametrize("A, err, match", [
    (np.zeros((10, 8)), ValueError, r"shape \(n, 9\)"),
    (np.zeros(9), ValueError, r"reshape\(1, 9\)"),
    (np.zeros((10, 9), dtype=complex), TypeError, "real numbers"),
    (np.array([["a"] * 9]), TypeError, "real numbers"),
])
def test_bad_shapes_and_dtypes(A, err, match):
    with pytest.raises(err, match=match):
        gf.solve_accel9(A, 0.01, 0.1)


@pytest.mark.parametrize("dt, l, match", [
    (0.0, 0.1, "dt_s"), (-0.01, 0.1, "dt_s"), (np.nan, 0.1, "dt_s"),
    (0.01, 0.0, "l_m"), (0.01, -0.1, "l_m"), (0.01, np.inf, "l_m"),
])
def test_bad_dt_and_lever_arm(dt, l, match):
    with pytest.raises(ValueError, match=match):
        gf.solve_accel9(np.zeros((3, 9)), dt, l)


def test_non_contiguous_and_integer_input_accepted():
    l, dt, n = 0.1, 0.01, 50
    u, th = paper_layout(l)
    _, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    big = np.zeros((n, 18))
    big[:, ::2] = A
    a = gf.solve_accel9(big[:, ::2], dt, l, W0)
    b = gf.solve_accel9(A, dt, l, W0)
    assert np.array_equal(a.omega_rad_s, b.omega_rad_s)
    ints = gf.solve_accel9(np.ones((2, 9), dtype=np.int32), dt, l)
    assert ints.f_m_s2.dtype == np.float64


@pytest.mark.parametrize("theta_row, match", [
    ([0, 0, 0], "sensor 1: the sensing direction is zero"),
    ([0, 1.1, 0], "sensor 1: .* norm 1.1"),
    ([0, np.nan, 0], "sensor 1: position or direction is not finite"),
])
def test_bad_geometry_names_the_sensor(theta_row, match):
    with pytest.raises(ValueError, match=match):
        gf.ArrayGeometry([[0.1, 0, 0], [0, 0.1, 0]], [[1, 0, 0], theta_row])


def test_bad_geometry_sizes():
    with pytest.raises(ValueError, match="1..64 sensors"):
        gf.ArrayGeometry(np.zeros((65, 3)), np.tile([1.0, 0, 0], (65, 1)))
    with pytest.raises(ValueError, match="u_m has 2 sensors but theta has 1"):
        gf.ArrayGeometry(np.zeros((2, 3)), [[1.0, 0, 0]])


def test_forward_model_nonfinite_names_input():
    g = gf.accel9_geometry(0.1)
    f = np.zeros((5, 3))
    w = np.zeros((5, 3))
    w[3, 2] = np.nan
    with pytest.raises(gf.NonFiniteInputError, match=r"omega_rad_s\[3, 2\]") as exc:
        gf.forward_model(g, f, w, np.zeros((5, 3)))
    assert exc.value.partial.shape == (3, 9)



def test_overflowing_samples_are_refused_not_inf():
    with pytest.raises(gf.SampleError, match="beyond the physical limits") as exc:
        gf.solve_accel9(np.r_[np.zeros((3, 9)), np.full((2, 9), 1e308)], 0.01, 0.1)
    assert exc.value.index == 3 and len(exc.value.partial) == 3
    with pytest.raises(gf.NonFiniteInputError, match="overflow"):
        gf.forward_model(gf.accel9_geometry(0.1), np.zeros((2, 3)), np.full((2, 3), 1e200),
                         np.zeros((2, 3)))
    with pytest.raises(ValueError, match="below 1e-06 m"):
        gf.solve_accel9(np.ones((2, 9)), 0.01, 1e-320)


def test_empty_geometry_message():
    with pytest.raises(ValueError, match="1..64 sensors; got 0"):
        gf.ArrayGeometry(np.zeros((0, 3)), np.zeros((0, 3)))


def test_samples_beyond_the_physical_limits_are_refused():
    """The navigators' limits (|w| <= 50 rad/s, |f| <= 1000 m/s^2, SinsConfig defaults)
    apply to the 9-accelerometer solver too (issue 15: 1e300 samples and dt = 1e300,
    which integrated w_dot into w = 1.6e150 rad/s, were accepted). Outputs from the
    independent numpy model; the limits are the module's published constants, checked
    against the navigators' defaults."""
    assert accel_array.MAX_RATE_RAD_S == gf.SinsConfig().max_rate_rad_s == 50.0
    assert accel_array.MAX_SPECIFIC_FORCE_M_S2 == gf.SinsConfig().max_specific_force_m_s2 == 1000.0
    u, th = paper_layout(0.1)
    z = np.zeros((1, 3))

    def solve(f=z, w=z, wd=z, dt=0.01, w0=(0.0, 0.0, 0.0)):
        return gf.solve_accel9(numpy_outputs(u, th, np.asarray(f, float), np.asarray(w, float),
                                             np.asarray(wd, float)), dt, 0.1, w0)
    assert solve(f=[[0.0, 999.0, 0.0]]).f_m_s2[0, 1] == pytest.approx(999.0, rel=1e-14)
    with pytest.raises(gf.SampleError, match=r"sample 0 is beyond the physical limits") as exc:
        solve(f=[[0.0, 0.0, -1001.0]])
    assert exc.value.index == 0 and len(exc.value.partial) == 0
    assert solve(w=[[49.9, 0.0, 0.0]], w0=(49.9, 0, 0)).omega_rad_s[0, 0] == pytest.approx(49.9, rel=1e-12)
    with pytest.raises(gf.SampleError, match="50 rad/s"):
        solve(w=[[0.0, 30.0, 40.1]], w0=(0, 1.0, 1.0))         # signs only
    with pytest.raises(ValueError, match="omega_init_rad_s .* exceeds the physical limit"):
        solve(w0=(0.0, 0.0, 50.5))
    with pytest.raises(gf.SampleError, match="sample 0"):
        gf.solve_accel9(np.full((3, 9), 1e300), 0.01, 0.1)
    # dt = 1e300 where noise makes omega_x^2 < 0 (-5e-3 rad^2/s^2): the rate is then the
    # integral of w_dot = 0.1 rad/s^2, 1e299 rad/s at sample 1 (before: accepted)
    A = numpy_outputs(u, th, np.zeros((3, 3)), np.zeros((3, 3)), np.tile([0.1, 0.0, 0.0], (3, 1)))
    A[:, [0, 3]] -= 1e-3
    with pytest.raises(gf.SampleError, match="sample 1 .*dt_s = 1e\\+300 s") as exc:
        gf.solve_accel9(A, 1e300, 0.1)
    assert len(exc.value.partial) == 1
