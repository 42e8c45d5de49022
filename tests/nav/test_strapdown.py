"""Strapdown mechanization (C core gf_sins through the Python API) against closed-form
motions of gfins_fmi.sim.trajectory, whose sensor outputs are exact (analytic rates, Gauss-
Legendre increments) and whose Earth model is written independently of the core."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.nav import earth
from support.truth import attitude_error_rad, horizontal_error_m

DEG = np.pi / 180


@pytest.fixture(scope="module")
def stationary_1h():
    return tj.sample(tj.Stationary(), 3600.0, 0.01)


@pytest.fixture(scope="module")
def sine_1h():
    return tj.sample(tj.SineVelocity(), 3600.0, 0.01)


def _nav(tr, **cfg):
    nav = gf.Strapdown(gf.NavState.from_trajectory(tr, 0), gf.SinsConfig(**cfg))
    return nav, nav.run(tr.dtheta_rad, tr.dv_m_s, dt_s=tr.dt_s)


def test_stationary_one_hour(stationary_1h):
    """Issue 3: 1 h at 100 Hz, horizontal position error < 1 mm, attitude < 1e-8 deg.
    Measured: horizontal 0 m (at rest every horizontal term cancels to the bit),
    attitude 2.4e-9 deg. Bounds: 1e-6 m (a round-off allowance, as the measured error
    is exactly zero) and 2x the measured attitude error."""
    tr = stationary_1h
    _, sol = _nav(tr)
    horiz = horizontal_error_m(sol.lat_rad, sol.lon_rad, tr.lat_rad[1:], tr.lon_rad[1:])
    att = np.degrees(np.linalg.norm(attitude_error_rad(sol.q_bn, tr.q_bn[1:]), axis=1))
    print(f"stationary 1 h: max horizontal error {horiz.max():.3g} m, attitude {att.max():.3g} deg, "
          f"height {np.abs(sol.h_m - tr.h_m[1:]).max():.3g} m (free vertical channel)")
    assert horiz.max() < 1e-6
    assert att.max() < 5e-9


def test_sine_velocity_one_hour_increments(sine_1h):
    """Issue 3: 1 h at 100 Hz from increments: horizontal < 0.1 m, attitude < 1e-5 deg;
    the vertical channel is reported. Measured: 10.5 mm, 1.1e-7 deg, horizontal velocity
    1.85e-5 m/s. Over the hour the free vertical channel (time constant ~570 s) amplifies
    its seed ~500 times and couples into the horizontal channels, so the bounds are 3x the
    measured errors (2x elsewhere)."""
    tr = sine_1h
    _, sol = _nav(tr)
    horiz = horizontal_error_m(sol.lat_rad, sol.lon_rad, tr.lat_rad[1:], tr.lon_rad[1:])
    att = np.degrees(np.linalg.norm(attitude_error_rad(sol.q_bn, tr.q_bn[1:]), axis=1))
    print(f"sine velocity 1 h: max horizontal error {horiz.max():.3g} m, attitude {att.max():.3g} deg, "
          f"height {np.abs(sol.h_m - tr.h_m[1:]).max():.3g} m (free vertical channel)")
    assert horiz.max() < 0.032
    assert att.max() < 3.3e-7
    assert np.abs(sol.v_n_m_s[:, :2] - tr.v_n_m_s[1:, :2]).max() < 5.6e-5


def test_coning_two_sample_beats_one_sample_by_theory():
    """Classic coning (half-angle a, angular frequency W, update interval h, l = W h).
    Per update, the rotation vector misses 1/2 sin^2 a (l - sin l) along the cone axis
    (Bortz term) without correction; the two-sample correction dtheta_(k-1) x dtheta_k /
    12 recovers (1/3) sin^2 a sin^2(l/2) sin l of it. The drift ratio one-sample /
    two-sample is therefore (l - sin l) / ((l - sin l) - (2/3) sin^2(l/2) sin l)
    (~ 5 / l^2). The simulated ratio must match within 3% (the formula neglects
    O(a^4) terms and the Earth rate's small cross-coupling)."""
    a, f, dt, dur = 1 * DEG, 5.0, 0.01, 20.0
    tr = tj.sample(tj.Coning(half_angle_rad=a, frequency_hz=f), dur, dt)
    lam = 2 * np.pi * f * dt
    ratio_theory = (lam - np.sin(lam)) / ((lam - np.sin(lam)) - 2 / 3 * np.sin(lam / 2) ** 2 * np.sin(lam))
    drift = {}
    for coning in (False, True):
        _, sol = _nav(tr, coning=coning)
        err = attitude_error_rad(sol.q_bn, tr.q_bn[1:])
        t = tr.t_s[1:]
        drift[coning] = abs(np.polyfit(t, err[:, 2], 1)[0])   # rad/s along the cone (up) axis
    ratio = drift[False] / drift[True]
    theory_one = 0.5 * np.sin(a) ** 2 * (lam - np.sin(lam)) / dt
    print(f"coning: one-sample drift {drift[False]:.4g} rad/s (theory {theory_one:.4g}), "
          f"two-sample {drift[True]:.4g} rad/s; ratio {ratio:.2f}, theory {ratio_theory:.2f}")
    assert drift[False] == pytest.approx(theory_one, rel=0.03)
    assert ratio == pytest.approx(ratio_theory, rel=0.03)


def test_schuler_period():
    """A 0.1 m/s north velocity error at rest oscillates with the Schuler period
    2 pi sqrt(R/g) (84.4 min): measured from the zero crossings of the velocity error
    over three periods, within 0.5% of 84.4 min and of the local value."""
    tr = tj.sample(tj.Stationary(), 3 * 5100.0, 0.1)
    x0 = gf.NavState.from_trajectory(tr, 0)
    x0.v_n_m_s = x0.v_n_m_s + [0.0, 0.1, 0.0]
    nav = gf.Strapdown(x0, gf.SinsConfig(vertical="hold", hold_height_m=float(tr.h_m[0])))
    sol = nav.run(tr.dtheta_rad, tr.dv_m_s, dt_s=tr.dt_s)
    e = sol.v_n_m_s[:, 1] - tr.v_n_m_s[1:, 1]
    t = sol.t_s
    i = np.flatnonzero(np.sign(e[:-1]) != np.sign(e[1:]))
    tz = t[i] - e[i] * (t[i + 1] - t[i]) / (e[i + 1] - e[i])     # interpolated zero crossings
    period_min = 2 * np.mean(np.diff(tz)) / 60
    RM, RN, _, _ = earth.radii(tr.lat_rad[0])
    local_min = 2 * np.pi * np.sqrt(np.sqrt(RM * RN) / earth.gravity(tr.lat_rad[0], tr.h_m[0])) / 60
    print(f"Schuler period: {period_min:.3f} min measured, {local_min:.3f} min local theory")
    assert len(tz) >= 5
    assert period_min == pytest.approx(84.4, rel=0.005)
    assert period_min == pytest.approx(local_min, rel=0.005)


def test_forward_then_reverse_returns_to_start():
    """10-minute dynamic record (circle), forward then reverse: the residual is the
    mechanization's truncation asymmetry (mid-point extrapolation), not round-off;
    measured 1.0e-5 m horizontal, 6.4e-8 m height, 2.3e-8 m/s, 1.3e-11 rad. Bounds: 2x
    those."""
    tr = tj.sample(tj.Circle(), 600.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    nav = gf.Strapdown(x0)
    fwd = nav.run(tr.dtheta_rad, tr.dv_m_s, dt_s=tr.dt_s)
    nav.reverse()
    back = nav.run(tr.dtheta_rad, tr.dv_m_s, dt_s=tr.dt_s)
    s = nav.state
    dpos = horizontal_error_m(np.array([s.lat_rad]), np.array([s.lon_rad]),
                              np.array([x0.lat_rad]), np.array([x0.lon_rad]))[0]
    dv = np.abs(s.v_n_m_s - x0.v_n_m_s).max()
    datt = np.linalg.norm(attitude_error_rad(s.q_bn, x0.q_bn))
    print(f"round trip 600 s: position {dpos:.3g} m, height {abs(s.h_m - x0.h_m):.3g} m, "
          f"velocity {dv:.3g} m/s, attitude {datt:.3g} rad, time {s.t_s:.3g} s")
    assert dpos < 2e-5 and abs(s.h_m - x0.h_m) < 1.3e-7
    assert dv < 4.6e-8 and datt < 2.7e-11
    assert abs(s.t_s - x0.t_s) < 1e-9
    # backward rows are the states at the start of each interval, in true-time velocity
    np.testing.assert_allclose(back.t_s[1:], fwd.t_s[:-1], atol=1e-9)
    np.testing.assert_allclose(back.v_n_m_s[1:], fwd.v_n_m_s[:-1], atol=1e-6)


def test_rates_input_and_time_stamps_agree():
    """Rate input reproduces the truth to the accuracy of linear interpolation, and a
    t_s array equal to the fixed grid gives the same solution as dt_s. Measured
    horizontal error 0.79 mm over 300 s; bound 2x."""
    tr = tj.sample(tj.SineVelocity(), 300.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    cfg = gf.SinsConfig(input="rates")
    a = gf.Strapdown(x0, cfg).run(tr.gyro_rad_s, tr.accel_m_s2, dt_s=0.01)
    b = gf.Strapdown(x0, cfg).run(tr.gyro_rad_s, tr.accel_m_s2, t_s=tr.t_s)
    np.testing.assert_allclose(b.lat_rad, a.lat_rad, rtol=0, atol=1e-13)
    horiz = horizontal_error_m(a.lat_rad, a.lon_rad, tr.lat_rad, tr.lon_rad)
    assert horiz.max() < 1.6e-3
    assert a.t_s[0] == 0.0 and a.t_s[-1] == pytest.approx(300.0)


def test_vertical_modes():
    tr = tj.sample(tj.SineVelocity(), 600.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    held = gf.Strapdown(x0, gf.SinsConfig(vertical="hold", hold_height_m=123.0)).run(
        tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)
    assert np.all(held.h_m == 123.0) and np.all(held.v_n_m_s[:, 2] == 0.0)
    # baro: a 2 m/s vertical velocity error is pulled back by the loop; with the free
    # channel it turns into a growing height error
    x1 = gf.NavState.from_trajectory(tr, 0)
    x1.v_n_m_s = x1.v_n_m_s + [0, 0, 2.0]
    free = gf.Strapdown(x1).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)
    baro = gf.Strapdown(x1, gf.SinsConfig(vertical="baro", baro_tau_s=10.0)).run(
        tr.dtheta_rad, tr.dv_m_s, dt_s=0.01, h_ext_m=tr.h_m[1:])
    e_free = np.abs(free.h_m - tr.h_m[1:])
    e_baro = np.abs(baro.h_m - tr.h_m[1:])
    assert e_free[-1] > 1000.0
    assert e_baro[-1] < 1e-3 and e_baro.max() < 20.0


def test_nonfinite_sample_keeps_solution_before_it(sine_1h):
    tr = sine_1h
    g, a = tr.dtheta_rad[:1000].copy(), tr.dv_m_s[:1000].copy()
    a[400, 1] = np.nan
    nav = gf.Strapdown(gf.NavState.from_trajectory(tr, 0))
    with pytest.raises(gf.NonFiniteInputError, match=r"accel\[400, 1\]") as exc:
        nav.run(g, a, dt_s=0.01)
    good = gf.Strapdown(gf.NavState.from_trajectory(tr, 0)).run(g[:400], a[:400], dt_s=0.01)
    assert len(exc.value.partial) == 400
    assert np.array_equal(exc.value.partial.lat_rad, good.lat_rad)
    assert nav.state.t_s == pytest.approx(4.0)   # the navigator stopped after sample 399


def test_absurd_rate_and_bad_times(sine_1h):
    tr = sine_1h
    g, a = tr.dtheta_rad[:100].copy(), tr.dv_m_s[:100].copy()
    g[10] = [0.0, 0.0, 1.0]          # 1 rad in 10 ms = 100 rad/s > 50 rad/s limit
    with pytest.raises(gf.SampleError, match=r"sample 10 exceeds \|w\| <= 50") as exc:
        gf.Strapdown(gf.NavState.from_trajectory(tr, 0)).run(g, a, dt_s=0.01)
    assert exc.value.index == 10 and len(exc.value.partial) == 10
    t = tr.t_s[1:101].copy()
    t[50] = t[49]                     # not strictly increasing
    with pytest.raises(gf.SampleError, match=r"sample 50 at t = 0.5 s does not come after 0.5 s, the previous sample.s; sample times must increase strictly"):
        gf.Strapdown(gf.NavState.from_trajectory(tr, 0)).run(tr.dtheta_rad[:100], tr.dv_m_s[:100], t_s=t)


@pytest.mark.parametrize("field, value, match", [
    ("lat_rad", np.radians(90.0), "outside"),
    ("lat_rad", np.radians(-91.0), "outside"),
    ("q_bn", np.zeros(4), "cannot be normalised"),
    ("q_bn", np.array([np.nan, 0, 0, 1.0]), r"initial\.q_bn must be finite"),
])
def test_bad_initial_state(field, value, match):
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    setattr(x0, field, value)
    with pytest.raises(ValueError, match=match):
        gf.Strapdown(x0)


def test_bad_config_and_arguments():
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    with pytest.raises(ValueError, match="input must be one of"):
        gf.Strapdown(x0, gf.SinsConfig(input="deltas"))
    with pytest.raises(ValueError, match="baro_tau_s"):
        gf.Strapdown(x0, gf.SinsConfig(baro_tau_s=0.0))
    nav = gf.Strapdown(x0)
    with pytest.raises(ValueError, match="exactly one of dt_s"):
        nav.run(np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"shape \(n, 3\)"):
        nav.run(np.zeros((3, 4)), np.zeros((3, 3)), dt_s=0.01)


@pytest.mark.parametrize("motion, duration, bound_m, bound_deg, bound_m_s", [
    (tj.Airdrop(), 200.0, 0.011, 3.8e-7, 5.2e-5),
    (tj.VehicleRun(), 1320.0, 0.0081, 7.5e-8, 3.4e-5),
    (tj.ConstantVelocity(), 600.0, 4.2e-5, 8.6e-10, 3.1e-10),
], ids=["airdrop", "vehicle-run-seed-001", "constant-velocity"])
def test_motions_navigate_to_truth(motion, duration, bound_m, bound_deg, bound_m_s):
    """Each motion's sensor outputs, navigated, give back its own trajectory: a check of
    the generator's consistency (velocity, acceleration, attitude and rates derived by
    hand) as much as of the mechanization. Measured (horizontal position, attitude,
    horizontal velocity): airdrop 5.4 mm, 1.9e-7 deg, 2.6e-5 m/s; vehicle run (22 min)
    4.0 mm, 3.7e-8 deg, 1.7e-5 m/s; constant velocity 2.1e-5 m, 4.3e-10 deg, 1.6e-10 m/s.
    Bounds: 2x those."""
    tr = tj.sample(motion, duration, 0.01)
    _, sol = _nav(tr)
    horiz = horizontal_error_m(sol.lat_rad, sol.lon_rad, tr.lat_rad[1:], tr.lon_rad[1:])
    att = np.degrees(np.linalg.norm(attitude_error_rad(sol.q_bn, tr.q_bn[1:]), axis=1))
    dv = np.abs(sol.v_n_m_s[:, :2] - tr.v_n_m_s[1:, :2]).max()
    print(f"{type(motion).__name__}: horizontal {horiz.max():.3g} m, attitude {att.max():.3g} deg, "
          f"horizontal velocity {dv:.3g} m/s")
    assert horiz.max() < bound_m
    assert att.max() < bound_deg
    assert dv < bound_m_s


def test_chunked_runs_equal_one_call_and_bad_chunk():
    tr = tj.sample(tj.Circle(), 20.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    one = gf.Strapdown(x0).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)
    for chunk in (1, 7, 333):
        part = gf.Strapdown(x0).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01, chunk=chunk)
        assert np.array_equal(part.lat_rad, one.lat_rad) and np.array_equal(part.q_bn, one.q_bn)
    for bad in (0, -5, 2.5, True):
        with pytest.raises(ValueError, match="chunk must be an integer >= 1"):
            gf.Strapdown(x0).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01, chunk=bad)


def test_backward_with_non_uniform_times_returns_to_start():
    """Increments on a non-uniform grid (first interval 0.02 s, then 0.01 s), forward
    then backward with the same t_s: back at the initial time and state."""
    tr = tj.sample(tj.Circle(), 60.0, 0.01)
    dth = np.r_[tr.dtheta_rad[:1] + tr.dtheta_rad[1:2], tr.dtheta_rad[2:]]
    dv = np.r_[tr.dv_m_s[:1] + tr.dv_m_s[1:2], tr.dv_m_s[2:]]
    t = tr.t_s[2:]
    x0 = gf.NavState.from_trajectory(tr, 0)
    nav = gf.Strapdown(x0)
    nav.run(dth, dv, t_s=t)
    nav.reverse()
    nav.run(dth, dv, t_s=t)
    s = nav.state
    assert s.t_s == pytest.approx(0.0, abs=1e-12)
    assert np.abs(s.v_n_m_s - x0.v_n_m_s).max() < 1e-4   # truncation of the merged step
    # one sample backward with times: interval from the initial time
    nav1 = gf.Strapdown(x0)
    nav1.run(dth[:1], dv[:1], t_s=t[:1])
    nav1.reverse()
    nav1.run(dth[:1], dv[:1], t_s=t[:1])
    assert nav1.state.t_s == pytest.approx(0.0, abs=1e-15)


def test_rate_input_reverse_round_trip():
    tr = tj.sample(tj.Circle(), 60.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    nav = gf.Strapdown(x0, gf.SinsConfig(input="rates"))
    nav.run(tr.gyro_rad_s, tr.accel_m_s2, dt_s=0.01)
    nav.reverse()
    back = nav.run(tr.gyro_rad_s, tr.accel_m_s2, dt_s=0.01)
    s = nav.state
    assert s.t_s == pytest.approx(0.0, abs=1e-9)
    assert np.linalg.norm(attitude_error_rad(s.q_bn, x0.q_bn)) < 1e-9
    assert horizontal_error_m(np.array([s.lat_rad]), np.array([s.lon_rad]),
                              np.array([x0.lat_rad]), np.array([x0.lon_rad]))[0] < 1e-3
    np.testing.assert_allclose(back.t_s, tr.t_s, atol=1e-9)   # row k: the state at t_k


def test_baro_loop_follows_a_climbing_height():
    """A 10 m/s climb with exact increments and an exact external height: the loop
    compares heights at the same instant, so it adds no lag (the free channel over
    this minute is itself accurate to millimetres). Measured 8.0e-7 m; bound 2x."""
    tr = tj.sample(tj.SineVelocity(amplitude_m_s=(2.0, 3.0, 10.0)), 300.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    sol = gf.Strapdown(x0, gf.SinsConfig(vertical="baro", baro_tau_s=10.0)).run(
        tr.dtheta_rad, tr.dv_m_s, dt_s=0.01, h_ext_m=tr.h_m[1:])
    err = np.abs(sol.h_m - tr.h_m[1:])
    print(f"baro, 10 m/s vertical amplitude: max height error {err.max():.3g} m")
    assert err.max() < 1.6e-6


def test_baro_without_external_height_is_refused():
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    with pytest.raises(ValueError, match='vertical="baro" needs h_ext_m'):
        gf.Strapdown(x0, gf.SinsConfig(vertical="baro")).run(np.zeros((3, 3)), np.zeros((3, 3)),
                                                               dt_s=0.01)


@pytest.mark.parametrize("q, match", [([np.nan, 0, 0, 0], "not a unit quaternion"),
                                      ([1.0, 0.5, 0, 0], "not a unit quaternion"),
                                      ([0.0, 0, 0, 0], "not a unit quaternion")])
def test_quat_to_euler_refuses_non_unit(q, match):
    with pytest.raises(ValueError, match=match):
        gf.quat_to_euler(q)
    with pytest.raises(ValueError, match=r"q_bn\[1\]"):
        gf.quat_to_euler([[1.0, 0, 0, 0], q])


@pytest.mark.parametrize("field, value, match", [
    ("lat_rad", np.nan, "initial.lat_rad"), ("h_m", -4e6, "below -a/2"),
    ("lon_rad", np.inf, "initial.lon_rad")])
def test_bad_initial_fields_are_named(field, value, match):
    x0 = gf.NavState.from_euler([0, 0, 0], [0, 0, 0], 0.5, 1.0, 0.0)
    setattr(x0, field, value)
    with pytest.raises(ValueError, match=match):
        gf.Strapdown(x0)


def test_sculling_two_sample_correction_by_theory():
    """Classic sculling in a fixed frame without gravity (SinsConfig(earth="flat")): the
    body rolls as theta(t) = a sin(W t) about x while its specific force along body y is
    A sin(W t). The rotated force rectifies into a mean vertical acceleration A J1(a)
    (Bessel), which an exact navigator integrates. Per update of h, with l = W h and the
    phases W t_k equally spaced over whole periods (l = 2 pi / 10), the one-sample
    algorithm (dv + 1/2 dtheta x dv) misses on average a A (l - sin l) / (2 l) per second
    (1/2 dtheta x dv averages to zero, the exact rotation term does not); the two-sample
    correction (dtheta_(k-1) x dv_k + dv_(k-1) x dtheta_k) / 12 recovers
    a A (2 sin l - sin 2l) / (12 l) of it (both worked by hand in the averages of the
    products of sines; the residual ~ a A l^4 / 60). Rotation about one axis has no
    coning, so coning=False/True switch exactly the sculling term here.
    Neglected: O(a^2) relative (1e-4) and the bounded oscillating velocity in the line
    fit over 20 s. Measured agreement: 7e-5 (one-sample) and 6.4e-4 (two-sample)
    relative; bound 5e-3 (8x the larger). Dropping the sculling term from gf_sins makes
    the two-sample drift 13x its theory (checked by planting it)."""
    from scipy.special import j1
    a, A, f_hz, dt, dur = 0.01, 10.0, 10.0, 0.01, 20.0
    W = 2 * np.pi * f_hz
    lam = W * dt
    t = np.arange(int(round(dur / dt)) + 1) * dt
    dth = np.zeros((t.size - 1, 3))
    dth[:, 0] = np.diff(a * np.sin(W * t))                              # exact increments
    dv = np.zeros((t.size - 1, 3))
    dv[:, 1] = A / W * (np.cos(W * t[:-1]) - np.cos(W * t[1:]))
    x0 = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), 0.0, 0.0, 0.0, 0.0, np.zeros(3))
    theory = {False: a * A * (lam - np.sin(lam)) / (2 * lam),
              True: a * A * ((lam - np.sin(lam)) / 2 - (2 * np.sin(lam) - np.sin(2 * lam)) / 12) / lam}
    for coning, expected in theory.items():
        sol = gf.Strapdown(x0, gf.SinsConfig(coning=coning, earth="flat")).run(dth, dv, dt_s=dt)
        drift = A * j1(a) - np.polyfit(sol.t_s, sol.v_n_m_s[:, 2], 1)[0]   # m/s^2 missed
        print(f"sculling, coning={coning}: velocity drift error {drift:.6g} m/s^2, theory {expected:.6g}")
        assert drift == pytest.approx(expected, rel=5e-3)


def test_held_height_defaults_to_the_initial_state():
    """SinsConfig(vertical="hold") holds the initial state's height unless told another
    (before: 0 m, discarding the initial height; the CLI held --h0)."""
    tr = tj.sample(tj.Circle(), 5.0, 0.01)
    x0 = gf.NavState.from_trajectory(tr, 0)
    assert x0.h_m == 100.0
    sol = gf.Strapdown(x0, gf.SinsConfig(vertical="hold")).run(tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)
    assert np.all(sol.h_m == x0.h_m)
    sol = gf.Strapdown(x0, gf.SinsConfig(vertical="hold", hold_height_m=42.0)).run(
        tr.dtheta_rad, tr.dv_m_s, dt_s=0.01)
    assert np.all(sol.h_m == 42.0)
    g = gf.layout("qin9", 0.1)
    sol, _ = gf.GyroFreeNavigator(g, x0, "sqrt", tr.gyro_rad_s[0],
                                  sins=gf.SinsConfig(vertical="hold")).run(tr.array_outputs(g), 0.01)
    assert np.all(sol.h_m == x0.h_m)
    from gfins_fmi.fmi.models import run_sins_fmu
    fmu = run_sins_fmu(tr.dtheta_rad[:20], tr.dv_m_s[:20], 0.01, x0, config=gf.SinsConfig(vertical="hold"))
    assert np.all(fmu.h_m == x0.h_m)
