"""Every FMU parameter, enumerated, with a value distinct from every other, so that a
mapping slip (one parameter read into another's place, one axis for another) cannot hide
behind equal values (issue 25: the integrated navigator's FMU taking the gyro
scale-factor P0 from the accelerometer's parameter passed every test, which gave both the
same value).

gfins_ins_gnss: the parameters are enumerated from the model description and each is
accounted for: a row of the settings table, an initial-state or initial-std parameter,
or one of the FMU's own (alignment, skip_steps; their own tests named below). Five
cases draw every float setting from the table with values all different from each other
(and different per axis), the switches (flags and the two enumerations) with a code per
switch, so that every two switches differ in at least one case and every switch is on in
one; in each case the FMU equals the batch API (IntegratedNavigator.run) bit for bit. In
the case with every switch on, each parameter is perturbed in the batch run alone to
show that the comparison sees it: the parameters it cannot see (limits that no sample
reaches, a latency no measurement has) are listed with the reason and the test that
checks their mapping instead (the refusal test names the parameter the core refused,
which is the one set out of bounds only when the mapping is right).

The other FMUs' parameters: tests/fmi/test_other_fmu_parameters.py.

Drive: 30 s of a simulated tactical-grade IMU (noise, so that the standstill thresholds
matter) from rest, start, turn, stop; GNSS at 1 Hz with a lever arm, barometer and
odometer at 10 Hz (gf_aiding_sim through gfins_fmi.sim).
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description

import gfins_fmi as gf
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.settings import fmu_settings
from gfins_fmi.fmi.ins_gnss import INITIAL_STD_PARAMETERS, ins_gnss_fmu_parameters, run_ins_gnss_fmu
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive
from gfins_fmi.sim.vehicle import Barometer, GnssReceiver, Odometer, Segment, VehicleProfile

T_S = 30.0
#: the switches, each with a code: case c turns switch i on when bit c of its code is
#: set; the codes differ pairwise in their low four bits (each pair of switches differs
#: in one of cases 0-3) and all have bit 4 (case 4: every switch on)
SWITCHES = ("input", "coning", "filter", "scale_factors", "baro_bias", "odometer_scale",
            "odometer_mount", "nhc", "zupt")
CODES = {name: 16 + i + 1 for i, name in enumerate(SWITCHES)}
N_CASES = 5
ALL_ON = 4

#: the FMU's own parameters (no row of the settings table, no batch counterpart) and
#: where their mapping is tested
FMU_ONLY = {
    "skip_steps": "tests/c/test_fmu_ins_gnss.c (skip_steps = 2 equals the core started there)",
    "align_time": "tests/fmi/test_fmu_alignment.py, test_fmu_ins_gnss.py::test_alignment_from_gnss_travel",
    "align_heading": "test_fmu_ins_gnss.py::test_alignment_from_gnss_travel",
    "align_min_speed": "test_fmu_ins_gnss.py::test_alignment_from_gnss_travel",
    "align_travel_std": "test_fmu_ins_gnss.py::test_alignment_from_gnss_travel (heading 1-sigma)",
}
INITIAL = ("q0", "v0", "lat0", "lon0", "h0", "sensors0")

#: settings the run cannot see (measured by the perturbation below), and why; their
#: mapping is checked by test_fmu_ins_gnss.py::test_every_bad_setting_is_refused_naming_its_parameter
INERT = {
    "max_imu_gap_s": "a limit: no IMU interval comes near it",
    "max_rate_rad_s": "a limit: no sample comes near it",
    "max_specific_force_m_s2": "a limit: no sample comes near it",
    "max_latency_s": "the driver delivers every measurement in the step of its time of "
                     "validity: none is late",
}


@pytest.fixture(scope="module")
def data():
    prof = VehicleProfile(speed0_m_s=0.0, segments=[
        Segment(4.0), Segment(4.0, dspeed_m_s=6.0), Segment(6.0, dheading_rad=np.pi / 2),
        Segment(4.0, dspeed_m_s=2.0), Segment(5.0, dspeed_m_s=-8.0), Segment(7.0)])
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, lever_arm_m=(0.31, 1.27, 1.61),
                      pos_std_m=(0.4, 0.5, 0.9), vel_std_m_s=(0.03, 0.04, 0.07))
    d = simulate_drive(prof, T_S, 0.01, imu=TACTICAL, gnss=rx, seed=17,
                       baro=Barometer(rate_hz=10.0, offset_s=0.023, std_m=0.35, bias0_m=1.5),
                       odometer=Odometer(rate_hz=10.0, offset_s=0.047, lever_arm_m=(-0.7, 0.2, -0.4),
                                         scale_error=0.015, std_m_s=0.04))
    # the same samples as rates at the sample times, the first at the start
    rates = d.imu.to_rates()
    return d, rates


#: the IMU's six noise settings come from FilterConfig.imu (datasheet units): the ImuNoise
#: field behind each, and its value here (all different)
IMU_FIELDS = {"gyro_arw_rad_sqrt_s": "gyro_arw_deg_sqrt_h", "accel_vrw_m_s_sqrt_s": "accel_vrw_ug_sqrt_hz",
              "gyro_bias_std_rad_s": "gyro_bias_instability_deg_h",
              "gyro_bias_tau_s": "gyro_correlation_time_s",
              "accel_bias_std_m_s2": "accel_bias_instability_ug",
              "accel_bias_tau_s": "accel_correlation_time_s"}
IMU = dict(gyro_arw_deg_sqrt_h=0.17, accel_vrw_ug_sqrt_hz=63.0, gyro_bias_instability_deg_h=2.3,
           gyro_correlation_time_s=3100.0, accel_bias_instability_ug=47.0,
           accel_correlation_time_s=2900.0)
#: FilterConfig's fields (Python form), every float and every vector element different
FIELDS = dict(
    propagation_interval_s=0.05, max_imu_gap_s=0.37, max_rate_rad_s=41.0,
    max_specific_force_m_s2=870.0, ukf_alpha=0.43, ukf_beta=2.17, ukf_kappa=0.29,
    gyro_scale_std=7.3e-4, gyro_scale_tau_s=5100.0, accel_scale_std=5.9e-4,
    accel_scale_tau_s=4700.0, baro_bias_std_m=1.7, baro_bias_tau_s=2300.0,
    odometer_scale_std=0.013, odometer_scale_tau_s=6100.0, odometer_mount_std_rad=0.027,
    odometer_mount_tau_s=7300.0, gnss_lever_arm_m=(0.31, 1.27, 1.61),
    odometer_lever_arm_m=(-0.7, 0.2, -0.4), gnss_position_std_floor_m=(0.53, 0.61, 0.97),
    gate_probability=0.83, gate_reset_count=3, nhc_std_m_s=0.11, nhc_interval_s=0.19,
    zupt_std_m_s=0.012, zaru_std_rad_s=3.7e-4, zupt_interval_s=0.14, standstill_window_s=0.47,
    standstill_accel_std_m_s2=0.057, standstill_gyro_rad_s=0.0093, max_latency_s=0.21,
    odometer_mount_rad=(0.0061, -0.0083))
#: InitialState's stds (the FMU's std0_*), every element different
STDS = dict(position_std_m=(0.8, 1.1, 1.9), velocity_std_m_s=(0.07, 0.08, 0.13),
            attitude_std_rad=(0.0031, 0.0043, 0.0157), gyro_bias_std_rad_s=(1.3e-5, 1.7e-5, 1.9e-5),
            accel_bias_std_m_s2=(2.9e-4, 3.3e-4, 3.9e-4), gyro_scale_std=(4.1e-4, 4.3e-4, 4.7e-4),
            accel_scale_std=(5.3e-4, 5.7e-4, 6.1e-4), baro_bias_std_m=2.3, odometer_scale_std=0.017,
            odometer_mount_std_rad=(0.019, 0.023))
#: the initial sensor-error estimates (SENSOR_NAMES order), all different
SENSORS0 = np.array([1.1e-5, -1.3e-5, 1.6e-5, 2.3e-4, -2.9e-4, 3.1e-4, 1.9e-4, -2.1e-4, 2.7e-4,
                     -3.3e-4, 3.4e-4, -4.1e-4, 0.41, 0.0047, 0.0013, -0.0019])


def _switch(case: int, name: str) -> int:
    return (CODES[name] >> case) & 1


def _objects(case: int, data, fields=None, imu=None, stds=None, nav_edit=None, sensors=None,
             filter=None):
    """(FilterConfig, InitialState, IMU record) of a case, with any part replaced."""
    d, rates = data
    kw = dict(FIELDS if fields is None else fields)
    for name in SWITCHES:
        on = _switch(case, name)
        kw[name] = {"input": ("increments", "rates"), "filter": ("ekf", "ukf")}.get(
            name, (False, True))[on]
    if filter:
        kw["filter"] = filter
    cfg = FilterConfig(imu=gf.ImuNoise(**(IMU if imu is None else imu)), **kw)
    rec = rates if cfg.input == "rates" else d.imu
    # the start: the truth's position, velocity and attitude a little off on every axis
    # (so that no two elements of q0 or v0 are equal)
    q = gf.euler_to_quat(gf.quat_to_euler(d.initial.q_bn) + np.array([0.0031, 0.0021, -0.0017]))
    nav = dict(q_bn=q, v_n_m_s=np.array([0.011, -0.007, 0.003]), lat_rad=d.initial.lat_rad + 2e-8,
               lon_rad=d.initial.lon_rad - 3e-8, h_m=d.initial.h_m + 0.7,
               t_s=0.0 if cfg.input == "increments" else float(rec.t_s[0]))
    if nav_edit:
        nav_edit(nav)
    init = InitialState(gf.NavState(**nav), **(STDS if stds is None else stds),
                        sensors=SENSORS0 if sensors is None else sensors)
    return cfg, init, rec


def _fmu_parameter_values(params: dict) -> list:
    """The float parameters' values, flattened (switches and counts left out)."""
    out = []
    for name, value in params.items():
        if name in CODES or name in FMU_ONLY or name == "gate_reset_count":
            continue
        out += [float(x) for x in np.ravel(value)]
    return out


def _same(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k))
               for k in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors"))


def test_every_fmu_parameter_is_accounted_for():
    """The model description's parameters = the settings table's FMU rows + the initial
    state + the initial stds + the FMU's own; ins_gnss_fmu_parameters sets every one but
    skip_steps; the switches are the table's flags and enumerations."""
    md = read_model_description(str(gf.fmu_path("ins_gnss", 3)))
    params = {v.name for v in md.modelVariables if v.causality == "parameter"}
    table = {st.short for st in fmu_settings()}
    expected = table | set(INITIAL_STD_PARAMETERS.values()) | set(INITIAL) | set(FMU_ONLY)
    assert params == expected, (params - expected, expected - params)
    switches = {st.short for st in fmu_settings() if st.kind in ("flag", "enum")}
    assert switches == set(SWITCHES)
    assert set(FIELDS) | set(IMU_FIELDS) | switches == {st.python_name or st.short
                                                        for st in fmu_settings()}
    assert set(STDS) == set(INITIAL_STD_PARAMETERS)
    # the codes: every switch on in some case, every two differing in one of cases 0-3
    for a in SWITCHES:
        assert any(_switch(c, a) for c in range(N_CASES - 1))
        assert all(_switch(ALL_ON, a) for a in SWITCHES)
        for b in SWITCHES:
            assert a == b or any(_switch(c, a) != _switch(c, b) for c in range(N_CASES - 1))


@pytest.mark.parametrize("case", range(N_CASES))
def test_fmu_equals_batch_with_every_parameter_distinct(data, case):
    """Every float parameter (settings, std0_*, q0, v0, position, sensors0) different from
    every other, the switches of the case: the FMU computes the batch API's bits."""
    d, _ = data
    cfg, init, rec = _objects(case, data)
    params = ins_gnss_fmu_parameters(cfg, init)
    values = _fmu_parameter_values(params)
    assert len(values) == len(set(values)), "two parameters share a value"
    ref = IntegratedNavigator(cfg, init).run(rec, d.gnss, d.baro, d.odometer)
    out = run_ins_gnss_fmu(rec, d.gnss, d.baro, d.odometer, config=cfg, initial=init,
                           fmi_version=2 + case % 2)
    for name in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors",
                 "standstill"):
        assert np.array_equal(getattr(out, name), getattr(ref, name)), name
    for name in ("t_s", "type", "status", "nis"):
        assert np.array_equal(out.innovations[name], ref.innovations[name], equal_nan=True), name
    # the switches act: the states, the constraints and the detector of the case
    kinds = set(np.unique(ref.innovations["type"]).tolist())
    assert (5 in kinds) == bool(_switch(case, "nhc"))                  # NHC updates
    assert (6 in kinds) == bool(_switch(case, "zupt"))                 # ZUPT updates
    assert cfg.n_states == 15 + 6 * _switch(case, "scale_factors") + _switch(case, "baro_bias") \
        + _switch(case, "odometer_scale") + 2 * _switch(case, "odometer_mount")


def _perturbations():
    """(FMU parameter[element], how to change it) for every float parameter the all-on
    case uses: each FilterConfig field and vector element, each ImuNoise value, each
    initial std element, q0, v0, lat0, lon0, h0 and every sensors0 element."""
    out = []
    for st in fmu_settings():
        if st.kind in ("flag", "enum"):
            continue
        if st.short in IMU_FIELDS:
            f = IMU_FIELDS[st.short]
            out.append((st.short, dict(imu={**IMU, f: IMU[f] * 1.1})))
            continue
        value = FIELDS[st.python_name]
        if st.kind == "vector":
            for i in range(st.size):
                v = list(value)
                v[i] = v[i] * 1.1 + 0.01
                out.append((f"{st.short}[{i}]", dict(fields={**FIELDS, st.python_name: tuple(v)})))
        elif st.kind == "int":
            out.append((st.short, dict(fields={**FIELDS, st.python_name: value + 1})))
        else:
            out.append((st.short, dict(fields={**FIELDS, st.python_name: value * 1.1})))
    for name, std0 in INITIAL_STD_PARAMETERS.items():
        value = STDS[name]
        for i in range(np.size(value)):
            v = np.array(value, float).ravel()
            v[i] *= 1.1
            out.append((f"{std0}[{i}]", dict(stds={**STDS, name: tuple(v) if np.ndim(value) else float(v[0])})))
    for i in range(16):
        s = SENSORS0.copy()
        s[i] *= 1.1
        out.append((f"sensors0[{i}]", dict(sensors=s)))

    def edit(key, i=None, dx=1e-4):
        def f(nav):
            if i is None:
                nav[key] = nav[key] + dx
            else:
                v = np.array(nav[key], float)
                v[i] += dx
                nav[key] = v
        return f
    for i in range(4):
        out.append((f"q0[{i}]", dict(nav_edit=edit("q_bn", i))))
    for i in range(3):
        out.append((f"v0[{i}]", dict(nav_edit=edit("v_n_m_s", i))))
    out += [("lat0", dict(nav_edit=edit("lat_rad", dx=1e-8))), ("lon0", dict(nav_edit=edit("lon_rad", dx=1e-8))),
            ("h0", dict(nav_edit=edit("h_m", dx=0.1)))]
    return out


@pytest.mark.parametrize("filter", ["ekf", "ukf"])
def test_the_comparison_sees_every_parameter(data, filter):
    """In the all-on case (rates, 25 states, NHC, ZUPT and ZARU), changing any one float
    parameter or element alone changes the batch run's outputs, except the INERT
    settings (limits and a latency the drive never reaches): so FMU = batch above could
    not hold with a parameter read into another's place. The EKF for every parameter but
    the UKF's three (a UKF run takes ten times an EKF run: 35 ms here), the UKF for
    those."""
    d, _ = data
    cfg, init, rec = _objects(ALL_ON, data, filter=filter)
    base = IntegratedNavigator(cfg, init).run(rec, d.gnss, d.baro, d.odometer)
    inert, seen = [], []
    for label, change in _perturbations():
        if label.startswith("ukf_") != (filter == "ukf"):
            continue
        seen.append(label)
        c, i, r = _objects(ALL_ON, data, filter=filter, **change)
        if _same(IntegratedNavigator(c, i).run(r, d.gnss, d.baro, d.odometer), base):
            inert.append(label)
    if filter == "ukf":
        assert seen == ["ukf_alpha", "ukf_beta", "ukf_kappa"] and not inert, inert
    else:
        assert sorted(inert) == sorted(INERT), inert
