"""Integrated navigation (csrc/est/gf_ins_gnss, gfins_fmi.estimation.navigator) on exact
sensors: residuals at the mechanization's truncation level with measurements off the IMU
grid, subsample groups, reported stds in metres, the process noise between propagations,
lever arms, odometer and NHC, refused input, stale and delayed measurements. The Kalman
engine's pieces: test_kalman_engine.py; the error model: test_ins_error_model.py.

Truth: exact sensor outputs of the closed-form vehicle (gf_vehicle, checked against the
independent Python trajectory generator in test_vehicle.py) and statistics of seeded noise.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.nav import earth
from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.estimation import FilterConfig, FilterError, InitialState, IntegratedNavigator
from support.drives import Rec, drive, gnss_record, quiet_config
from support.truth import OMEGA, radii


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
    with pytest.raises(ValueError, match="FilterConfig.subsamples = 5: must be an integer in 1..4"):
        quiet_config(subsamples=5)
    with pytest.raises(ValueError, match="more than 1 only with input 'increments'"):
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


@pytest.mark.parametrize("kind", ["increments", "rates"])
def test_sensor_estimates_compensate_every_axis(exact_drive, kind):
    """Raw samples made from the exact ones with a bias and a scale factor on every axis
    of both sensors, all different (raw = (1 + s) true + b, b integrated over the interval
    for increments), and the filter told them as its initial sensor estimates: its free
    inertial run (no measurements) is the run of the exact samples with zero estimates,
    to the round-off of the compensation (1 + s)^-1 ((1 + s) x) ~ 2 eps relative per
    sample (measured over 60 s: 1.8e-15 of the largest velocity, 3e-16 on q; bounds 1e-12
    and 1e-14). A gyro scale used for the accelerometer, a bias of the wrong sensor or
    sign, or one axis for another moves the velocity by ~0.1 m/s within seconds; without
    the estimates: 2.2 m/s."""
    tr, imu = exact_drive
    n = 6000
    bg, ba = np.array([1.1e-4, -1.3e-4, 1.7e-4]), np.array([0.023, -0.029, 0.031])
    sg, sa = np.array([1.9e-3, -2.3e-3, 2.9e-3]), np.array([-3.1e-3, 3.7e-3, -4.1e-3])
    sensors = np.r_[bg, ba, sg, sa, 0.0, 0.0, 0.0, 0.0]
    if kind == "increments":
        t, g, a = imu.t_s[:n], imu.gyro[:n], imu.accel[:n]
        dt = np.diff(np.r_[tr.t_s[0], t])[:, None]
        raw = Rec(t_s=t, gyro=(1 + sg) * g + bg * dt, accel=(1 + sa) * a + ba * dt, kind=kind)
        exact = Rec(t_s=t, gyro=g, accel=a, kind=kind)
    else:
        sl = slice(0, 10 * n, 10)
        t, g, a = tr.t_s[sl], tr.gyro_rad_s[sl], tr.accel_m_s2[sl]
        raw = Rec(t_s=t, gyro=(1 + sg) * g + bg, accel=(1 + sa) * a + ba, kind=kind)
        exact = Rec(t_s=t, gyro=g, accel=a, kind=kind)
    cfg = quiet_config(input=kind, scale_factors=True)
    nav0 = gf.NavState.from_trajectory(tr, 0)
    with_errors = IntegratedNavigator(cfg, InitialState(nav0, sensors=sensors)).run(raw)
    clean = IntegratedNavigator(cfg, InitialState(nav0)).run(exact)
    scale = np.abs(clean.v_n_m_s).max()
    assert np.abs(with_errors.v_n_m_s - clean.v_n_m_s).max() < 1e-12 * scale
    assert np.abs(with_errors.q_bn - clean.q_bn).max() < 1e-14
    # and without the estimates the errors show: the check can fail
    blind = IntegratedNavigator(cfg, InitialState(nav0)).run(raw)
    assert np.abs(blind.v_n_m_s - clean.v_n_m_s).max() > 0.1


def test_gate_rejects_then_forces_after_its_count(exact_drive):
    """gate_reset_count = 3: GNSS position epochs 60 m off are rejected by the gate; the
    fourth in a row is applied (forced); an accepted epoch starts the count again. Epochs
    (b: bad, g: good): b b g b b b b -> rejected, rejected, accepted, rejected, rejected,
    rejected, forced."""
    tr, imu = exact_drive
    k = np.arange(1003, 7004, 1000)                  # 7 epochs, 1 Hz
    g = gnss_record(tr, k, std=(0.5, 0.5, 1.0))
    bad = np.array([1, 1, 0, 1, 1, 1, 1], bool)
    g.lat_rad = g.lat_rad + bad * 60.0 / 6.37e6     # 60 m north, 120 sigma
    cfg = quiet_config(gate_probability=0.9999, gate_reset_count=3)
    sol = start(tr, cfg, position_std_m=0.5, velocity_std_m_s=0.05,
                attitude_std_rad=1e-3).run(imu, Rec(t_s=g.t_s, lat_rad=g.lat_rad, lon_rad=g.lon_rad,
                                                    h_m=g.h_m, pos_std_m=g.pos_std_m))
    st = sol.innovations_of("gnss_pos")["status"]
    assert list(st) == [lib.GF_INS_REJECTED_GATE] * 2 + [lib.GF_INS_ACCEPTED] + \
        [lib.GF_INS_REJECTED_GATE] * 3 + [lib.GF_INS_FORCED], list(st)


def test_nhc_keeps_its_own_interval(exact_drive):
    """NHC updates come every nhc_interval_s (0.3 s here), whatever the ZUPT interval
    (0.1 s): the log's NHC times are 0.3 s apart."""
    tr, imu = exact_drive
    cfg = quiet_config(nhc=True, nhc_interval_s=0.3, zupt_interval_s=0.1, propagation_interval_s=0.1)
    sol = start(tr, cfg).run(Rec(t_s=imu.t_s[:1000], gyro=imu.gyro[:1000], accel=imu.accel[:1000],
                                 kind="increments"))
    dt = np.diff(sol.innovations_of("nhc")["t_s"])
    assert len(dt) > 20 and np.allclose(dt, 0.3, atol=1e-9), dt[:5]


@pytest.mark.parametrize("yaw_rate, still", [(0.005, True), (0.02, False)])
def test_standstill_needs_a_small_mean_rate(yaw_rate, still):
    """At rest on the ground turning about the vertical at a constant rate: the specific
    force is steady, so only the gyro thresholds decide; standstill_gyro_rad_s = 0.01
    rad/s: 0.005 rad/s is standstill, 0.02 rad/s is not (it is below the accelerometer's
    threshold 0.05 and below 3 x 0.01, so only the mean-rate test refuses it)."""
    lat = 0.6
    n, dt = 400, 0.01
    g = np.array([0.0, 0.0, 9.80])
    w_ie = np.array([0.0, OMEGA * np.cos(lat), OMEGA * np.sin(lat)])
    gyro = np.tile(w_ie + [0.0, 0.0, yaw_rate], (n, 1))      # level: body = ENU at the start
    accel = np.tile(g, (n, 1))
    t = dt * np.arange(1, n + 1)
    nav0 = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), lat, 2.0, 50.0, 0.0)
    cfg = quiet_config(input="rates", zupt=True, standstill_gyro_rad_s=0.01,   # the detector
                       standstill_accel_std_m_s2=0.05, standstill_window_s=0.5)    # runs with zupt
    sol = IntegratedNavigator(cfg, InitialState(nav0)).run(
        Rec(t_s=np.r_[0.0, t[:-1]], gyro=gyro, accel=accel, kind="rates"))
    assert bool(sol.standstill[-1]) is still
    assert (len(sol.innovations_of("zupt")) > 0) is still


@pytest.mark.parametrize("kind", ["increments", "rates"])
def test_standstill_is_found_one_window_after_the_start(kind):
    """At rest from the start: the detector (exponential averages over
    standstill_window_s = 0.5 s, seeded with the first sample) says standstill once the
    IMU has been quiet for one window, at 0.5 s (+ one 10 ms sample), for increments and
    rates alike. (Rates: the first sample only starts the record; the averages were not
    seeded from it, so they rose from zero and |f|'s spread stayed above its threshold
    for 5.3 s.)"""
    lat, n, dt = 0.6, 200, 0.01
    w_ie = np.array([0.0, OMEGA * np.cos(lat), OMEGA * np.sin(lat)])
    f = np.array([0.0, 0.0, 9.8])
    nav0 = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), lat, 2.0, 50.0, 0.0)
    if kind == "rates":
        rec = Rec(t_s=dt * np.arange(n), gyro=np.tile(w_ie, (n, 1)), accel=np.tile(f, (n, 1)), kind=kind)
    else:
        rec = Rec(t_s=dt * np.arange(1, n + 1), gyro=np.tile(w_ie * dt, (n, 1)),
                  accel=np.tile(f * dt, (n, 1)), kind=kind)
    sol = IntegratedNavigator(quiet_config(input=kind, zupt=True), InitialState(nav0)).run(rec)
    first = sol.t_s[np.argmax(sol.standstill)]
    assert sol.standstill.any() and 0.5 - 1e-9 <= first <= 0.5 + dt + 1e-9, (kind, first)
