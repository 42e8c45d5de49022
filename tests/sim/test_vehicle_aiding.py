"""Aiding sensors on the vehicle (C gf_aiding_sim through gfins_fmi.sim.vehicle and the
vehicle FMU): GNSS antenna position and velocity and odometer speed against numpy
derivations on the independent trajectory generator (gfins_fmi.sim.trajectory: its own
WGS-84, closed forms), the antenna velocity against finite differences of the antenna
position, noise statistics against their definitions (chi-square bounds, fixed seeds),
outage and latency semantics, and the FMU (FMI 2.0 and 3.0) against the batch, bit for
bit.

Chi-square bounds: for n independent N(0, s^2) samples, (n - 1) var / s^2 follows
chi2(n - 1); each check accepts the central 1 - 1e-4 of it (a false alarm once in 10^4
per check with a random seed; the seeds here are fixed, so the outcome is reproducible)."""
import numpy as np
import pytest
from scipy.stats import chi2

from gfins_fmi.fmi.runner import FmuLog, FmuSlave
from gfins_fmi.fmi.paths import fmu_path
from gfins_fmi.nav.earth import WGS84, quat_to_dcm, radii
from gfins_fmi.sim.trajectory import VehicleRun
from gfins_fmi.sim.vehicle import (Barometer, GnssReceiver, Odometer, VehicleProfile,
                                   simulate_vehicle)

# 2 s at rest, a start to 15 m/s in 3 s, a 180 deg turn in 6 s: lever-arm velocities up
# to 1 rad/s x 1.5 m; the same motion as the trajectory generator's VehicleRun
KW = dict(align_s=2.0, accel_s=3.0, turn_times_s=(6.0,), turn_s=6.0)
PROFILE = VehicleProfile.seed001(**KW)
MOTION = VehicleRun(**KW)
L_GNSS = np.array([0.4, 1.2, 1.5])
L_ODO = np.array([0.8, -1.3, -0.4])


def _chi2_ok(x, std):
    """Sample variance of x (zero-mean N(0, std^2) expected) inside the chi-square bounds."""
    x = np.ravel(x)
    n = x.size
    stat = (n - 1) * np.var(x, ddof=1) / std ** 2
    lo, hi = chi2.ppf([0.5e-4, 1 - 0.5e-4], n - 1)
    return lo <= stat <= hi, (stat / (n - 1), lo / (n - 1), hi / (n - 1))


def _enu_error_m(lat, lon, h, lat_t, lon_t, h_t):
    """Geodetic differences -> ENU metres with the radii at the truth (the mapping of
    CONVENTIONS_AIDING.md; the radii at the antenna instead of the IMU change this by
    |l| / R ~ 2e-7 relative, far below the statistics' resolution)."""
    RM, RN, _, _ = radii(lat_t)
    return np.c_[(lon - lon_t) * (RN + h_t) * np.cos(lat_t), (lat - lat_t) * (RM + h_t), h - h_t]


# ---- truth -----------------------------------------------------------------------------
def _independent_truth(t):
    """Antenna position/velocity and wheel speed at times t from VehicleRun (numpy), with
    the lever-arm formulas written out here."""
    st = MOTION.state(t)
    C = quat_to_dcm(st["q_bn"])                                  # C_b^n, (n, 3, 3)
    L, h, v = st["lat"], st["h"], st["v_n"]
    RM, RN, _, _ = radii(L)
    w_ie_n = WGS84.omega_ie * np.c_[np.zeros_like(L), np.cos(L), np.sin(L)]
    w_eb_b = st["gyro"] - np.einsum("nji,nj->ni", C, w_ie_n)    # w_ib^b - C^T w_ie^n
    l_n = C @ L_GNSS
    lat = L + l_n[:, 1] / (RM + h)
    lon = st["lon"] + l_n[:, 0] / ((RN + h) * np.cos(L))
    v_ant = v + np.einsum("nij,nj->ni", C, np.cross(w_eb_b, L_GNSS))
    v_b = np.einsum("nji,nj->ni", C, v)
    speed = (v_b + np.cross(w_eb_b, L_ODO))[:, 1]
    return lat, lon, h + l_n[:, 2], v_ant, speed


def test_gnss_and_odometer_truth_equal_independent_derivation():
    rec = simulate_vehicle(PROFILE, 16.0, 0.01, gnss=GnssReceiver(rate_hz=20.0, offset_s=0.0137,
                           lever_arm_m=L_GNSS), odometer=Odometer(rate_hz=50.0, offset_s=0.0051,
                           lever_arm_m=L_ODO))
    g, o = rec.aiding_truth.gnss, rec.aiding_truth.odometer
    assert len(g.t_s) == 320 and len(o.t_s) == 800
    lat, lon, h, v, _ = _independent_truth(g.t_s)
    # two implementations of the same closed-form path (independent quadratures of the
    # displacement, tests/sim/test_vehicle.py): round-off. Measured 0 rad, 0 m, 1.1e-14 m/s
    # (velocity), 1.4e-14 m/s (wheel); bounds a few ulps: 1e-15 rad (0.5 rad: ulp 1.1e-16),
    # 1e-13 m (ulp of 100 m: 1.4e-14), 1e-13 m/s (ulp of 15 m/s: 1.8e-15)
    assert np.max(np.abs(g.lat_rad - lat)) <= 1e-15 and np.max(np.abs(g.lon_rad - lon)) <= 1e-15
    assert np.max(np.abs(g.h_m - h)) <= 1e-13
    assert np.max(np.abs(g.vel_enu_m_s - v)) <= 1e-13
    speed = _independent_truth(o.t_s)[4]
    assert np.max(np.abs(o.speed_m_s - speed)) <= 1e-13
    # the lever arm matters here: the turn moves the antenna by up to 1.5 m/s sideways
    assert np.max(np.abs(g.vel_enu_m_s - MOTION.state(g.t_s)["v_n"])) > 0.5


def test_gnss_velocity_is_the_derivative_of_the_antenna_position():
    """Central differences of the antenna's geodetic position (1 kHz epochs), converted
    to ENU with the radii at the epoch, against the reported true velocity. They differ
    by the rotation of the ENU frame between the IMU and the antenna and the change of
    the radii along the lever arm, O(|w_en| |l|) ~ 2.3e-6 rad/s x 1.97 m = 4.6e-6 m/s at
    15 m/s; the difference quotient's round-off is 1e-16 x 6.4e6 m / 2e-3 s = 3e-7 m/s and
    its truncation (jerk x dt^2 / 6) far less. Measured 3.9e-6 m/s; bound 2e-5."""
    rec = simulate_vehicle(PROFILE, 16.0, 0.5, gnss=GnssReceiver(rate_hz=1000.0,
                           lever_arm_m=L_GNSS))
    g = rec.aiding_truth.gnss
    RM, RN, _, _ = radii(g.lat_rad[1:-1])
    dt = g.t_s[2:] - g.t_s[:-2]                                  # 2 ms
    h = g.h_m[1:-1]
    v_fd = np.c_[(g.lon_rad[2:] - g.lon_rad[:-2]) / dt * (RN + h) * np.cos(g.lat_rad[1:-1]),
                 (g.lat_rad[2:] - g.lat_rad[:-2]) / dt * (RM + h), (g.h_m[2:] - g.h_m[:-2]) / dt]
    err = np.max(np.abs(v_fd - g.vel_enu_m_s[1:-1]))
    assert err <= 2e-5, err


def test_odometer_wheel_speed_physics():
    """A wheel 1 m to the right of the IMU in a right turn of rate r runs at u - r (the
    inner wheel); 1 m ahead or below it, at u (the yaw rate moves it sideways only). The
    Earth and transport rates add up to |w_ie + w_en| x 1 m = 7.4e-5 m/s (measured
    1.6e-5); bound 1e-4."""
    prof = VehicleProfile.circle(radius_m=20.0, speed_m_s=8.0)       # a left turn: r = -0.4
    speeds = []
    for arm in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]):
        rec = simulate_vehicle(prof, 5.0, 0.01, odometer=Odometer(rate_hz=10.0, lever_arm_m=arm))
        speeds.append(rec.aiding_truth.odometer.speed_m_s)
    assert np.allclose(speeds[0], 8.0 + 0.4, rtol=0, atol=1e-4)
    assert np.allclose(speeds[1], 8.0, rtol=0, atol=1e-4)
    assert np.allclose(speeds[2], 8.0, rtol=0, atol=1e-4)


# ---- noise -----------------------------------------------------------------------------
def _long_run(**sensors):
    """1000 s (straight at 15 m/s after the start), IMU record at 1 s (unused)."""
    return simulate_vehicle(VehicleProfile.seed001(align_s=10.0, turn_times_s=()), 1000.0, 1.0,
                            seed=2024, **sensors)


def test_gnss_white_noise_statistics():
    pos_std, vel_std = np.array([1.0, 1.5, 3.0]), np.array([0.05, 0.07, 0.1])
    rec = _long_run(gnss=GnssReceiver(rate_hz=20.0, lever_arm_m=L_GNSS, pos_std_m=pos_std,
                                      vel_std_m_s=vel_std))
    g, t = rec.gnss, rec.aiding_truth.gnss
    assert len(g.t_s) == 20001
    e = _enu_error_m(g.lat_rad, g.lon_rad, g.h_m, t.lat_rad, t.lon_rad, t.h_m)
    ev = g.vel_enu_m_s - t.vel_enu_m_s
    for i in range(3):
        ok, info = _chi2_ok(e[:, i], pos_std[i])
        assert ok, ("position", i, info)
        ok, info = _chi2_ok(ev[:, i], vel_std[i])
        assert ok, ("velocity", i, info)
        # means: 4.5 standard errors (2 sided 7e-6)
        assert abs(e[:, i].mean()) < 4.5 * pos_std[i] / np.sqrt(len(e))
    # white: no correlation between epochs (lag-1 coefficient, std 1/sqrt(n) = 0.007)
    assert abs(np.corrcoef(e[1:, 0], e[:-1, 0])[0, 1]) < 4.5 / np.sqrt(len(e))
    assert np.array_equal(g.pos_std_m, np.tile(pos_std, (len(e), 1)))
    assert np.array_equal(g.vel_std_m_s, np.tile(vel_std, (len(e), 1)))
    assert np.all(g.quality == 5) and g.quality.dtype == np.int8


def test_gnss_gauss_markov_statistics():
    """Position error y_k = a y_(k-1) + w_k, a = exp(-dt / tau): the innovations w are
    N(0, sigma^2 (1 - a^2)) and independent; the reported std is sigma (no white part)."""
    sigma, tau, rate = np.array([0.5, 0.8, 1.2]), 5.0, 20.0
    rec = _long_run(gnss=GnssReceiver(rate_hz=rate, pos_std_m=(0, 0, 0), pos_gm_std_m=sigma,
                                      pos_gm_tau_s=tau))
    g, t = rec.gnss, rec.aiding_truth.gnss
    y = _enu_error_m(g.lat_rad, g.lon_rad, g.h_m, t.lat_rad, t.lon_rad, t.h_m)
    a = np.exp(-1.0 / rate / tau)
    w = y[1:] - a * y[:-1]
    for i in range(3):
        ok, info = _chi2_ok(w[:, i], sigma[i] * np.sqrt(1 - a * a))
        assert ok, (i, info)
    assert abs(np.corrcoef(w[1:, 0], w[:-1, 0])[0, 1]) < 4.5 / np.sqrt(len(w))
    assert np.allclose(g.pos_std_m, sigma, rtol=1e-15)


def test_barometer_bias_and_noise_statistics():
    rate, std, K, b0 = 10.0, 0.4, 0.05, 3.0
    rec = _long_run(baro=Barometer(rate_hz=rate, std_m=std, bias0_m=b0, bias_rw_m_sqrt_s=K))
    b, t = rec.baro, rec.aiding_truth
    bias = t.baro_bias_m
    assert len(b.t_s) == 10001 and bias[0] == b0            # the walk starts at 0
    ok, info = _chi2_ok(b.h_m - t.baro.h_m - bias, std)
    assert ok, ("white", info)
    ok, info = _chi2_ok(np.diff(bias), K * np.sqrt(1 / rate))
    assert ok, ("random walk steps", info)
    assert np.all(b.std_m == std) and np.all(t.baro.h_m == 100.0)
    sigma, tau = 0.8, 20.0
    rec = _long_run(baro=Barometer(rate_hz=rate, std_m=0.0, bias_gm_std_m=sigma, bias_gm_tau_s=tau))
    y = rec.baro.h_m - rec.aiding_truth.baro.h_m
    # no white part: (h + b) - h = b to an ulp of h (1.4e-14 m)
    assert np.max(np.abs(y - rec.aiding_truth.baro_bias_m)) <= 3e-14
    a = np.exp(-1 / rate / tau)
    ok, info = _chi2_ok(y[1:] - a * y[:-1], sigma * np.sqrt(1 - a * a))
    assert ok, ("Gauss-Markov innovations", info)


def test_odometer_scale_error_and_noise_statistics():
    k, std = 0.02, 0.03
    rec = _long_run(odometer=Odometer(rate_hz=50.0, lever_arm_m=L_ODO, scale_error=k, std_m_s=std))
    o, t = rec.odometer, rec.aiding_truth.odometer
    ok, info = _chi2_ok(o.speed_m_s - (1 + k) * t.speed_m_s, std)
    assert ok, info
    # the scale error: regression through 0 of the measured on the true speed; standard
    # error std / sqrt(sum u^2) = 9e-6 (measured offset 1.1e-5); bound 5 of them
    moving = t.speed_m_s > 1.0
    u = t.speed_m_s[moving]
    slope = np.sum(o.speed_m_s[moving] * u) / np.sum(u ** 2)
    assert abs(slope - (1 + k)) <= 5 * std / np.sqrt(np.sum(u ** 2))


def test_seeds_and_independent_streams():
    gnss, baro = GnssReceiver(rate_hz=5.0), Barometer(rate_hz=5.0)
    a = simulate_vehicle(PROFILE, 10.0, 0.1, gnss=gnss, baro=baro, seed=7)
    b = simulate_vehicle(PROFILE, 10.0, 0.1, gnss=gnss, seed=7)
    c = simulate_vehicle(PROFILE, 10.0, 0.1, gnss=gnss, baro=baro, seed=8)
    assert np.array_equal(a.gnss.lat_rad, b.gnss.lat_rad)         # baro has its own stream
    assert not np.array_equal(a.gnss.lat_rad, c.gnss.lat_rad)
    assert np.array_equal(a.aiding_truth.gnss.lat_rad, c.aiding_truth.gnss.lat_rad)


# ---- timing ----------------------------------------------------------------------------
def test_epoch_times_outages_and_latency():
    """Epoch k valid at (t0 + offset) + k / rate, delivered at + latency if that is by the
    end of the record, unless valid in [start, end) of an interval or of the periodic
    rule (first 10 s, every 4 s, 1 s long)."""
    t0, end = 100.0, 120.0
    gnss = GnssReceiver(rate_hz=10.0, offset_s=0.05, latency_s=0.23, outages_s=[(103.0, 104.5), (107.25, 107.55)],
                        outage_first_s=110.0, outage_period_s=4.0, outage_duration_s=1.0)
    rec = simulate_vehicle(PROFILE, end - t0, 0.01, start_time_s=t0, gnss=gnss)
    k = np.arange(400)
    t = (t0 + 0.05) + k / 10.0
    out = ((t >= 103.0) & (t < 104.5)) | ((t >= 107.25) & (t < 107.55)) | \
          ((t >= 110.0) & (np.fmod(t - 110.0, 4.0) < 1.0))
    want = t[~out & (t + 0.23 <= end)]
    assert np.array_equal(rec.gnss.t_s, want)
    assert np.array_equal(rec.aiding_truth.gnss_delivered_s, want + 0.23)
    assert want[-1] == pytest.approx(119.75)       # 119.85 + 0.23 is after the end
    # an outage masks epochs only: the noise of the others is the same as without it
    free = simulate_vehicle(PROFILE, end - t0, 0.01, start_time_s=t0,
                            gnss=GnssReceiver(rate_hz=10.0, offset_s=0.05, latency_s=0.23))
    keep = np.isin(free.gnss.t_s, want)
    assert np.array_equal(free.gnss.lat_rad[keep], rec.gnss.lat_rad)


def test_bad_sensor_parameters_say_what_to_change():
    cases = [(dict(gnss=GnssReceiver(rate_hz=0.0)), "GnssReceiver.rate_hz must be finite, > 0"),
             (dict(gnss=GnssReceiver(rate_hz=10.0, latency_s=2.0)), "GnssReceiver.latency_s"),
             (dict(gnss=GnssReceiver(outages_s=[(5.0, 4.0)])), r"GnssReceiver.outages_s\[0\]"),
             (dict(gnss=GnssReceiver(outages_s=[(1.0, 2.0)] * 9)), "at most 8"),
             (dict(gnss=GnssReceiver(outage_duration_s=2.0, outage_period_s=1.0)), "outage_period_s"),
             (dict(gnss=GnssReceiver(quality=7)), "GnssReceiver.quality must be 0 .. 6"),
             (dict(gnss=GnssReceiver(lever_arm_m=(0, 1))), "lever_arm_m must have shape \\(3,\\)"),
             (dict(baro=Barometer(bias_gm_std_m=1.0, bias_gm_tau_s=0.0)), "Barometer.bias_gm_tau_s"),
             (dict(odometer=Odometer(scale_error=0.5)), "Odometer.scale_error"),
             (dict(odometer=Odometer(), seed=-1), "seed")]
    for kw, text in cases:
        with pytest.raises(ValueError, match=text):
            simulate_vehicle(PROFILE, 1.0, 0.1, **kw)
    with pytest.raises(TypeError, match="GnssReceiver.quality must be an integer"):
        simulate_vehicle(PROFILE, 1.0, 0.1, gnss=GnssReceiver(quality=1.5))
    with pytest.raises(TypeError, match="gnss must be a GnssReceiver"):
        simulate_vehicle(PROFILE, 1.0, 0.1, gnss=Barometer())


# ---- the FMU ---------------------------------------------------------------------------
SENSORS = dict(gnss=GnssReceiver(rate_hz=5.0, offset_s=0.0137, latency_s=0.12, lever_arm_m=L_GNSS,
                                 pos_gm_std_m=(0.4, 0.4, 0.9), pos_gm_tau_s=20.0,
                                 outages_s=[(6.0, 8.0)], outage_first_s=10.0,
                                 outage_period_s=3.0, outage_duration_s=1.0),
               baro=Barometer(rate_hz=25.0, offset_s=0.004, bias0_m=3.0, bias_rw_m_sqrt_s=0.02,
                              bias_gm_std_m=0.3, bias_gm_tau_s=30.0),
               odometer=Odometer(rate_hz=50.0, offset_s=0.0051, lever_arm_m=L_ODO, scale_error=0.004))
GNSS_OUT = ["gnss_time_s", "gnss_lat_rad", "gnss_lon_rad", "gnss_h_m", "gnss_vel_enu_m_s",
            "gnss_pos_std_m", "gnss_vel_std_m_s", "gnss_quality"]


def _run_fmu(version, params, stop_s, h=0.01, extra=(), drive=None):
    names = ["gnss_valid", "baro_valid", "odo_valid", *GNSS_OUT, "baro_time_s", "baro_h_m",
             "baro_std_m", "odo_time_s", "odo_speed_m_s", "odo_std_m_s", *extra]
    s = FmuSlave(fmu_path("vehicle", version), version, FmuLog(), False)
    try:
        s.initialize(0.0, stop_s, params)
        rows = [[s.get(n) for n in names]]
        n = int(round(stop_s / h))
        for k in range(n):
            if drive:
                drive(s, k * h)
            s.slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            rows.append([s.get(n) for n in names])
    finally:
        s.close()
    return {name: np.array([r[i] for r in rows]) for i, name in enumerate(names)}


def _delivered(r, valid, names):
    rows = np.flatnonzero(r[valid][:, 0] > 0)
    return rows, {n: r[n][rows] for n in names}


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_aiding_equals_batch_bit_for_bit(version):
    stop = 16.0
    rec = simulate_vehicle(PROFILE, stop, 0.01, seed=11, **SENSORS)
    params = {**PROFILE.as_parameters(), "noise_seed": 11,
              **{k: v for s in SENSORS.values() for k, v in s.fmu_parameters().items()}}
    r = _run_fmu(version, params, stop)
    assert np.all(r["gnss_valid"] <= 1) and np.all(r["baro_valid"] <= 1) and np.all(r["odo_valid"] <= 1)
    rows, g = _delivered(r, "gnss_valid", GNSS_OUT)
    want = rec.gnss
    assert len(rows) == len(want.t_s) == 80 - 10 - 10         # 5 Hz, outages 2 s and 2 x 1 s
    for name, ref in [("gnss_time_s", want.t_s), ("gnss_lat_rad", want.lat_rad),
                      ("gnss_lon_rad", want.lon_rad), ("gnss_h_m", want.h_m),
                      ("gnss_vel_enu_m_s", want.vel_enu_m_s), ("gnss_pos_std_m", want.pos_std_m),
                      ("gnss_vel_std_m_s", want.vel_std_m_s), ("gnss_quality", want.quality)]:
        assert np.array_equal(g[name].reshape(ref.shape), ref), name
    # delivered in the first step whose end (row k: k h) reaches t + latency
    due = rec.aiding_truth.gnss_delivered_s
    assert np.all(rows * 0.01 >= due - 1e-12) and np.all((rows - 1) * 0.01 < due)
    rows, b = _delivered(r, "baro_valid", ["baro_time_s", "baro_h_m", "baro_std_m"])
    assert np.array_equal(b["baro_time_s"][:, 0], rec.baro.t_s)
    assert np.array_equal(b["baro_h_m"][:, 0], rec.baro.h_m)
    assert np.array_equal(b["baro_std_m"][:, 0], rec.baro.std_m)
    rows, o = _delivered(r, "odo_valid", ["odo_time_s", "odo_speed_m_s"])
    assert np.array_equal(o["odo_time_s"][:, 0], rec.odometer.t_s)
    assert np.array_equal(o["odo_speed_m_s"][:, 0], rec.odometer.speed_m_s)
    # before the first epoch: NaN and quality 0; then held between epochs
    assert np.isnan(r["gnss_lat_rad"][0, 0]) and r["gnss_quality"][0, 0] == 0
    first = np.flatnonzero(r["gnss_valid"][:, 0])[0]
    assert np.array_equal(r["gnss_lat_rad"][first + 1], r["gnss_lat_rad"][first])


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_epoch_at_the_start_and_on_the_step_grid(version):
    """offset 0, no latency, 10 Hz epochs on the 0.01 s grid: the first is delivered by
    initialization, each other in the step ending at it (the master's clock k h differs
    from k / 10 by an ulp: the glue's tolerance), every one once."""
    gnss = GnssReceiver(rate_hz=10.0, pos_std_m=(0, 0, 0), vel_std_m_s=(0, 0, 0))
    r = _run_fmu(version, {**PROFILE.as_parameters(), **gnss.fmu_parameters()}, 3.0,
                 extra=("lat", "time_s"))
    rows = np.flatnonzero(r["gnss_valid"][:, 0])
    assert np.array_equal(rows, np.arange(0, 301, 10))
    assert np.array_equal(r["gnss_time_s"][rows, 0], np.arange(31) / 10.0)
    # no errors, no lever arm: the antenna is the IMU; the FMU's own truth at that step
    # comes from another quadrature partition: round-off (measured 0), 1e-15 rad
    assert np.max(np.abs(r["gnss_lat_rad"][rows, 0] - r["lat"][rows, 0])) < 1e-15


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_aiding_follows_commands(version):
    """drive = 1: the sensors' copy of the vehicle takes each new command, so the GNSS
    (no errors, no lever arm) reports the commanded vehicle's position and velocity
    (round-off: measured 0 m and 2.7e-15 m/s; bounds 1e-8 m (epoch time and step end
    agree to the glue's 1e-9 s tolerance) and 1e-13 m/s). The wheel (no lever arm) runs
    at |v| up to the mapping's direction error (1e-6 rad: 1e-11 relative; measured
    1.1e-11 m/s; bound 1e-10)."""
    def drive(s, t):
        s.set("speed_cmd", 5.0 if t < 2.0 else 9.0)
        s.set("heading_rate_cmd", 0.0 if t < 3.0 else 0.2)
    gnss = GnssReceiver(rate_hz=10.0, pos_std_m=(0, 0, 0), vel_std_m_s=(0, 0, 0))
    params = {"drive": 1, "command_time": 1.0, "n_segments": 0, **gnss.fmu_parameters(),
              **Odometer(rate_hz=10.0, std_m_s=0.0).fmu_parameters()}
    r = _run_fmu(version, params, 6.0, extra=("lat", "lon", "v"), drive=drive)
    rows = np.flatnonzero(r["gnss_valid"][:, 0])
    R = 6.4e6
    assert np.max(np.abs(r["gnss_lat_rad"][rows, 0] - r["lat"][rows, 0])) * R < 1e-8
    assert np.max(np.abs(r["gnss_lon_rad"][rows, 0] - r["lon"][rows, 0])) * R < 1e-8
    assert np.max(np.abs(r["gnss_vel_enu_m_s"][rows] - r["v"][rows])) < 1e-13
    odo = np.flatnonzero(r["odo_valid"][:, 0])
    assert np.max(np.abs(r["odo_speed_m_s"][odo, 0] - np.hypot(*r["v"][odo, :2].T))) < 1e-10
    assert r["odo_speed_m_s"][odo[-1], 0] == pytest.approx(9.0, rel=1e-6)


def test_fmu_defaults_equal_the_python_defaults_and_sensors_are_off():
    """One set of defaults: the FMU's start values are the dataclasses' defaults."""
    from fmpy import read_model_description
    md = read_model_description(str(fmu_path("vehicle", 3)))
    start = {v.name: v.start for v in md.modelVariables}
    for sensor in (GnssReceiver(), Barometer(), Odometer()):
        for name, value in sensor.fmu_parameters().items():
            got = [float(x) for x in str(start[name]).split()]
            if name in ("gnss", "baro", "odo"):
                assert got == [0.0], name                           # off by default
            else:
                assert got == list(np.atleast_1d(np.asarray(value, float))), name
    r = _run_fmu(2, {}, 0.5)
    assert np.all(r["gnss_valid"] == 0) and np.all(np.isnan(r["gnss_lat_rad"]))
    assert np.all(r["baro_valid"] == 0) and np.all(r["odo_valid"] == 0)

