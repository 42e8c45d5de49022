"""Vehicle + navigator co-simulation (issue 6): the vehicle FMU against the C vehicle
model called through cffi, the navigator inside three masters (ours, fmpy's SSP
simulator, fmpy's container FMU) against the navigator called through cffi on the same
sensor data, roll-back, interleaved instances, and the FMUs' behaviour under a master.

Tolerances. Where the co-simulated navigator and the cffi navigator receive the same
input bits, they run the same C functions in the same order (the core is compiled with
-ffp-contract=off into both), so the results must be bit-identical: asserted with
array_equal. Where the inputs come from two computations of the same quantity (the FMU's
time t + h versus t0 + (k + 1) h), the bound is stated at the assertion."""
import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi import ImuErrors
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.reference import direct_navigation
from gfins_fmi.fmi.container import run_container, write_container
from gfins_fmi.fmi.ssp import run_ssp, write_ssp
from gfins_fmi.fmi.system import vehicle_integrated_navigation, vehicle_navigation
from gfins_fmi.fmi.paths import FmuRunError, fmu_path, validate
from gfins_fmi.fmi.runner import FmuLog, FmuSlave
from gfins_fmi.sim.vehicle import GnssReceiver, Segment, VehicleProfile, simulate_vehicle

# a short run that still turns: 2 s at rest, start to 15 m/s in 3 s, a 180 deg turn
PROFILE = VehicleProfile.seed001(align_s=2.0, accel_s=3.0, turn_times_s=(6.0,), turn_s=6.0)
STOP_S = 16.0


def _rows(r, name, n):
    """Columns name_1 .. name_n of a container result as an (rows, n) array."""
    return np.stack([r[f"{name}_{i}"] for i in range(1, n + 1)], 1)


# ---- the vehicle FMU ------------------------------------------------------------------
@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_equals_cffi_vehicle_with_sensor_errors(version):
    rng = np.random.default_rng(6)
    imu = ImuErrors.random(rng, gyro_bias_deg_h=0.01, gyro_scale_ppm=50, gyro_misalignment_arcsec=10,
                           accel_bias_ug=1000, accel_scale_ppm=50, accel_misalignment_arcsec=10,
                           accel_k2_ug_g2=20, lever_arm_cm=3)
    bias = rng.normal(0, 1e-3, 9)
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=STOP_S, imu_errors=imu,
                                      array_bias_m_s2=bias)
    system.outputs = {"vehicle": ["time_s", "lat", "lon", "v", "q", "gyro_rate", "specific_force",
                                  "dtheta", "dv", "A", "angular_accel"]}
    with CoSimulation(system, fmi_version=version) as m:
        m.initialize()
        r = m.run()
    rec = simulate_vehicle(PROFILE, STOP_S, system.step_s)
    # times: the FMU reaches t + h from the master's t = k h, the batch (k + 1) h; they
    # may differ by an ulp (1.8e-15 s at 16 s), which moves a rate by < 1e-14 relative
    assert np.max(np.abs(r["vehicle.time_s"][:, 0] - rec.t_s)) <= 4e-15
    for name, ref, scale in [("lat", rec.lat_rad[:, None], 1.0), ("v", rec.v_n_m_s, 15.0),
                             ("q", rec.q_bn, 1.0)]:
        assert np.max(np.abs(r[f"vehicle.{name}"] - ref)) <= 1e-13 * scale, name
    g_err, f_err = imu.apply(rec.gyro_rad_s, rec.accel_m_s2)
    h = system.step_s
    gi, fi = imu.apply(rec.dtheta_rad / h, rec.dv_m_s / h)
    # increments carry the errors as mean rates over the step (the SINS FMU's convention)
    A = rec.array_outputs(__import__("gfins_fmi").layout("qin9", 0.1)) + bias
    for got, ref in [(r["vehicle.gyro_rate"], g_err), (r["vehicle.specific_force"], f_err),
                     (r["vehicle.A"][:, :9], A)]:
        assert np.max(np.abs(got - ref)) <= 1e-13 * np.max(np.abs(ref))
    # increments: the step lengths themselves differ by up to an ulp of t (3.6e-15 s at
    # 16 s), i.e. 3.6e-13 of a 0.01 s increment
    for got, ref in [(r["vehicle.dtheta"][1:], gi * h), (r["vehicle.dv"][1:], fi * h)]:
        assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert np.all(r["vehicle.A"][:, 9:] == 0.0)
    # the true angular acceleration (no sensor errors): the batch's, same round-off as the rates
    ref = rec.gyro_dot_rad_s2
    assert np.max(np.abs(r["vehicle.angular_accel"] - ref)) <= 1e-13 * np.max(np.abs(ref))


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_variable_steps_reach_the_same_state(version):
    """Any step sequence reaching t gives the same truth at t (closed-form profile,
    quadrature pieces <= 0.25 s): 1e-9 m; increments are additive. The two clocks sum
    different steps, so they differ by ~1e-13 s: 1e-11 m/s at 8 m/s^2."""
    def run(steps):
        s = FmuSlave(fmu_path("vehicle", version), version, FmuLog(), False)
        try:
            s.initialize(0.0, 20.0, PROFILE.as_parameters())
            t, dth = 0.0, np.zeros(3)
            for h in steps:
                s.slave.doStep(currentCommunicationPoint=t, communicationStepSize=h)
                t += h
                dth += s.get("dtheta")
            return np.array(s.get("lat") + s.get("lon") + s.get("v")), dth
        finally:
            s.close()
    a, da = run([0.01] * 1000)
    rng = np.random.default_rng(1)
    steps = rng.uniform(0.001, 0.4, 200)
    steps = steps[np.cumsum(steps) < 9.5]
    b, db = run(list(steps) + [10.0 - steps.sum()])
    assert np.max(np.abs(a[:2] - b[:2])) * 6.4e6 <= 1e-9      # position, m
    assert np.max(np.abs(a[2:] - b[2:])) <= 1e-11              # velocity, m/s
    assert np.max(np.abs(da - db)) <= 1e-12                    # summed increments, rad


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_follows_commands(version):
    s = FmuSlave(fmu_path("vehicle", version), version, FmuLog(), False)
    try:
        s.initialize(0.0, 10.0, {"drive": 1, "command_time": 2.0, "n_segments": 0})
        s.set("speed_cmd", 8.0)
        s.set("heading_rate_cmd", 0.1)
        for k in range(400):
            s.slave.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
        v = np.array(s.get("v"))
        heading = s.get("euler")[0]
    finally:
        s.close()
    # a held command is reached after command_time: speed 8 m/s, heading rate 0.1 rad/s,
    # heading 0.1 (2 s / 2 + 2 s) = 0.3 rad (the smooth step integrates to 1/2)
    # (the true ENU speed differs from the profile speed by the geodetic mapping's scale,
    # tan(L) N / R ~ 1.6e-7 relative after 30 m north: see gf_vehicle.h)
    assert np.hypot(v[0], v[1]) == pytest.approx(8.0, rel=1e-6)
    assert heading == pytest.approx(0.3, abs=1e-12)
    assert np.arctan2(v[0], v[1]) == pytest.approx(heading, abs=1e-6)  # same mapping


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_refuses_bad_parameters_with_a_reason(version):
    for params, text in [({"n_segments": 40}, "n_segments"), ({"lat0": 1.56}, "lat0"),
                         ({"array_layout": 5}, "array_layout"), ({"command_time": 0.0}, "command_time"),
                         ({"seg_dspeed": [-20.0] + [0.0] * 31, "n_segments": 1,
                           "seg_duration": [1.0] + [0.0] * 31}, "segment 1"),
                         ({"imu_errors": 1, "gyro_scale": [0.6, 0, 0]}, "gyro_scale")]:
        log = FmuLog()
        s = FmuSlave(fmu_path("vehicle", version), version, log, False)
        try:
            with pytest.raises(Exception):
                s.initialize(0.0, 10.0, params)
            assert any(text in m for m in log.messages), (params, log.messages)
        finally:
            s.close()


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_under_a_master_sequence_stop_time_variability(version):
    log = FmuLog()
    s = FmuSlave(fmu_path("vehicle", version), version, log, False)
    try:
        with pytest.raises(Exception):     # doStep before initialization
            s.slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.1)
        assert any("must not be called in mode" in m for m in log.messages)
        s.initialize(0.0, 1.0, {})
        with pytest.raises(Exception):     # a fixed parameter in step mode
            s.set("speed0", 3.0)
        assert any("speed0" in m for m in log.messages), log.messages
        s.slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.5)
        with pytest.raises(Exception):     # past the stop time
            s.slave.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.6)
        assert any("stop time" in m for m in log.messages)
    finally:
        s.close()


# ---- masters: the navigator equals the cffi navigator on the same sensor data -----------
@pytest.mark.parametrize("navigator", ["gfnav_qin9", "gfnav_cube6", "sins"])
@pytest.mark.parametrize("version", [2, 3])
def test_python_master_equals_direct_pipeline(navigator, version):
    system = vehicle_navigation(navigator, PROFILE, stop_s=STOP_S)
    with CoSimulation(system, fmi_version=version) as m:
        m.initialize()
        r = m.run()
    nav = r["navigator.lat"][:, 0]
    if navigator == "sins":
        # row k + 1 holds the state after the increment that ends at t_k (k >= 1)
        sol = direct_navigation(system, {"dtheta": r["vehicle.dtheta"][1:-1],
                                               "dv": r["vehicle.dv"][1:-1]})
        got, got_v = nav[2:], r["navigator.v"][2:]
    else:
        n = {"gfnav_qin9": 9, "gfnav_cube6": 6}[navigator]
        # Jacobi: the step at t_k takes the vehicle's outputs at t_k (row k)
        sol = direct_navigation(system, {"A": r["vehicle.A"][:-1, :n]})
        got, got_v = nav[1:], r["navigator.v"][1:]
    assert np.array_equal(got, sol.lat_rad) and np.array_equal(got_v, sol.v_n_m_s)
    # and it navigates: the error stays small (exact sensors)
    assert np.max(np.abs(nav[1:] - r["vehicle.lat"][:-1, 0])) * 6.4e6 < 0.05


@pytest.mark.parametrize("version", [2, 3])
def test_integrated_navigator_takes_every_gnss_epoch_through_the_master(version):
    """vehicle_integrated_navigation: the receiver's epochs reach the filter FMU through
    the master's Int32 (gnss_valid) and Float64 connections in the step whose IMU
    interval holds them: 5 Hz, 13.7 ms off the samples, 5 s -> 25 epochs, each a position
    and a velocity update, none stale or rejected; the recorded Int32 outputs are the
    counts. (tests/fmi/test_osp.py compares the same system with libcosim bit for bit.)"""
    rx = GnssReceiver(rate_hz=5.0, offset_s=0.0137, lever_arm_m=(0.3, 1.1, 1.6))
    system = vehicle_integrated_navigation(PROFILE, stop_s=5.0, gnss=rx)
    with CoSimulation(system, fmi_version=version) as m:
        m.initialize()
        r = m.run()
    assert r["vehicle.gnss_valid"].sum() == 25
    assert r["navigator.n_updates"][-1, 0] == 50 and r["navigator.n_rejected"][-1, 0] == 0
    with pytest.raises(ValueError, match="vehicle_integrated_navigation"):
        vehicle_navigation("ins_gnss", PROFILE)


def test_gauss_seidel_navigator_first_equals_jacobi():
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=4.0)
    out = []
    for kw in (dict(algorithm="jacobi"), dict(algorithm="gauss-seidel", order=["navigator", "vehicle"])):
        with CoSimulation(system, **kw) as m:
            m.initialize()
            out.append(m.run())
    assert np.array_equal(out[0]["navigator.q"], out[1]["navigator.q"])


def test_ssp_run_equals_direct_pipeline(tmp_path):
    """fmpy's SSP simulator: FMI 2.0, scalar connections. It starts every connection at
    0 and passes no output before the first step, so the navigator skips that step
    (skip_steps=1) and starts from the truth at h."""
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=STOP_S, skip_steps=1)
    path = write_ssp(system, tmp_path / "vn.ssp")
    r = run_ssp(path, STOP_S, system.step_s)
    # row k, recorded after the step at t_k: vehicle at t_(k+1), navigator the sample at
    # t_k, taken from the vehicle's row k - 1
    A = np.stack([r[f"vehicle.A[{i}]"] for i in range(1, 10)], 1)
    sol = direct_navigation(system, {"A": A[:-1]})
    assert np.array_equal(r["navigator.lat"][1:], sol.lat_rad)
    assert np.array_equal(r["navigator.v[2]"][1:], sol.v_n_m_s[:, 1])
    assert np.max(np.abs(r["navigator.lat"][1:] - r["vehicle.lat"][:-1])) * 6.4e6 < 0.05


def test_ssp_sins_equals_direct_pipeline(tmp_path):
    """The SSP of the vehicle and the strapdown INS (increments dtheta, dv connected)."""
    system = vehicle_navigation("sins", PROFILE, stop_s=STOP_S, skip_steps=1)
    r = run_ssp(write_ssp(system, tmp_path / "vs.ssp"), STOP_S, system.step_s)
    inc = {k: np.stack([r[f"vehicle.{k}[{i}]"] for i in (1, 2, 3)], 1) for k in ("dtheta", "dv")}
    # navigation restarts at t_1 (skip), the first increment it uses ends at t_2: it is
    # the vehicle's row 1; the navigator's row k >= 2 is the state at t_k
    sol = direct_navigation(system, {k: v[1:-1] for k, v in inc.items()})
    assert np.array_equal(r["navigator.lat"][2:], sol.lat_rad)
    assert np.array_equal(r["navigator.v[1]"][2:], sol.v_n_m_s[:, 0])
    # and navigates: exact increments, a 180 deg turn in 6 s: 2 mm measured
    assert np.max(np.abs(r["navigator.lat"][1:] - r["vehicle.lat"][:-1])) * 6.4e6 < 0.01


def test_ssp_without_skip_navigates_a_zero_first_sample(tmp_path):
    """Why skip_steps exists: without it the first array sample the navigator gets from
    fmpy's SSP simulator is zeros (no gravity), a velocity error of g h / 2."""
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=1.0, hold_height=False)
    r = run_ssp(write_ssp(system, tmp_path / "vn0.ssp"), 1.0, system.step_s)
    assert abs(r["navigator.v[3]"][-1]) > 0.01


def test_container_fmi2_valid_and_equals_direct_pipeline(tmp_path):
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=STOP_S, skip_steps=1)
    path = write_container(system, tmp_path / "vn2.fmu", fmi_version=2)
    assert validate(path) == []
    r = run_container(path, STOP_S, system.step_s)
    # fmpy's container also passes no connection before its first internal step (the
    # navigator's first sample would be zeros): skip_steps=1 as for SSP; rows as in SSP
    # but with one more row (the initial one) first
    A = _rows(r, "vehicle_A", 9)
    sol = direct_navigation(system, {"A": A[1:-1]})
    assert np.array_equal(r["navigator_lat"][2:], sol.lat_rad)
    assert np.array_equal(_rows(r, "navigator_v", 3)[2:], sol.v_n_m_s)


def test_container_fmi3_array_connections(tmp_path):
    """FMI 3.0 container: whole-array connections work (vehicle A[12] -> gfnav_12 A[12]);
    array outputs and array parameters do not in fmpy 0.3.32 (docs/cosim.md), so the
    check uses scalar outputs and the cffi vehicle's array data: same samples to an ulp
    of time (1e-15 relative in A), so the navigators agree to 1e-9 m over 16 s."""
    system = vehicle_navigation("gfnav_12", None, stop_s=STOP_S, skip_steps=1)
    system.outputs = {"vehicle": ["time_s", "lat"], "navigator": ["time_s", "lat", "lon"]}
    path = write_container(system, tmp_path / "vn3.fmu", fmi_version=3)
    assert validate(path) == []
    r = run_container(path, STOP_S, system.step_s)
    rec = simulate_vehicle(VehicleProfile.seed001(align_s=60.0), STOP_S, system.step_s)
    sol = direct_navigation(system, {"A": rec.array_outputs(__import__("gfins_fmi").layout("12", 0.1))[1:]})
    assert np.max(np.abs(r["navigator_lat"][2:] - sol.lat_rad[:-1])) * 6.4e6 < 1e-9


# ---- roll-back and instances ----------------------------------------------------------
@pytest.mark.parametrize("version", [2, 3])
def test_rollback_serialize_restore_reproduces(version):
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=STOP_S)
    with CoSimulation(system, fmi_version=version) as m:
        m.initialize()
        m.run(stop_s=7.0)                       # t1 = 7 s: inside the turn
        saved = m.serialize_state(m.get_state())
        first = m.run(stop_s=10.0)              # to t2
        state = m.deserialize_state(saved)
        m.set_state(state)
        m.free_state(state)
        assert m.time_s == 7.0
        again = m.run(stop_s=10.0)
    for k in first:
        assert np.array_equal(first[k], again[k]), k


def test_two_interleaved_systems_equal_separate_runs():
    sa = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=6.0)
    sb = vehicle_navigation("sins", VehicleProfile.circle(30.0, 6.0), stop_s=6.0)
    sep = []
    for s in (sa, sb):
        with CoSimulation(s) as m:
            m.initialize()
            sep.append(m.run())
    with CoSimulation(sa) as ma, CoSimulation(sb) as mb:
        ma.initialize()
        mb.initialize()
        la, lb = [], []
        for k in range(600):          # alternate: one step of each
            ma.time_s, mb.time_s = k * 0.01, k * 0.01
            ma.step(0.01)
            mb.step(0.01)
            la.append(ma.read("navigator", "lat"))
            lb.append(mb.read("navigator", "lat"))
    assert np.array_equal(np.array(la), sep[0]["navigator.lat"][1:])
    assert np.array_equal(np.array(lb), sep[1]["navigator.lat"][1:])


def test_master_reports_fmu_errors_with_the_log():
    system = vehicle_navigation("gfnav_qin9", VehicleProfile(segments=[Segment(1.0)]), stop_s=1.0)
    system.components["navigator"][1]["l"] = -1.0
    with CoSimulation(system) as m:
        with pytest.raises(FmuRunError, match="lever arm"):
            m.initialize()


@pytest.mark.parametrize("navigator", ["gfnav_cube6", "sins", "ins_gnss"])
def test_cli_cosim_checks_every_runner(tmp_path, navigator, capsys):
    from gfins_fmi.cli import main
    rc = main(["cosim", "--navigator", navigator, "--seconds", "4", "--align", "1",
               "--quiet", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "bit for bit" in out
    errors = np.loadtxt(tmp_path / "cosim_errors.csv", delimiter=",", skiprows=1)
    assert errors.shape == (400, 4)        # a row per step, a column per header name
    assert (tmp_path / "vehicle_navigation.ssp").is_file()
    assert validate(tmp_path / "vehicle_navigation.fmu") == []


def test_master_keeps_the_rows_before_a_failing_step():
    """The vehicle runs north into 89 deg latitude: the FMU refuses the step, the error
    names the reason and the rows recorded before it are kept."""
    fast = VehicleProfile(lat0_rad=np.radians(88.99), speed0_m_s=200.0)
    system = vehicle_navigation("sins", fast, stop_s=100.0)
    with CoSimulation(system) as m:
        m.initialize()
        with pytest.raises(FmuRunError, match="89 deg") as info:
            m.run()
    part = info.value.partial
    assert 1 < len(part["time"]) < 10001
    assert np.all(np.isfinite(part["vehicle.lat"]))


# ---- noise in the vehicle FMU -----------------------------------------------------------
def _vehicle_outputs(params, n=6000, version=2, h=0.01, names=("gyro_rate", "specific_force", "dtheta", "A")):
    s = FmuSlave(fmu_path("vehicle", version), version, FmuLog(), False)
    try:
        s.initialize(0.0, n * h, {**PROFILE.as_parameters(), **params})
        out = {k: [s.get(k)] for k in names}
        for k in range(n):
            s.slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
            for name in names:
                out[name].append(s.get(name))
        return {k: np.array(v) for k, v in out.items()}
    finally:
        s.close()


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_noise_follows_the_imu_noise_conventions(version):
    """Each noise process alone, against its definition (gfins_fmi.ImuNoise, csrc/sim/gf_noise.h):
    white gyro std N / sqrt(h), white accelerometer std ASD sqrt(1/(2h)), Gauss-Markov
    residual y_k - a y_(k-1) of std sigma sqrt(1 - a^2), random-walk steps of std K sqrt(h),
    array white noise. 6000 steps x 3 axes: a sample std is within 1.5% (1 sigma, 18000
    terms: 0.5%) of the truth; the bound 3% is 6 sigma."""
    h = 0.01
    clean = _vehicle_outputs({}, version=version)
    noise = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.05, accel_vrw_ug_sqrt_hz=50.0).fmu_parameters()
    noisy = _vehicle_outputs({"noise": 1, "noise_seed": 7, "array_noise": 1e-3, **noise},
                             version=version)
    g = (noisy["gyro_rate"] - clean["gyro_rate"])[1:]
    a = (noisy["specific_force"] - clean["specific_force"])[1:]
    assert np.all(noisy["gyro_rate"][0] == clean["gyro_rate"][0])     # no noise at the start
    assert np.std(g) == pytest.approx(noise["gyro_arw"] / np.sqrt(h), rel=0.03)
    assert np.std(a) == pytest.approx(noise["accel_vrw"] * np.sqrt(0.5 / h), rel=0.03)
    # the increments carry the same sample times h
    assert np.max(np.abs((noisy["dtheta"] - clean["dtheta"])[1:] - g * h)) < 1e-15
    A = (noisy["A"] - clean["A"])[1:, :9]
    assert np.std(A) == pytest.approx(1e-3, rel=0.03)
    assert np.all(noisy["A"][:, 9:] == 0.0)
    sigma, tau, K = 2e-5, 0.5, 1e-6
    gm = _vehicle_outputs({"noise": 1, "gyro_bias_instability": sigma, "gyro_correlation_time": tau,
                           "accel_rrw": K}, version=version)
    y = (gm["gyro_rate"] - clean["gyro_rate"])[1:]
    r = y[1:] - np.exp(-h / tau) * y[:-1]
    assert np.std(r) == pytest.approx(sigma * np.sqrt(1 - np.exp(-2 * h / tau)), rel=0.03)
    b = (gm["specific_force"] - clean["specific_force"])[1:]
    assert np.std(np.diff(b, axis=0)) == pytest.approx(K * np.sqrt(h), rel=0.03)


def test_vehicle_fmu_noise_is_seeded_and_restored():
    p = {"noise": 1, "accel_vrw": 1e-3, "gyro_arw": 1e-4, "array_noise": 1e-3}
    a = _vehicle_outputs({**p, "noise_seed": 3}, n=300)
    b = _vehicle_outputs({**p, "noise_seed": 3}, n=300)
    c = _vehicle_outputs({**p, "noise_seed": 4}, n=300)
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert not np.array_equal(a["A"], c["A"]) and not np.array_equal(a["gyro_rate"], c["gyro_rate"])
    # an FMU state holds the generators: roll back and replay the same noise
    system = vehicle_navigation("gfnav_qin9", PROFILE, stop_s=4.0,
                                      navigator_parameters={"strategy": 3})
    system.components["vehicle"][1].update(p)
    with CoSimulation(system, fmi_version=3) as m:
        m.initialize()
        m.run(stop_s=1.0)
        st = m.get_state()
        first = m.run(stop_s=2.0)
        m.set_state(st)
        again = m.run(stop_s=2.0)
    assert all(np.array_equal(first[k], again[k]) for k in first)


def test_vehicle_fmu_refuses_bad_noise_and_aiding_parameters():
    for params, text in [({"noise": 1, "gyro_arw": -1.0}, "gyro_arw"),
                         ({"noise": 1, "gyro_bias_instability": 1e-5, "gyro_correlation_time": 0.0},
                          "gyro_correlation_time"),
                         ({"noise": 1, "array_noise": float("nan")}, "array_noise"),
                         ({"noise": 2}, "noise"),
                         ({"gnss": 1, "gnss_rate": -1.0}, "gnss_rate must be finite"),
                         ({"gnss": 1, "gnss_n_outages": 1, "gnss_outage_start": [3.0] + [0.0] * 7,
                           "gnss_outage_end": [2.0] + [0.0] * 7}, "GNSS outage 1"),
                         ({"baro": 1, "baro_std": float("nan")}, "baro_std"),
                         ({"odo": 3}, "odo must be 0 or 1")]:
        log = FmuLog()
        s = FmuSlave(fmu_path("vehicle", 2), 2, log, False)
        try:
            with pytest.raises(Exception):
                s.initialize(0.0, 1.0, params)
            assert any(text in m for m in log.messages), (params, log.messages)
        finally:
            s.close()
