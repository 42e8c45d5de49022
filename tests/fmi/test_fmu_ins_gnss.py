"""The integrated-navigator FMU (gfins_ins_gnss, FMI 2.0 and 3.0) against the batch API
(IntegratedNavigator.run) on a simulated drive: the same gf_ins_step calls, so the same
bits; measurement timing, FMU states, refused parameters and inputs.

Records: the drive and the GNSS epochs of tests/estimation/test_integrated_navigator.py (exact vehicle truth
from gf_vehicle, IMU increments summed from a 1 kHz truth, GNSS antenna positions and
velocities computed in numpy)."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import gfins_fmi as gf
from gfins_fmi.nav import earth
from gfins_fmi._lib import lib
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.fmi.paths import FmuRunError
from gfins_fmi.fmi.ins_gnss import InsGnssDriver, ins_gnss_fmu_parameters, run_ins_gnss_fmu
from gfins_fmi.estimation.settings import fmu_settings
from support.drives import Rec, drive, gnss_record, quiet_config

LEVER = np.array([0.4, 1.2, 1.6])


@pytest.fixture(scope="module")
def rec():
    """30 s of the drive: IMU increments at 100 Hz; GNSS at 1 Hz, 3 ms after IMU samples
    (the interval is split there), with a lever arm; barometer at 10 Hz and odometer at
    10 Hz at other odd instants."""
    tr, imu = drive(30.0)
    gnss = gnss_record(tr, np.arange(1003, len(tr.t_s), 1000), LEVER)
    kb = np.arange(1057, len(tr.t_s), 100)
    baro = Rec(t_s=tr.t_s[kb].copy(), h_m=tr.h_m[kb] + 2.0, std_m=np.full(len(kb), 0.5))
    ko = np.arange(1021, len(tr.t_s), 100)
    C = np.array(earth.quat_to_dcm(tr.q_bn[ko]))
    u = np.einsum("kji,kj->ki", C, tr.v_n_m_s[ko])[:, 1]       # forward speed, body y
    odo = Rec(t_s=tr.t_s[ko].copy(), speed_m_s=1.002 * u, std_m_s=np.full(len(ko), 0.02))
    return tr, imu, gnss, baro, odo


def _initial(tr, k=0, cls=InitialState):
    return cls(gf.NavState.from_trajectory(tr, k), position_std_m=(0.3, 0.2, 0.5),
               velocity_std_m_s=0.05, attitude_std_rad=(1e-3, 1e-3, 5e-3))




CASES = {
    "ekf": dict(),
    "ukf": dict(filter="ukf"),
    # every measurement kind, every optional state, NHC, propagation at every sample, a
    # configured odometer boresight (FMU parameter odometer_mount_rad)
    "ekf-aided-25": dict(scale_factors=True, baro_bias=True, odometer_scale=True, nhc=True,
                         odometer_mount=True, propagation_interval_s=0.0,
                         odometer_mount_rad=(0.01, -0.02)),
    "ukf-aided-25": dict(filter="ukf", scale_factors=True, baro_bias=True, odometer_scale=True,
                         nhc=True, odometer_mount=True, odometer_mount_tau_s=900.0),
    "ekf-rates": dict(input="rates"),
}


def _case(rec, name):
    tr, imu, gnss, baro, odo = rec
    cfg = quiet_config(gnss_lever_arm_m=LEVER, **CASES[name])
    aided = "aided" in name
    if cfg.input == "rates":   # rate samples at the IMU times, the first at the start
        imu = Rec(t_s=tr.t_s[::10].copy(), gyro=tr.gyro_rad_s[::10], accel=tr.accel_m_s2[::10],
                  kind="rates")
    return cfg, imu, gnss, baro if aided else None, odo if aided else None


@pytest.mark.parametrize("version", [2, 3])
def test_ins_gnss_fmu_valid(version):
    path = gf.fmu_path("ins_gnss", version)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.coSimulation.modelIdentifier == "gfins_ins_gnss"
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate


def _start_values(version=3):
    md = read_model_description(str(gf.fmu_path("ins_gnss", version)))
    out = {}
    for v in md.modelVariables:
        if v.causality == "parameter":
            vals = [float(x) for x in str(v.start).split()]
            out[v.name] = vals if len(vals) > 1 or v.dimensions else vals[0]
    return out


def test_fmu_defaults_are_the_batch_defaults():
    """The FMU's start values = what ins_gnss_fmu_parameters makes of FilterConfig() with the
    documented default IMU and InitialState()'s defaults; every FMU parameter is set by it."""
    imu = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=10.0,
                      gyro_correlation_time_s=3600.0, accel_vrw_ug_sqrt_hz=100.0,
                      accel_bias_instability_ug=100.0, accel_correlation_time_s=3600.0)
    start = _start_values()
    nav = gf.NavState(np.array(start["q0"]), np.array(start["v0"]), start["lat0"], start["lon0"],
                      start["h0"], 0.0)
    params = ins_gnss_fmu_parameters(FilterConfig(imu=imu), InitialState(nav))
    assert set(start) - set(params) == {"skip_steps"}
    assert set(params) <= set(start)
    for name, value in params.items():
        # the spec writes the SI noise with repr(): equal to the last bit
        assert np.array_equal(np.asarray(start[name], float), np.asarray(value, float)), name
    assert {st.short for st in fmu_settings()} <= set(start)


def _reference(cfg, imu, gnss, baro, odo, initial):
    return IntegratedNavigator(cfg, initial).run(imu, gnss, baro, odo)


FIELDS = ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors", "standstill")


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", sorted(CASES))
def test_fmu_equals_batch_bit_for_bit(rec, version, case):
    """Same samples, times, measurements and P0: the FMU makes the gf_ins_step calls of
    gf_ins_run, so every output and every update's time, kind, outcome and NIS are equal
    to the last bit."""
    cfg, imu, gnss, baro, odo = _case(rec, case)
    init = _initial(rec[0])
    ref = _reference(cfg, imu, gnss, baro, odo, init)
    out = run_ins_gnss_fmu(imu, gnss, baro, odo, config=cfg, initial=init, fmi_version=version)
    assert len(out) == len(ref) == len(imu.t_s)
    for name in FIELDS:
        assert np.array_equal(getattr(out, name), getattr(ref, name)), name
    for name in ("t_s", "type", "status", "m", "nis"):
        assert np.array_equal(out.innovations[name], ref.innovations[name], equal_nan=True), name
    kinds = set(np.unique(ref.innovations["type"]).tolist())
    assert kinds == ({1, 2, 3, 4, 5} if "aided" in case else {1, 2})
    # and the filter works on these exact data: position within a centimetre of the truth
    tr = rec[0]
    k = np.searchsorted(tr.t_s, out.t_s[-1] - 1e-9)
    assert abs(out.lat_rad[-1] - tr.lat_rad[k]) * 6.4e6 < 0.01


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_with_its_own_p0_agrees_with_the_batch(rec, version):
    """InitialState converts the position stds with gf_earth's radii as the FMU does, so
    the batch API and the FMU start from the same P0 and compute the same bits."""
    cfg, imu, gnss, baro, odo = _case(rec, "ekf")
    init = _initial(rec[0])
    ref = _reference(cfg, imu, gnss, baro, odo, init)
    out = run_ins_gnss_fmu(imu, gnss, config=cfg, initial=init, fmi_version=version)
    for name in FIELDS:
        x, y = np.asarray(getattr(out, name), float), np.asarray(getattr(ref, name), float)
        assert np.array_equal(x, y), name


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("serialize", [False, True])
def test_fmu_state_restore_reproduces_the_run(rec, version, serialize):
    """FMU state taken mid-run (after 1 200 samples), continued, restored and continued
    again — in the same instance, or serialized into a fresh one — gives the same rows,
    which are the batch API's."""
    cfg, imu, gnss, baro, odo = _case(rec, "ukf-aided-25")
    init = _initial(rec[0])
    kw = dict(config=cfg, initial=init, fmi_version=version)
    mid = 1200
    a = InsGnssDriver(imu, gnss, baro, odo, **kw)
    b = InsGnssDriver(imu, gnss, baro, odo, **kw)
    try:
        a.initialize()
        a.run(0, mid)
        s = a.slave.slave
        state = s.getFMUState() if version == 3 else s.getFMUstate()
        a.run(mid, a.n_steps)
        first = a.out_f.copy(), a.out_i.copy()
        a.out_f[mid:] = np.nan
        if serialize:
            blob = s.serializeFMUState(state) if version == 3 else s.serializeFMUstate(state)
            b.initialize()
            t = b.slave.slave
            state_b = (t.deserializeFMUState if version == 3 else t.deSerializeFMUstate)(blob)
            (t.setFMUState if version == 3 else t.setFMUstate)(state_b)
            b.forget_inputs()
            b.out_f[:mid], b.out_i[:mid] = first[0][:mid], first[1][:mid]
            b.run(mid, b.n_steps)
            again, sol = (b.out_f, b.out_i), b.solution()
        else:
            (s.setFMUState if version == 3 else s.setFMUstate)(state)
            a.forget_inputs()
            a.run(mid, a.n_steps)
            again, sol = (a.out_f, a.out_i), a.solution()
        (s.freeFMUState if version == 3 else s.freeFMUstate)(state)
    finally:
        a.close()
        b.close()
    assert np.array_equal(first[0], again[0], equal_nan=True) and np.array_equal(first[1], again[1])
    ref = _reference(cfg, imu, gnss, baro, odo, init)
    assert np.array_equal(sol.lat_rad, ref.lat_rad) and np.array_equal(sol.q_bn, ref.q_bn)


def bad_value(st):
    """A value outside a setting's bounds (C form), and the flag it needs to be checked."""
    bad = {"flag": 2, "enum": 7, "count": -1, "subsamples": 9, "nonneg": -1.0, "positive": 0.0,
           "finite": float("nan"), "probability": 1.5}.get(st.bounds)
    if st.kind == "vector":
        bad = [0.0] * st.size
        bad[-1] = 2.0 if st.bounds == "half_pi" else float("nan")
    return bad, ({st.when: 1} if st.when else {})


SETTINGS_REFUSED = [s for s in fmu_settings()]


@pytest.mark.parametrize("st", SETTINGS_REFUSED, ids=[s.short for s in SETTINGS_REFUSED])
def test_every_bad_setting_is_refused_naming_its_parameter(rec, st):
    """Every FMU parameter of the settings table, set outside its bounds, is refused with a
    message naming the parameter, its value, unit and bounds (the FMU's table is generated
    from the same rows)."""
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    value, extra = bad_value(st)
    extra[st.short] = value
    version = 3 if st.kind == "vector" else 2        # both glues: the same model code
    with pytest.raises(FmuRunError, match="refused its parameters") as exc:
        run_ins_gnss_fmu(Rec(t_s=imu.t_s[:5], gyro=imu.gyro[:5], accel=imu.accel[:5],
                             kind="increments"), config=cfg, initial=_initial(rec[0]),
                         parameters=extra, fmi_version=version)
    unit = f" {st.unit}" if st.unit else ""
    want = f"parameter {st.short} = .*{re.escape(unit)} refused: must be "
    assert any(re.search(want, m) for m in exc.value.messages), (want, exc.value.messages)


REFUSED = [
    ("lat0", 1.56, "parameter lat0 = 1.56 rad \\(start latitude 1.56 rad\\): it must be within "
                   "\\+-89 deg"),
    ("h0", float("nan"), "q0, v0, lon0 and h0 must be finite"),
    ("sensors0", [0.0] * 15 + [float("nan")], "sensors0 must be finite"),
    ("std0_pos", [1.0, 0.0, 1.0], "parameter std0_pos = \\[1, 0, 1\\] m: every element"),
    ("std0_att", [1e-3, 1e-3, -1.0], "std0_att"),
    ("std0_baro_bias", 0.0, "std0_baro_bias = 0 m"),       # with baro_bias = 1 below
    ("skip_steps", -1, "skip_steps = -1 must be >= 0"),
]


@pytest.mark.parametrize("name, value, match", REFUSED, ids=[r[0] for r in REFUSED])
def test_bad_parameters_are_refused_naming_the_parameter(rec, name, value, match):
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    extra = {name: value}
    if name == "std0_baro_bias":
        extra["baro_bias"] = 1
    version = 3 if name in ("lat0", "std0_pos") else 2   # both glues: same model
    with pytest.raises(FmuRunError, match="refused its parameters") as exc:
        run_ins_gnss_fmu(Rec(t_s=imu.t_s[:5], gyro=imu.gyro[:5], accel=imu.accel[:5],
                             kind="increments"), config=cfg, initial=_initial(rec[0]),
                         parameters=extra, fmi_version=version)
    assert any(re.search(match, m) for m in exc.value.messages), exc.value.messages


def test_unused_optional_std_is_not_checked(rec):
    """std0 of a block whose state is off is not used, so not refused."""
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    out = run_ins_gnss_fmu(Rec(t_s=imu.t_s[:5], gyro=imu.gyro[:5], accel=imu.accel[:5],
                               kind="increments"), config=cfg, initial=_initial(rec[0]),
                           parameters={"std0_baro_bias": 0.0, "std0_gyro_scale": [0, 0, 0]})
    assert len(out) == 5


def _driver(rec, case="ekf", version=2, **kw):
    cfg, imu, gnss, baro, odo = _case(rec, case)
    return InsGnssDriver(imu, gnss, baro, odo, config=cfg, initial=_initial(rec[0]),
                          fmi_version=version, **kw), cfg, imu, gnss


@pytest.mark.parametrize("version", [2, 3])
def test_measurement_delivered_late_is_stale(rec, version):
    """GNSS epochs delivered 0.5 s after their time of validity (latency): valid before the
    sample interval, logged as stale (status 3, NIS NaN) and counted as rejected, as the
    batch API logs a measurement valid before the filter's time; the navigation equals the
    batch run without GNSS."""
    drv, cfg, imu, gnss = _driver(rec, version=version)
    at = drv.gnss_at.copy()
    drv.gnss_at[:] = -1
    idx = np.flatnonzero(at >= 0)
    drv.gnss_at[idx + 50] = at[idx]
    try:
        drv.initialize()
        drv.run(0, drv.n_steps)
        sol = drv.solution()
        st, cnt = drv.out_i[-1, drv.cols_i["update_status"]], drv.out_i[-1, drv.cols_i["update_count"]]
    finally:
        drv.close()
    inn = sol.innovations
    assert len(inn) == 2 * len(idx) and np.all(inn["status"] == lib.GF_INS_REJECTED_STALE)
    assert np.all(np.isnan(inn["nis"]))
    assert list(st[:2]) == [3, 3] and list(cnt[:2]) == [len(idx)] * 2 and list(st[2:]) == [-1] * 5
    # stale: no update, so the run is the free-inertial one with the same filter
    ref = _reference(cfg, imu, None, None, None, _initial(rec[0]))
    assert np.array_equal(sol.lat_rad, ref.lat_rad) and np.array_equal(sol.std, ref.std)


def _one_epoch_run(rec, version, k_fine, edit=None, steps=None):
    """One exact GNSS epoch (truth row k_fine of the 1 kHz drive, a multiple of 10: on the
    IMU sample k_fine / 10 - 1) delivered in the FMU step of that sample, its inputs changed
    by ``edit``; returns (float outputs, int outputs, their columns, log, error, the
    latitude output read after the run)."""
    tr = rec[0]
    drv, cfg, imu, gnss = _driver(rec, version=version)
    step = k_fine // 10                 # FMU step k takes record row k - 1 (increments)
    g = gnss_record(tr, np.array([k_fine]), LEVER)
    row = np.r_[g.t_s, g.lat_rad, g.lon_rad, g.h_m, g.vel_enu_m_s[0], g.pos_std_m[0],
                g.vel_std_m_s[0]]
    if edit:
        edit(row)
    drv.gnss = row[None, :]
    drv.gnss_at[:] = -1
    drv.gnss_at[step] = 0
    err = None
    try:
        drv.initialize()
        try:
            drv.run(0, steps or step + 20)
        except FMICallException as exc:
            err = exc
        lat = drv.slave.get("lat")[0]
        return (drv.out_f.copy(), drv.out_i.copy(), drv.cols_f, drv.cols_i, list(drv.log.messages),
                err, lat)
    finally:
        drv.close()


@pytest.mark.parametrize("version", [2, 3])
def test_measurement_from_the_future_is_refused(rec, version):
    def future(row):
        row[0] += 0.5                                # valid 0.5 s after the sample (1.01 s)
    f, i, cf, ci, log, err, lat = _one_epoch_run(rec, version, 1010, future)
    assert err is not None
    assert any("gnss measurement valid at gnss_time_s = 1.51 s, after the IMU sample" in m
               for m in log), log
    assert lat == f[100, cf["lat"]][0]                # the outputs of the last good step are kept


@pytest.mark.parametrize("version", [2, 3])
def test_measurement_within_the_clock_tolerance_is_taken_at_the_sample(rec, version):
    """A time of validity 1e-8 s after the sample at t = 25.01 s: beyond the core's 1e-9 s
    but within the glue's tolerance on communication points (1e-9 max(1, t) = 2.5e-8 s), a
    master's clock rounding: the FMU takes it at the sample (accepted, logged at t)."""
    def late(row):
        row[0] += 1e-8
    f, i, cf, ci, log, err, _ = _one_epoch_run(rec, version, 25010, late)
    assert err is None, log
    k = 2501
    assert list(i[k, ci["update_status"]][:2]) == [0, 0]
    assert list(i[k, ci["update_count"]][:2]) == [1, 1]
    assert f[k, cf["update_time"]][0] == f[k, cf["time_s"]][0] == rec[1].t_s[2500]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("column, value, match", [
    (7, 0.0, "inputs GNSS gnss_lat_rad, gnss_lon_rad, gnss_h_m, gnss_pos_std_m: values must be "
             "finite and std > 0 (got [0.5"),
    (1, np.nan, "gnss_lat_rad"),
    (4, np.inf, "gnss_vel_enu_m_s, gnss_vel_std_m_s: values must be finite and std > 0 (got [inf"),
    (12, -1.0, "gnss_vel_std_m_s"),
    (0, np.nan, "gnss_time_s = nan is not finite"),
])
def test_bad_measurement_input_is_refused(rec, version, column, value, match):
    def bad(row):
        row[column] = value
    f, i, cf, ci, log, err, lat = _one_epoch_run(rec, version, 1010, bad)
    assert err is not None and any(match in m for m in log), log
    assert lat == f[100, cf["lat"]][0]


def test_gnss_velocity_flag(rec):
    """gnss_vel_valid = 0: position updates only, as the batch API with gnss_velocity=False."""
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    init = _initial(rec[0])
    ref = IntegratedNavigator(cfg, init).run(imu, gnss, gnss_velocity=False)
    out = run_ins_gnss_fmu(imu, gnss, config=cfg, initial=init, gnss_velocity=False)
    assert set(out.innovations["type"].tolist()) == {1}
    assert np.array_equal(out.lat_rad, ref.lat_rad) and np.array_equal(out.v_n_m_s, ref.v_n_m_s)


@pytest.mark.parametrize("version", [2, 3])
def test_nonfinite_imu_sample_keeps_the_outputs(rec, version):
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    g = imu.gyro.copy()
    g[250, 1] = np.nan
    bad = Rec(t_s=imu.t_s, gyro=g, accel=imu.accel, kind="increments")
    init = _initial(rec[0])
    with pytest.raises(FmuRunError, match="record row 250") as exc:
        run_ins_gnss_fmu(bad, gnss, config=cfg, initial=init, fmi_version=version)
    assert any("input dtheta = [" in m and "is not finite" in m for m in exc.value.messages)
    part = exc.value.partial
    ref = IntegratedNavigator(cfg, init).run(Rec(t_s=imu.t_s[:250], gyro=imu.gyro[:250],
                                                 accel=imu.accel[:250], kind="increments"), gnss)
    assert len(part) == 250 and np.array_equal(part.lat_rad, ref.lat_rad)


def test_helper_refuses_what_the_fmu_cannot_take(rec):
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    init = _initial(rec[0])
    two = Rec(t_s=np.array([1.003, 1.006]), lat_rad=gnss.lat_rad[:2], lon_rad=gnss.lon_rad[:2],
              h_m=gnss.h_m[:2], pos_std_m=gnss.pos_std_m[:2])
    with pytest.raises(ValueError, match="two GNSS measurements fall into the interval of IMU "
                                         "sample 100"):
        run_ins_gnss_fmu(imu, two, config=cfg, initial=init)
    with pytest.raises(ValueError, match="must be after initial.nav.t_s"):
        run_ins_gnss_fmu(Rec(t_s=imu.t_s - imu.t_s[0], gyro=imu.gyro, accel=imu.accel,
                             kind="increments"), config=cfg, initial=init)
    with pytest.raises(ValueError, match="holds 'increments' but the filter is configured for "
                                         "input='rates'"):
        run_ins_gnss_fmu(imu, config=quiet_config(input="rates"), initial=init)
    assert math.isfinite(run_ins_gnss_fmu(Rec(t_s=imu.t_s[:3], gyro=imu.gyro[:3],
                                              accel=imu.accel[:3], kind="increments"),
                                          config=cfg, initial=init).lat_rad[-1])


# ---- alignment from the GNSS direction of travel (align_heading = 1) -----------------------

MISALIGN = np.radians(3.0)        # IMU yawed against the vehicle: forward axis 3 deg left of travel
TRAVEL_LEVER = np.array([0.3, 1.0, 1.5])   # IMU -> antenna, vehicle axes


def _qmul(p, q):
    """Hamilton product of (n, 4) quaternions, written from its definition."""
    w0, x0, y0, z0 = np.moveaxis(np.asarray(p, float), -1, 0)
    w1, x1, y1, z1 = np.moveaxis(np.asarray(q, float), -1, 0)
    return np.stack([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1, w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                     w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1, w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1], -1)


@pytest.fixture(scope="module")
def travel():
    """A car at rest 15 s, then driving off (0 -> 10 m/s in 10 s), a right and a left turn,
    100 s, heading 70 deg (not told to the FMU); a consumer MEMS IMU (gyro bias 10 deg/h
    against a horizontal Earth rate of 13 deg/h at 30 deg latitude: gyrocompassing would be
    off by ~ bias / (Omega cos L) ~ 45 deg), mounted yawed MISALIGN to the left of the
    vehicle's forward axis; GNSS at 1 Hz, velocity noise 0.03 m/s, antenna TRAVEL_LEVER.

    The IMU record of the vehicle frame is turned into the IMU frame b' = Rz(MISALIGN) b:
    a constant rotation, so the increments turn with it exactly (dtheta' = Rz^T dtheta);
    the IMU's true attitude is q_bn (x) q_z(MISALIGN) and the lever arm in its axes
    Rz^T TRAVEL_LEVER."""
    from gfins_fmi.sim.scenarios import CONSUMER, simulate_drive
    from gfins_fmi.sim.vehicle import GnssReceiver, Segment, VehicleProfile
    prof = VehicleProfile(heading0_rad=np.radians(70.0), segments=[
        Segment(15.0), Segment(10.0, dspeed_m_s=10.0), Segment(15.0),
        Segment(10.0, dheading_rad=np.pi / 2), Segment(20.0),
        Segment(10.0, dheading_rad=-np.pi / 2, dspeed_m_s=-5.0), Segment(20.0)])
    rx = GnssReceiver(rate_hz=1.0, lever_arm_m=TRAVEL_LEVER, pos_std_m=(0.5, 0.5, 1.0),
                      vel_std_m_s=(0.03, 0.03, 0.05))
    d = simulate_drive(prof, 100.0, 0.01, imu=CONSUMER, gnss=rx, seed=11)
    c, s = math.cos(MISALIGN), math.sin(MISALIGN)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])    # b' axes in b
    imu = Rec(t_s=d.imu.t_s, gyro=np.ascontiguousarray(d.imu.gyro @ Rz),   # rows: Rz^T x
              accel=np.ascontiguousarray(d.imu.accel @ Rz), kind="increments")
    q_imu = _qmul(d.truth.q_bn, [math.cos(MISALIGN / 2), 0.0, 0.0, math.sin(MISALIGN / 2)])
    cfg = FilterConfig(imu=CONSUMER, gnss_lever_arm_m=Rz.T @ TRAVEL_LEVER)
    return d, imu, q_imu, cfg


def _travel_run(travel, version, aligned, mid=None):
    """The FMU over the travel record: aligned = True: align_time 10 s, align_heading 1,
    started at the first GNSS position with an identity attitude; False: align_time 0,
    started from the true state. Returns the solution, the aligning output per record row,
    and, with mid, (outputs continued from the FMU state taken after FMU step mid, outputs of
    the uninterrupted run)."""
    d, imu, q_imu, cfg = travel
    g = d.gnss
    if aligned:
        nav = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), float(g.lat_rad[0]),
                          float(g.lon_rad[0]), float(g.h_m[0]), float(d.initial.t_s))
        params = {"align_time": 10.0, "align_heading": 1}
    else:
        nav = gf.NavState(q_imu[0], d.truth.v_n_m_s[0], d.truth.lat_rad[0], d.truth.lon_rad[0],
                          d.truth.h_m[0], float(d.initial.t_s))
        params = {}
    init = InitialState(nav, position_std_m=1.0, velocity_std_m_s=0.1,
                        attitude_std_rad=(0.01, 0.01, 0.05))
    drv = InsGnssDriver(imu, g, None, None, config=cfg, initial=init, fmi_version=version,
                         parameters=params)
    try:
        drv.initialize()
        if mid is None:
            drv.run(0, drv.n_steps)
            restored = None
        else:
            drv.run(0, mid)
            s = drv.slave.slave
            state = s.getFMUState() if version == 3 else s.getFMUstate()
            blob = s.serializeFMUState(state) if version == 3 else s.serializeFMUstate(state)
            drv.run(mid, drv.n_steps)
            first = drv.out_f.copy(), drv.out_i.copy()
            drv.out_f[mid:] = np.nan
            drv.out_i[mid:] = -7
            state2 = (s.deserializeFMUState if version == 3 else s.deSerializeFMUstate)(blob)
            (s.setFMUState if version == 3 else s.setFMUstate)(state2)
            drv.forget_inputs()
            drv.run(mid, drv.n_steps)
            restored = (drv.out_f.copy(), drv.out_i.copy()), first
            for st in (state, state2):
                (s.freeFMUState if version == 3 else s.freeFMUstate)(st)
        aligning = drv.out_i[drv.shift:, drv.cols_i["aligning"]][:, 0].copy()
        return drv.solution(), aligning, restored
    finally:
        drv.close()


def _heading_error(q, q_true):
    from gfins_fmi.nav.strapdown import quat_to_euler
    dpsi = quat_to_euler(q)[:, 0] - quat_to_euler(q_true)[:, 0]
    return (dpsi + np.pi) % (2 * np.pi) - np.pi


def _horizontal_error(sol, tr):
    R = 6.378e6     # metres per radian: a 0.3 % scale error is immaterial here
    rows = slice(1, None)           # record row k = truth sample k + 1
    dn = (sol.lat_rad - tr.lat_rad[rows]) * R
    de = (sol.lon_rad - tr.lon_rad[rows]) * R * np.cos(tr.lat_rad[rows])
    return np.hypot(de, dn)


@pytest.mark.parametrize("version", [2, 3])
def test_alignment_from_gnss_travel(travel, version):
    """align_heading = 1: levelled at rest, mechanized with heading 0 while driving off,
    aligned at the first GNSS epoch faster than 1 m/s; the heading error right after is the
    IMU's misalignment plus the direction noise of the GNSS velocity, and the position
    error over the drive that of the filter started from the true state."""
    d, imu, q_imu, cfg = travel
    g = d.gnss
    sol, aligning, _ = _travel_run(travel, version, aligned=True)
    ref, ref_aligning, _ = _travel_run(travel, version, aligned=False)
    assert not ref_aligning.any()
    # (b) aligning is 1 up to the first GNSS epoch after the phase at rest (10 s) faster
    # than align_min_speed (1 m/s), 0 from the record row of the sample it came with on
    sp = np.hypot(g.vel_enu_m_s[:, 0], g.vel_enu_m_s[:, 1])
    j = int(np.flatnonzero((g.t_s > 10.0) & (sp > 1.0))[0])
    k = int(np.searchsorted(imu.t_s, g.t_s[j] - 1e-9))
    assert np.all(aligning[:k] == 1) and np.all(aligning[k:] == 0), (k, np.flatnonzero(aligning == 0)[:1])
    assert 16.0 < g.t_s[j] < 20.0        # 3 s after driving off the smooth start passes 1 m/s
    # (a) the heading right after the alignment: the forward axis along the GNSS velocity,
    # the IMU yawed MISALIGN left of it (estimated - true = +MISALIGN), and the GNSS
    # velocity's direction noise: 1-sigma 0.03 m/s / speed (1.51 m/s here: 1.1 deg);
    # measured error 4.0 deg (MISALIGN 3 deg + 1.0 deg of noise); bound MISALIGN + 3 sigma
    sigma_dir = 0.03 / sp[j]
    e_h = _heading_error(sol.q_bn, q_imu[1:])
    assert abs(e_h[k] - MISALIGN) < 3 * sigma_dir, np.degrees([e_h[k], sigma_dir])
    # the filter was told so: heading 1-sigma = sqrt(align_travel_std^2 + sigma_dir^2)
    assert abs(sol.std[k, 8] - math.hypot(math.radians(10.0), sigma_dir)) < 1e-12
    # ... and learns the misalignment from the turns and speed changes: measured 0.2 deg at
    # the end (the reference filter: 0.1 deg); bound 1 deg
    assert abs(e_h[-1]) < math.radians(1.0), np.degrees(e_h[-1])
    # position over the drive after the alignment: measured (FMI 2 and 3 alike) max 0.62 m,
    # RMS 0.25 m, against max 0.39 m, RMS 0.21 m of the filter started from the true state
    # (GNSS white position noise 0.5 m); bounds: RMS within 1.5 x the reference's, max 1.5 m
    e_p, e_r = _horizontal_error(sol, d.truth)[k:], _horizontal_error(ref, d.truth)[k:]
    rms, rms_ref = np.sqrt(np.mean(e_p ** 2)), np.sqrt(np.mean(e_r ** 2))
    assert rms < 1.5 * rms_ref and e_p.max() < 1.5, (rms, rms_ref, e_p.max(), e_r.max())
    # while aligning the outputs are the mechanization's: at rest the start position
    assert sol.lat_rad[0] == g.lat_rad[0]
    # the innovation log rebuilt from the monitoring outputs has no entry for the counts'
    # restart at the end of the alignment (status -1, "none yet"; it had one per kind)
    assert len(sol.innovations) and not np.any(sol.innovations["status"] == -1)


@pytest.mark.parametrize("filt, kind", [("ukf", "increments"), ("ekf", "rates")])
def test_alignment_from_gnss_travel_ukf_and_rates(travel, filt, kind):
    """The same alignment with the UKF, and with rate samples (the first sample after the
    phase starts the filter's record): aligned at the same GNSS epoch, heading and
    position within the bounds of test_alignment_from_gnss_travel. Measured: heading error
    4.05 deg right after the alignment in both, 0.24 deg (UKF) and 0.22 deg (rates) at the
    end; horizontal error after the alignment max 0.62 m, RMS 0.25 m in both."""
    import dataclasses
    d, imu, q_imu, cfg = travel
    g = d.gnss
    if kind == "rates":
        dt = np.diff(np.r_[d.initial.t_s, imu.t_s])[:, None]
        imu = Rec(t_s=imu.t_s, gyro=imu.gyro / dt, accel=imu.accel / dt, kind="rates")
    cfg = dataclasses.replace(cfg, filter=filt, input=kind)
    t0 = float(imu.t_s[0]) if kind == "rates" else float(d.initial.t_s)   # rates: at a sample
    nav = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), float(g.lat_rad[0]),
                      float(g.lon_rad[0]), float(g.h_m[0]), t0)
    init = InitialState(nav, position_std_m=1.0, velocity_std_m_s=0.1, attitude_std_rad=(0.01, 0.01, 0.05))
    drv = InsGnssDriver(imu, g, None, None, config=cfg, initial=init, fmi_version=2,
                         parameters={"align_time": 10.0, "align_heading": 1})
    try:
        drv.initialize()
        drv.run(0, drv.n_steps)
        aligning = drv.out_i[drv.shift:, drv.cols_i["aligning"]][:, 0].copy()
        sol = drv.solution()
    finally:
        drv.close()
    sp = np.hypot(g.vel_enu_m_s[:, 0], g.vel_enu_m_s[:, 1])
    j = int(np.flatnonzero((g.t_s > 10.0) & (sp > 1.0))[0])
    k = int(np.searchsorted(imu.t_s, g.t_s[j] - 1e-9))
    assert aligning[k - 1] == 1 and np.all(aligning[k + 1:] == 0)
    e_h = _heading_error(sol.q_bn, q_imu[1:])
    assert abs(e_h[-1]) < math.radians(1.0), np.degrees(e_h[-1])
    e_p = _horizontal_error(sol, d.truth)[k + 1:]
    assert e_p.max() < 1.5, e_p.max()


@pytest.mark.parametrize("version", [2, 3])
def test_alignment_from_gnss_travel_state_restore(travel, version):
    """(c) An FMU state taken while driving off, before the heading is known (FMU step 1500:
    15 s), serialized, restored into the same instance and continued reproduces the run
    bit for bit, the alignment at the GNSS epoch included."""
    _, aligning, (again, first) = _travel_run(travel, version, aligned=True, mid=1500)
    assert aligning[1499] == 1 and aligning[-1] == 0
    assert np.array_equal(first[0], again[0], equal_nan=True) and np.array_equal(first[1], again[1])


def test_alignment_from_gnss_travel_never_fast(travel):
    """No GNSS epoch faster than align_min_speed (here 50 m/s): aligning stays 1 to the end,
    the outputs are the mechanization's (the run does not fail); bad parameters are refused."""
    d, imu, q_imu, cfg = travel
    g = d.gnss
    nav = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), float(g.lat_rad[0]),
                      float(g.lon_rad[0]), float(g.h_m[0]), float(d.initial.t_s))
    init = InitialState(nav)
    drv = InsGnssDriver(imu, g, None, None, config=cfg, initial=init, fmi_version=3,
                         parameters={"align_time": 10.0, "align_heading": 1, "align_min_speed": 50.0})
    try:
        drv.initialize()
        drv.run(0, drv.n_steps)
        aligning = drv.out_i[drv.shift:, drv.cols_i["aligning"]][:, 0]
        last = drv.out_i[-1]
        sol = drv.solution()
    finally:
        drv.close()
    assert np.all(aligning == 1) and np.all(np.isfinite(sol.lat_rad))
    # every GNSS epoch after the phase at rest (whose end restarts the monitoring outputs)
    # reported unused (status 3, as while aligning at rest), none applied
    status, count = last[drv.cols_i["update_status"]], last[drv.cols_i["update_count"]]
    assert list(status[:2]) == [3, 3] and list(count[:2]) == [np.sum(g.t_s > 10.0)] * 2
    for name, value, match in [("align_heading", 2, "parameter align_heading = 2 must be 0"),
                               ("align_min_speed", 0.0, "align_min_speed = 0 m/s"),
                               ("align_travel_std", float("nan"), "align_travel_std = nan rad")]:
        with pytest.raises(FmuRunError, match=match):
            run_ins_gnss_fmu(imu, g, config=cfg, initial=init, fmi_version=3,
                             parameters={"align_time": 10.0, "align_heading": 1, name: value})


def test_alignment_from_gnss_travel_nonfinite_sample(travel):
    """A NaN IMU sample in the step that brings the fast GNSS epoch is an FMU error naming
    the input; the outputs before it are the aligning mechanization's (aligning 1)."""
    d, imu, q_imu, cfg = travel
    g = d.gnss
    sp = np.hypot(g.vel_enu_m_s[:, 0], g.vel_enu_m_s[:, 1])
    j = int(np.flatnonzero((g.t_s > 10.0) & (sp > 1.0))[0])
    k = int(np.searchsorted(imu.t_s, g.t_s[j] - 1e-9))
    gyro = imu.gyro.copy()
    gyro[k, 1] = np.nan
    bad = Rec(t_s=imu.t_s, gyro=gyro, accel=imu.accel, kind="increments")
    nav = gf.NavState(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), float(g.lat_rad[0]),
                      float(g.lon_rad[0]), float(g.h_m[0]), float(d.initial.t_s))
    with pytest.raises(FmuRunError, match="is not finite") as exc:
        run_ins_gnss_fmu(bad, g, config=cfg, initial=InitialState(nav), fmi_version=3,
                         parameters={"align_time": 10.0, "align_heading": 1})
    part = exc.value.partial
    assert len(part.t_s) == k and np.all(np.isfinite(part.lat_rad))


def test_old_parameter_names_still_work_with_a_warning(rec):
    """The FMU's parameters took the settings table's names; the old ones are mapped for
    one release (with a DeprecationWarning): every old name maps to a parameter the FMU
    has, and a run with old names equals the run with the new ones."""
    from gfins_fmi.fmi.ins_gnss import OLD_PARAMETER_NAMES
    assert set(OLD_PARAMETER_NAMES.values()) <= {st.short for st in fmu_settings()}
    cfg, imu, gnss, _, _ = _case(rec, "ekf")
    short = Rec(t_s=imu.t_s[:200], gyro=imu.gyro[:200], accel=imu.accel[:200], kind="increments")
    new = run_ins_gnss_fmu(short, gnss, config=cfg, initial=_initial(rec[0]),
                           parameters={"gate_probability": 0.99, "propagation_interval_s": 0.05})
    with pytest.warns(DeprecationWarning) as caught:
        old = run_ins_gnss_fmu(short, gnss, config=cfg, initial=_initial(rec[0]),
                               parameters={"gate_prob": 0.99, "propagation_interval": 0.05})
    said = " ".join(str(w.message) for w in caught)
    assert "'gate_prob' is now 'gate_probability'" in said
    assert "'propagation_interval' is now 'propagation_interval_s'" in said
    assert np.array_equal(old.lat_rad, new.lat_rad) and np.array_equal(old.std, new.std)
