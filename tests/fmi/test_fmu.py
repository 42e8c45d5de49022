"""The accel9 FMUs (FMI 2.0 and 3.0) through fmpy: validity, equality with the cffi
path, FMU state round trips, and errors for bad input and bad call sequences."""
from __future__ import annotations

import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

import gfins_fmi as gf
from support.truth import W0, numpy_outputs, paper_layout, smooth_motion

L, DT = 0.1, 0.01


@pytest.fixture(scope="module")
def record():
    u, th = paper_layout(L)
    _, f, w, wd = smooth_motion(1500, DT)
    A = numpy_outputs(u, th, f, w, wd)
    # noise so that the negative-omega^2 policy and its flags take part in the comparison
    A += np.random.default_rng(7).normal(0, 2e-3, A.shape)
    return A


@pytest.mark.parametrize("version", [2, 3])
def test_installed_fmu_is_valid(version):
    path = gf.fmu_path("accel9", version)
    assert path.is_file() and path.suffix == ".fmu"
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion.startswith(str(version))
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    # the validator does not require these; a generator slip once dropped them in FMI 3
    assert md.defaultExperiment is not None and float(md.defaultExperiment.stepSize) == 0.01
    assert {c.name for c in md.logCategories} >= {"logStatusError", "logEvents"}


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_equals_cffi(record, version):
    """Same C core, same inputs: the results must agree to 1e-12 relative (measured:
    bitwise; the FMU integrates omega_dot over the previous communication step, which
    fmpy's fixed step makes equal to DT)."""
    ref = gf.solve_accel9(record, DT, L, W0)
    out = gf.run_accel9_fmu(record, DT, L, W0, fmi_version=version)
    assert ref.flag_counts()["neg_omega_sq_x"] > 0  # the policy path is exercised
    for name in ("f_m_s2", "omega_rad_s", "omega_dot_rad_s2", "omega_sq_rad2_s2"):
        a, b = getattr(out, name), getattr(ref, name)
        assert np.all(np.abs(a - b) <= 1e-12 * np.maximum(np.abs(b), 1e-300)), name
    assert np.array_equal(out.flags, ref.flags)


def test_fmi2_simulate_fmu_rows_lag_one_sample(record):
    """fmpy's own master: it records outputs after each doStep, so row k+1 holds the
    solution of the sample applied at t_k (the documented sampling convention)."""
    n = 200
    t = np.arange(n) * DT
    signals = np.zeros(n, dtype=[("time", float)] + [(f"A[{i + 1}]", float) for i in range(9)])
    signals["time"] = t
    for i in range(9):
        signals[f"A[{i + 1}]"] = record[:n, i]
    res = simulate_fmu(str(gf.fmu_path("accel9", 2)), start_time=0.0, stop_time=t[-1],
                       output_interval=DT, input=signals,
                       start_values={"l": L, "omega_init[1]": W0[0], "omega_init[2]": W0[1],
                                     "omega_init[3]": W0[2]},
                       output=["omega[1]", "omega[2]", "omega[3]", "f[3]"])
    ref = gf.solve_accel9(record[:n], DT, L, W0)
    # fmpy interpolates the input linearly; at the sample times the interpolant is
    # the sample itself up to rounding of t, hence the tolerance
    got = np.c_[res["omega[1]"], res["omega[2]"], res["omega[3]"]][1:n]
    np.testing.assert_allclose(got, ref.omega_rad_s[:n - 1], rtol=1e-9, atol=1e-9)


def _slave(version, path):
    md = read_model_description(str(path))
    unzip = extract(str(path))
    vars_ = {v.name: v.valueReference for v in md.modelVariables}
    log = []
    if version == 2:
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzip,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
        s.instantiate(loggingOn=False)
    else:
        s = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzip,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
        s.instantiate(loggingOn=False, logMessage=lambda env, st, cat, msg: log.append(msg.decode()))
    return s, vars_, unzip, log


def _init(s, version, vars_, stop):
    if version == 2:
        s.setupExperiment(startTime=0.0, stopTime=stop)
        s.enterInitializationMode()
        s.setReal([vars_["l"]], [L])
        s.setReal([vars_[f"omega_init[{i}]"] for i in (1, 2, 3)], W0)
    else:
        s.enterInitializationMode(startTime=0.0, stopTime=stop)
        s.setFloat64([vars_["l"]], [L])
        s.setFloat64([vars_["omega_init"]], W0)
    s.exitInitializationMode()


def _run(s, version, vars_, A, k0, k1):
    out = []
    for k in range(k0, k1):
        if version == 2:
            s.setReal([vars_[f"A[{i + 1}]"] for i in range(9)], A[k].tolist())
        else:
            s.setFloat64([vars_["A"]], A[k].tolist())
        s.doStep(currentCommunicationPoint=k * DT, communicationStepSize=DT)
        if version == 2:
            out.append(s.getReal([vars_[f"omega[{i}]"] for i in (1, 2, 3)]))
        else:
            out.append(s.getFloat64([vars_["omega"]], 3))
    return np.array(out)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("serialize", [False, True])
def test_fmu_state_restore_reproduces_continuation(record, version, serialize):
    path = gf.fmu_path("accel9", version)
    s, vars_, unzip, _ = _slave(version, path)
    try:
        n, mid = 600, 250
        _init(s, version, vars_, n * DT)
        _run(s, version, vars_, record, 0, mid)
        state = s.getFMUState() if version == 3 else s.getFMUstate()
        if serialize:
            blob = s.serializeFMUState(state) if version == 3 else s.serializeFMUstate(state)
            (s.freeFMUState if version == 3 else s.freeFMUstate)(state)
            state = (s.deserializeFMUState if version == 3 else s.deSerializeFMUstate)(blob)
        first = _run(s, version, vars_, record, mid, n)
        (s.setFMUState if version == 3 else s.setFMUstate)(state)
        again = _run(s, version, vars_, record, mid, n)
        assert np.array_equal(first, again)  # exactly: same bytes in, same code
        (s.freeFMUState if version == 3 else s.freeFMUstate)(state)
    finally:
        s.terminate()
        s.freeInstance()
        shutil.rmtree(unzip, ignore_errors=True)


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_rejects_nonfinite_input_keeps_outputs(record, version):
    A = record[:100].copy()
    A[60, 2] = np.nan
    with pytest.raises(gf.FmuRunError, match=r"A\[3\] = nan at t = 0.6") as exc:
        gf.run_accel9_fmu(A, DT, L, W0, fmi_version=version)
    ref = gf.solve_accel9(record[:60], DT, L, W0)
    got = exc.value.partial.omega_rad_s
    assert got.shape == (60, 3)
    assert np.all(np.abs(got - ref.omega_rad_s) <= 1e-12 * np.abs(ref.omega_rad_s))


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("l", [0.0, -0.1, float("nan")])
def test_fmu_rejects_bad_lever_arm(record, version, l):
    with pytest.raises(gf.FmuRunError, match=r"ExitInitializationMode.*parameter l = .* >= 1e-6 m"):
        gf.run_accel9_fmu(record[:5], DT, l, W0, fmi_version=version)


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_call_sequence_and_stop_time(record, version):
    path = gf.fmu_path("accel9", version)
    s, vars_, unzip, log = _slave(version, path)
    try:
        with pytest.raises(FMICallException):  # doStep before initialization
            s.doStep(currentCommunicationPoint=0.0, communicationStepSize=DT)
        _init(s, version, vars_, 10 * DT)
        with pytest.raises(FMICallException):  # fixed parameter in step mode
            (s.setReal if version == 2 else s.setFloat64)([vars_["l"]], [0.2])
        _run(s, version, vars_, record, 0, 10)
        with pytest.raises(FMICallException):  # past the stop time
            s.doStep(currentCommunicationPoint=10 * DT, communicationStepSize=DT)
        if version == 3:
            text = " ".join(log)
            assert "must not be called in mode Instantiated" in text
            assert "fixed parameter" in text and "would pass the stop time" in text
    finally:
        s.terminate()
        s.freeInstance()
        shutil.rmtree(unzip, ignore_errors=True)


# ---- the strapdown navigator FMU ----------------------------------------------------

from gfins_fmi.sim import trajectory as tj
from gfins_fmi.fmi.runner import run_fmu  # noqa: E402
from gfins_fmi.fmi.models import run_sins_fmu


@pytest.fixture(scope="module")
def circle():
    return tj.sample(tj.Circle(), 20.0, 0.01)


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_valid(version):
    path = gf.fmu_path("sins", version)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.coSimulation.modelIdentifier == "gfins_sins"


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("cfg", [gf.SinsConfig(), gf.SinsConfig(input="rates"),
                                 gf.SinsConfig(coning=False, vertical="baro", baro_tau_s=5.0)],
                         ids=["increments", "rates", "baro"])
def test_sins_fmu_equals_batch(circle, version, cfg):
    """The FMU and the batch call run the same gf_sins code on the same samples with the
    same intervals: equal to 1e-12 relative (measured: bitwise)."""
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    if cfg.input == "rates":
        g, a, h = tr.gyro_rad_s, tr.accel_m_s2, tr.h_m + 1.0
    else:
        g, a, h = tr.dtheta_rad, tr.dv_m_s, tr.h_m[1:] + 1.0
    ref = gf.Strapdown(x0, cfg).run(g, a, dt_s=tr.dt_s, h_ext_m=h)
    out = run_sins_fmu(g, a, tr.dt_s, x0, config=cfg, h_ext_m=h, fmi_version=version)
    for name in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "t_s"):
        x, y = getattr(out, name), getattr(ref, name)
        assert np.all(np.abs(x - y) <= 1e-12 * np.maximum(np.abs(y), 1e-300)), name


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_bad_parameters_and_input(circle, version):
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    x0.lat_rad = 1.6
    with pytest.raises(ValueError, match=r"initial\.lat_rad = 1.6 rad .* is outside"):
        run_sins_fmu(tr.dtheta_rad[:5], tr.dv_m_s[:5], 0.01, x0, fmi_version=version)
    with pytest.raises(gf.FmuRunError, match="parameter lat0 = 1.6 rad is outside"):   # the FMU's own
        run_fmu("sins", {"dtheta": np.zeros((3, 3))}, ["q"], 0.01,
                parameters={"lat0": 1.6, "q0": [1.0, 0, 0, 0]}, fmi_version=version)
    with pytest.raises(gf.FmuRunError, match="input_mode = 7 must be 0"):
        run_fmu("sins", {"dtheta": np.zeros((3, 3))}, ["q"], 0.01,
                parameters={"input_mode": 7}, fmi_version=version)
    g = tr.dtheta_rad[:50].copy()
    g[20, 0] = np.inf
    x0 = gf.NavState.from_trajectory(tr, 0)
    with pytest.raises(gf.FmuRunError, match=r"t = 0.21 s: input dtheta = \[inf"):
        run_sins_fmu(g, tr.dv_m_s[:50], 0.01, x0, fmi_version=version)



@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_baro_without_height_keeps_the_height(circle, version):
    """h_ext starts as NaN ("none"): an unconnected baro input must not pull the height
    to 0 m."""
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    out = run_fmu("sins", {"dtheta": np.r_[np.zeros((1, 3)), tr.dtheta_rad[:200]],
                           "dv": np.r_[np.zeros((1, 3)), tr.dv_m_s[:200]]}, ["h"], 0.01,
                  parameters={"vertical_mode": 2, "q0": x0.q_bn, "v0": x0.v_n_m_s,
                              "lat0": x0.lat_rad, "lon0": x0.lon_rad, "h0": x0.h_m},
                  fmi_version=version)
    assert np.abs(out["h"][:, 0] - x0.h_m).max() < 0.01


def test_sins_fmu_error_partial_is_a_solution(circle):
    tr = circle
    g = tr.dtheta_rad[:60].copy()
    g[50, 1] = np.nan
    x0 = gf.NavState.from_trajectory(tr, 0)
    with pytest.raises(gf.FmuRunError, match="record row 50") as exc:
        run_sins_fmu(g, tr.dv_m_s[:60], 0.01, x0, fmi_version=3)
    ref = gf.Strapdown(x0).run(tr.dtheta_rad[:50], tr.dv_m_s[:50], dt_s=0.01)
    assert np.array_equal(exc.value.partial.lat_rad, ref.lat_rad)


# ---- gyro-free navigator FMUs (one per layout) ---------------------------------------

from gfins_fmi.fmi.paths import MODELS  # noqa: E402
from gfins_fmi.fmi.models import run_gfnav_fmu


@pytest.mark.parametrize("model", sorted(MODELS))
@pytest.mark.parametrize("version", [2, 3])
def test_every_fmu_is_valid(model, version):
    assert validate_fmu(str(gf.fmu_path(model, version))) == []


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("layout_name, strategy", [("cube6", "integrate"), ("qin9", "sqrt"),
                                                   ("qin9", "fused"), ("12", "eigen")])
def test_gfnav_fmu_equals_batch(circle, version, layout_name, strategy):
    """Same C code, same samples, interval = the previous communication step = dt:
    equal to 1e-12 relative (measured: bitwise, except the reported time, which the FMU
    accumulates and the batch API computes as t0 + k dt: 2e-13 s apart)."""
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    g = gf.layout(layout_name, 0.1)
    A = tr.array_outputs(g) + np.random.default_rng(3).normal(0, 1e-5, (tr.t_s.size, g.n_sensors))
    ref, rates = gf.GyroFreeNavigator(g, x0, strategy, tr.gyro_rad_s[0]).run(A, tr.dt_s)
    sol, w, f, flags = run_gfnav_fmu(layout_name, A, tr.dt_s, x0, strategy=strategy,
                                     omega_init_rad_s=tr.gyro_rad_s[0], fmi_version=version)
    for name in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "t_s"):
        x, y = getattr(sol, name), getattr(ref, name)
        assert np.all(np.abs(x - y) <= 1e-12 * np.maximum(np.abs(y), 1e-300)), name
    assert np.array_equal(w, rates.omega_rad_s) and np.array_equal(f, rates.f_m_s2)
    assert np.array_equal(flags, rates.flags)


@pytest.mark.parametrize("version", [2, 3])
def test_gfnav_fmu_errors(circle, version):
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    A = tr.array_outputs(gf.layout("cube6", 0.1))[:20]
    with pytest.raises(gf.FmuRunError, match="strategy = 1 needs the squared rates"):
        run_gfnav_fmu("cube6", A, 0.01, x0, strategy="sqrt", fmi_version=version)
    A[7, 2] = np.nan
    with pytest.raises(gf.FmuRunError, match="A\\[i\\] is not finite"):
        run_gfnav_fmu("cube6", A, 0.01, x0, fmi_version=version)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("mode", ["rates", "increments"])
def test_sins_fmu_compensation_and_lowpass_equal_the_batch_pipeline(circle, version, mode):
    """imu_comp + lowpass in the FMU = ImuErrors.compensate -> BiquadFilter -> Strapdown
    (increments are compensated as mean rates over the step, exactly as the FMU does)."""
    from gfins_fmi.nav import signal_conditioning
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    e = gf.ImuErrors.random(np.random.default_rng(4), gyro_bias_deg_h=10, gyro_scale_ppm=1000,
                            gyro_misalignment_arcsec=100, accel_bias_ug=1000, accel_scale_ppm=1000,
                            accel_misalignment_arcsec=100, accel_k2_ug_g2=50, lever_arm_cm=3)
    sos = signal_conditioning.design_cheby2(20.0, 100.0, order=4)
    dt = tr.dt_s
    if mode == "rates":
        g_out, a_out = e.apply(tr.gyro_rad_s, tr.accel_m_s2)
        g_c, a_c = e.compensate(g_out, a_out)
    else:
        g_out, a_out = e.apply(tr.dtheta_rad / dt, tr.dv_m_s / dt)
        g_out, a_out = g_out * dt, a_out * dt
        k = 1.0 / dt                                  # the FMU's arithmetic, to the bit
        g_c, a_c = e.compensate(g_out * k, a_out * k)
        g_c, a_c = g_c / k, a_c / k
    y = signal_conditioning.BiquadFilter(sos, 6).filter(np.c_[g_c, a_c])
    cfg = gf.SinsConfig(input=mode)
    ref = gf.Strapdown(x0, cfg).run(y[:, :3], y[:, 3:], dt_s=dt)
    out = run_sins_fmu(g_out, a_out, dt, x0, config=cfg, imu_errors=e, lowpass_sos=sos,
                       fmi_version=version)
    for name in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"):
        x, r = getattr(out, name), getattr(ref, name)
        assert np.all(np.abs(x - r) <= 1e-12 * np.maximum(np.abs(r), 1e-300)), name


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_refuses_bad_error_parameters(circle, version):
    x0 = gf.NavState.from_trajectory(circle, 0)
    with pytest.raises(gf.FmuRunError, match="gyro_scale"):
        run_fmu("sins", {"dtheta": np.zeros((3, 3))}, ["q"], 0.01,
                parameters={"imu_comp": 1, "gyro_scale": [0.7, 0, 0], "q0": x0.q_bn},
                fmi_version=version)
    with pytest.raises(gf.FmuRunError, match="lowpass_sos section 0: unstable"):
        run_fmu("sins", {"dtheta": np.zeros((3, 3))}, ["q"], 0.01,
                parameters={"lowpass_sections": 1, "lowpass_sos": [1, 0, 0, 1, -2.5, 1.5] + [0] * 42},
                fmi_version=version)


# ---- issue 15: the Euler output, parameter messages -----------------------------------

def _wrap_pi(x):
    return (np.asarray(x) + np.pi) % (2 * np.pi) - np.pi


@pytest.mark.parametrize("version", [2, 3])
def test_navigator_fmus_euler_output_follows_the_attitude(circle, version):
    """The "euler" output (heading, pitch, roll) of the SINS and gyro-free navigator FMUs
    against the circle's closed-form Euler angles (trajectory.Circle.euler: heading -w t,
    pitch 3 deg sin 2wt, roll -5 deg), along 2 s in which the heading turns 11.5 deg.
    Measured: 6.8e-9 rad for both (the navigation error of these exact rate inputs);
    bound 2x. (Before, no test read this output: freezing it at the initial attitude
    went unnoticed.)"""
    tr = circle
    n = 200
    x0 = gf.NavState.from_trajectory(tr, 0)
    (psi, th, ga), _ = tr.motion.euler(tr.t_s[:n])
    start = {"q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad, "lon0": x0.lon_rad,
             "h0": x0.h_m}
    # rates: the outputs after the step at t_k describe t_k
    sins = run_fmu("sins", {"gyro_rate": tr.gyro_rad_s[:n], "specific_force": tr.accel_m_s2[:n]},
                   ["euler"], tr.dt_s, parameters={"input_mode": 1, **start},
                   fmi_version=version)["euler"]
    g = gf.layout("qin9", 0.1)
    gfnav = run_fmu("gfnav_qin9", {"A": tr.array_outputs(g)[:n]}, ["euler"], tr.dt_s,
                    parameters={"strategy": 1, "omega_init": tr.gyro_rad_s[0], **start},
                    fmi_version=version)["euler"]
    for name, e in (("sins", sins), ("gfnav_qin9", gfnav)):
        err = np.c_[_wrap_pi(e[:, 0] - psi), e[:, 1] - th, e[:, 2] - ga]
        assert np.abs(err).max() < 1.4e-8, name
        assert abs(_wrap_pi(e[-1, 0] - e[0, 0])) > np.radians(11), name     # it did turn


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_vehicle_attitude_outputs(circle, version):
    """With rotating = 1 the SINS FMU navigates the IMU frame m and outputs the vehicle's
    attitude from the gimbal input: q_vehicle = q_m^n * conj(q_m^b) with C_m^b = R_x(alpha)
    R_z(beta) (docs/rotating_ins.md), written here with numpy quaternions, and
    euler_vehicle its Euler angles. Round-off only: 1e-12."""
    tr = circle
    n = 50
    x0 = gf.NavState.from_trajectory(tr, 0)
    start = {"q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad, "lon0": x0.lon_rad, "h0": x0.h_m}
    alpha, beta = 0.3, -0.7
    gimbal = np.tile([alpha, beta], (n, 1))
    out = run_fmu("sins", {"gyro_rate": tr.gyro_rad_s[:n], "specific_force": tr.accel_m_s2[:n],
                           "gimbal": gimbal}, ["q", "q_vehicle", "euler_vehicle"], tr.dt_s,
                  parameters={"input_mode": 1, "rotating": 1, **start}, fmi_version=version)

    def qmul(p, q):
        w1, x1, y1, z1 = p.T
        w2, x2, y2, z2 = q.T
        return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                         w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], -1)

    q_mb = qmul(np.array([np.cos(alpha / 2), np.sin(alpha / 2), 0, 0]),
                np.array([np.cos(beta / 2), 0, 0, np.sin(beta / 2)]))
    want = qmul(out["q"], np.tile(q_mb * [1, -1, -1, -1], (n, 1)))
    got = out["q_vehicle"] * np.sign(np.sum(out["q_vehicle"] * want, axis=1))[:, None]
    assert np.abs(got - want).max() < 1e-12
    e = gf.quat_to_euler(out["q_vehicle"])
    assert np.abs(np.c_[_wrap_pi(out["euler_vehicle"][:, 0] - e[:, 0]), out["euler_vehicle"][:, 1:] - e[:, 1:]]).max() < 1e-12


@pytest.mark.parametrize("version", [2, 3])
def test_accel9_fmu_blames_the_lever_arm_below_its_minimum(record, version):
    """l = 1e-7 m is positive but below the 1e-6 m minimum (before: the FMU logged
    'omega_init must be finite')."""
    with pytest.raises(gf.FmuRunError, match=r"parameter l = 1e-07 m: the lever arm must be "
                                             r"finite and >= 1e-6 m") as exc:
        gf.run_accel9_fmu(record[:5], DT, 1e-7, W0, fmi_version=version)
    assert "omega_init" not in str(exc.value)
    with pytest.raises(gf.FmuRunError, match=r"parameter omega_init = \[nan"):
        run_fmu("accel9", {"A": record[:5]}, ["omega"], DT,
                parameters={"l": L, "omega_init": [np.nan, 0, 0]}, fmi_version=version)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("parameters, message", [
    ({"lat0": 2.0}, "parameter lat0 = 2 rad is outside the latitude limit"),
    ({"accel_noise": 0.0}, "parameter accel_noise = 0 m/s2 must be finite and > 0"),
    ({"omega_init": [np.inf, 0.0, 0.0]}, "parameter omega_init = [inf, 0, 0] rad/s must be finite"),
    ({"v0": [0.0, np.nan, 0.0]}, "parameter v0 = [0, nan, 0] m/s must be finite"),
    ({"q0": [0.0, 0.0, 0.0, 0.0]}, "parameter q0 = [0, 0, 0, 0] must be a finite, non-zero quaternion"),
    ({"h0": -4e6}, "parameter h0 = -4e+06 m must be finite and above -a/2"),
    ({"baro_tau": 0.0}, "parameter baro_tau = 0 s must be finite and > 0"),
    ({"vertical_mode": 5}, "parameter vertical_mode = 5 must be 0, 1 or 2"),
    ({"earth": 2}, "parameter earth = 2 must be 0 (WGS-84) or 1 (fixed frame)"),
    ({"strategy": 2}, "parameter strategy = 2 needs all products w w^T"),
], ids=["lat0", "accel_noise", "omega_init", "v0", "q0", "h0", "baro_tau", "vertical_mode",
        "earth", "strategy"])
def test_gfnav_fmu_blames_the_parameter_at_fault(version, parameters, message):
    """Before: lat0 = 2 rad and accel_noise = 0 were reported as 'strategy = 1 needs
    products this layout does not measure' on the qin9 navigator (strategy 1 = sqrt,
    which qin9 does measure); only the eigen strategy (2) is refused by this layout."""
    with pytest.raises(gf.FmuRunError) as exc:
        run_fmu("gfnav_qin9", {"A": np.zeros((3, 9))}, ["q"], 0.01,
                parameters={"strategy": 1, "q0": [1.0, 0, 0, 0], "lat0": 0.5, **parameters},
                fmi_version=version)
    text = str(exc.value)
    assert message in text, text
    if "strategy" not in parameters:
        assert "needs" not in text


@pytest.mark.parametrize("version", [2, 3])
def test_accel9_fmu_refuses_samples_beyond_the_physical_limits(record, version):
    """The FMU runs gf9_step, which applies the solver's physical limits (|f| <= 1000
    m/s^2, |omega| <= 50 rad/s) as gf9_solve does: same refusal, same partial."""
    A = record[:10].copy()
    A[6] = 1e300
    with pytest.raises(gf.FmuRunError, match=r"t = 0.06 s failed: a sample is beyond the stated "
                                             r"physical limit") as exc:
        gf.run_accel9_fmu(A, DT, L, W0, fmi_version=version)
    with pytest.raises(gf.SampleError) as ref:
        gf.solve_accel9(A, DT, L, W0)
    assert len(exc.value.partial) == ref.value.index == 6
    assert np.array_equal(exc.value.partial.omega_rad_s, ref.value.partial.omega_rad_s)


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_compensates_lever_arms_across_the_axes_and_the_delay(circle, version):
    """Issue 22: the SINS FMU's compensation with accelerometers offset across their axes
    and a 1 ms delay = ImuErrors.compensate with the angular acceleration from the
    backward difference of the compensated mean rates (gf_imu_compensate_step), then the
    strapdown; 1e-12 relative (the FMU scales by 1/dt in its own order)."""
    tr = circle
    x0 = gf.NavState.from_trajectory(tr, 0)
    e = gf.ImuErrors(accel_bias_ug=[10, 20, 30], lever_arm_cm=[[1, 2, 3], [4, 5, 6], [0, 0, 0]],
                     accel_delay_ms=1.0)
    dt = tr.dt_s
    g_out, a_out = e.apply_increments(tr.dtheta_rad, tr.dv_m_s, dt)
    k = 1.0 / dt
    w0, _ = e.compensate(g_out * k, a_out * k)
    wd = gf.ImuErrors.rate_derivative(w0, dt)
    g_c, a_c = e.compensate(g_out * k, a_out * k, omega_dot_rad_s2=wd)
    cfg = gf.SinsConfig(input="increments")
    ref = gf.Strapdown(x0, cfg).run(g_c / k, a_c / k, dt_s=dt)
    out = run_sins_fmu(g_out, a_out, dt, x0, config=cfg, imu_errors=e, fmi_version=version)
    for name in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"):
        x, r = getattr(out, name), getattr(ref, name)
        assert np.all(np.abs(x - r) <= 1e-12 * np.maximum(np.abs(r), 1e-300)), name
