"""The filter's settings table (gfins_fmi/estimation/settings.py) against the C core, the
Python configuration and the state layout: every setting said once, every layer derived
from it. Truth: the C core's own enumeration of its checked fields and defaults (the table
must agree with it row by row), bad values made from each row's bounds, and numpy for P0.
"""
from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from gfins_fmi._lib import ffi, lib
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.error_model import ins_state_names
from gfins_fmi.estimation.settings import SETTINGS, by_member, fmu_settings, python_settings
from gfins_fmi.nav.earth import radii
from gfins_fmi.nav.strapdown import NavState
from support.drives import Rec, drive, gnss_record, quiet_config


def c_fields() -> list:
    """The members gf_ins_config_check can name, by code 1, 2, ... until NULL."""
    out, code = [], 1
    while (name := lib.gf_ins_config_field(code)) != ffi.NULL:
        out.append(ffi.string(name).decode())
        code += 1
    return out


def test_the_table_is_the_c_core_s_list_of_fields():
    """Each member the C check names has one row, and each row is a member C checks: a
    setting added on one side only fails here."""
    names = c_fields()
    assert len(names) == len(set(names))
    assert sorted(names) == sorted(st.member for st in SETTINGS)
    assert lib.gf_ins_config_field(0) == ffi.NULL and lib.gf_ins_config_field(-1) == ffi.NULL


def _member(cfg, st):
    owner, _, member = st.member.rpartition(".")
    return (getattr(cfg, owner) if owner else cfg), member


def test_the_table_s_defaults_are_the_c_defaults():
    cfg = ffi.new("gf_ins_config *")
    lib.gf_ins_config_default(cfg)
    for st in SETTINGS:
        target, member = _member(cfg, st)
        got = getattr(target, member)
        got = list(got) if st.kind == "vector" else got
        assert got == st.c_value(st.default), st.name


def bad_c_value(st):
    """A value outside a row's bounds, in C form."""
    if st.kind == "vector":
        if st.bounds == "mount":           # a pitch of 2 rad (heading and roll are free)
            return [0.0, 2.0, 0.0]
        return [0.0] * (st.size - 1) + [2.0 if st.bounds == "half_pi" else math.nan]
    return {"flag": 2, "enum": 7, "count": -1, "subsamples": 9, "nonneg": -1.0, "positive": 0.0,
            "finite": math.nan, "probability": 1.5}[st.bounds]


@pytest.mark.parametrize("st", SETTINGS, ids=[s.name for s in SETTINGS])
def test_c_names_the_field_it_refuses(st):
    """Set one member outside its bounds (its flag on where it is checked only then): the C
    check names that member, so every layer's message can name the setting."""
    cfg = ffi.new("gf_ins_config *")
    lib.gf_ins_config_default(cfg)
    if st.when:
        setattr(cfg, st.when, 1)
    target, member = _member(cfg, st)
    setattr(target, member, bad_c_value(st))
    bad = ffi.new("int32_t *")
    assert lib.gf_ins_config_check(cfg, bad) == lib.GF_ERR_BAD_PARAMETER
    assert ffi.string(lib.gf_ins_config_field(bad[0])).decode() == st.member


def bad_python_value(st):
    return {"flag": "yes", "enum": "kalman", "int": -1 if st.bounds == "count" else 9,
            "float": 1.5 if st.bounds == "probability" else
            (math.nan if st.bounds == "finite" else (0.0 if st.bounds == "positive" else -1.0)),
            "vector": (0.0, 2.0) if st.bounds == "half_pi" else
            ((3.0, 2.0, -3.0) if st.bounds == "mount" else (0.0, math.nan, 0.0))}[st.kind]


@pytest.mark.parametrize("st", python_settings(), ids=[s.python_name for s in python_settings()])
def test_filter_config_refuses_naming_the_field_value_and_bounds(st):
    kw = {st.python_name: bad_python_value(st)}
    if st.when:
        kw[st.when] = True
    with pytest.raises(ValueError, match=f"^FilterConfig.{st.python_name} = .*: must be ") as e:
        FilterConfig(**kw)
    assert "np.float64" not in str(e.value)


def test_filter_config_fields_and_defaults_come_from_the_table():
    cfg = FilterConfig()
    fields = [f for f in cfg.__dataclass_fields__ if f != "imu"]
    assert fields == [st.python_name for st in python_settings()]
    for st in python_settings():
        assert getattr(cfg, st.python_name) == st.default, st.name
        assert st.python_name in FilterConfig.__doc__


def test_noise_rows_reach_c_from_the_imu_model_and_the_fields():
    imu = FilterConfig().imu.__class__(gyro_arw_deg_sqrt_h=0.2, accel_vrw_ug_sqrt_hz=30.0)
    cfg = FilterConfig(imu=imu, odometer_scale_std=0.02, baro_bias_tau_s=100.0)
    c = cfg._c()
    assert c.noise.gyro_arw_rad_sqrt_s == 0.2 * math.pi / 180 / 60
    assert c.noise.odometer_scale_std == 0.02 and c.noise.baro_bias_tau_s == 100.0
    assert by_member("noise.gyro_arw_rad_sqrt_s").python_name == ""   # from imu, not a field


def test_fmu_parameters_are_the_fmu_rows():
    """gfins_ins_gnss takes every FMU row but the transfer-alignment ones (it has no master
    inputs); the transfer-alignment FMU takes them all."""
    transfer = {st.short for st in SETTINGS if st.transfer}
    assert transfer == {"flexure_std_rad", "flexure_tau_s", "master_mount", "master_lever",
                        "master_time_offset", "flexure", "master_mount_rad", "master_lever_arm_m",
                        "master_time_offset_s"}
    assert {st.short for st in fmu_settings()} == {st.short for st in SETTINGS} - {
        "speed_min_m_s", "subsamples"} - transfer
    assert {st.short for st in fmu_settings(transfer=True)} == {st.short for st in SETTINGS} - {
        "speed_min_m_s", "subsamples"}


FLAGS = ("scale_factors", "baro_bias", "odometer_scale", "odometer_mount")
TRANSFER_FLAGS = ("master_mount", "master_lever", "master_time_offset", "flexure")


@pytest.mark.parametrize("flags", list(itertools.product([False, True], repeat=4)) +
                         [(True, False, True, True, True, True, False, True),
                          (False, True, False, False, True, False, True, True),
                          (True,) * 8])
def test_layout_from_c_is_the_error_model_s_order(flags):
    """The C layout (gf_ins_state_layout) against the numpy error model's state names (the
    definition the C filter is tested against): blocks where the names put them (the
    transfer-alignment blocks in three combinations, 38 states with everything)."""
    flags = tuple(flags) + (False,) * (8 - len(flags))
    cfg = FilterConfig(**dict(zip(FLAGS + TRANSFER_FLAGS, flags)))
    lay = cfg.layout()
    names = ins_state_names(*flags[:4], **dict(zip(TRANSFER_FLAGS, flags[4:])))
    assert lay.n_states == cfg.n_states == len(names)
    where = {"idx_vel": "dv_E", "idx_pos": "dL", "idx_att": "phi_E", "idx_bg": "bg_x",
             "idx_ba": "ba_x", "idx_sg": "sg_x", "idx_sa": "sa_x", "idx_baro": "b_baro",
             "idx_odo": "k_odo", "idx_mount": "odo_pitch", "idx_tmount": "mount_heading",
             "idx_tlever": "lever_x", "idx_toffset": "time_offset", "idx_flex": "flex_heading"}
    for field, first in where.items():
        idx = getattr(lay, field)
        assert idx == (names.index(first) if first in names else -1), (field, names)


def test_initial_covariance_from_c_against_numpy():
    """P0 of gf_ins_initial_covariance = the diagonal written out with numpy's WGS-84 radii:
    east/north metres over the radii of curvature, the rest squared as given; the same
    formulas evaluated in the same order, so equal to the last bit apart from the radii
    (numpy vs C sin/pow: relative 1e-15)."""
    nav = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), 0.61, 1.9, 320.0, 0.0)
    cfg = FilterConfig(scale_factors=True, baro_bias=True, odometer_scale=True, odometer_mount=True)
    init = InitialState(nav, position_std_m=(2.0, 3.0, 5.0), velocity_std_m_s=(0.1, 0.2, 0.3),
                        attitude_std_rad=(0.01, 0.02, 0.03), gyro_bias_std_rad_s=1e-5,
                        accel_bias_std_m_s2=(1e-3, 2e-3, 3e-3), gyro_scale_std=1e-4,
                        odometer_mount_std_rad=(0.01, 0.02))
    P = init.covariance(cfg)
    RM, RN = radii(0.61)[:2]
    want = [0.1, 0.2, 0.3, 3.0 / (RM + 320.0), 2.0 / ((RN + 320.0) * math.cos(0.61)), 5.0,
            0.01, 0.02, 0.03, 1e-5, 1e-5, 1e-5, 1e-3, 2e-3, 3e-3, 1e-4, 1e-4, 1e-4,
            1e-3, 1e-3, 1e-3, cfg.baro_bias_std_m, cfg.odometer_scale_std, 0.01, 0.02]
    assert P.shape == (25, 25) and np.count_nonzero(P - np.diag(np.diag(P))) == 0
    np.testing.assert_allclose(np.sqrt(np.diag(P)), want, rtol=1e-15)
    with pytest.raises(ValueError, match=r"InitialState.position_std_m = \[2.0, 0.0, 5.0\]"):
        InitialState(nav, position_std_m=(2.0, 0.0, 5.0)).covariance(cfg)
    # the transfer-alignment blocks: mounting, lever arm and offset as given, the flexure's
    # stationary std sigma and b sigma (b = 2.146 / tau, gf_ins_gnss.h)
    cfg = FilterConfig(master_mount=True, master_lever=True, master_time_offset=True, flexure=True,
                       flexure_std_rad=2e-3, flexure_tau_s=0.5)
    init = InitialState(nav, gyro_bias_std_rad_s=1e-5, accel_bias_std_m_s2=1e-3,
                        master_mount_std_rad=(0.01, 0.02, 0.03), master_lever_std_m=0.2,
                        master_time_offset_std_s=0.03)
    b = 2.146 / 0.5
    want = [0.01, 0.02, 0.03, 0.2, 0.2, 0.2, 0.03] + [2e-3] * 3 + [b * 2e-3] * 3
    np.testing.assert_allclose(np.sqrt(np.diag(init.covariance(cfg)))[15:], want, rtol=1e-15)
    with pytest.raises(ValueError, match=r"InitialState.master_lever_std_m = \[0.1, -0.1, 0.1\]"):
        InitialState(nav, gyro_bias_std_rad_s=1e-5, accel_bias_std_m_s2=1e-3,
                     master_lever_std_m=(0.1, -0.1, 0.1)).covariance(cfg)
    polar = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), math.radians(89.5), 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="beyond \\+-89 deg"):
        InitialState(polar).covariance(FilterConfig())


@pytest.fixture(scope="module")
def exact_drive_records():
    """40 s of the exact drive of tests/support/drives.py, GNSS at 1 Hz with a lever arm."""
    tr, imu = drive(40.0)
    lever = np.array([0.3, 1.0, 1.4])
    gnss = gnss_record(tr, np.arange(1003, len(tr.t_s), 1000), lever)
    init = InitialState(NavState.from_trajectory(tr, 0), position_std_m=0.5,
                        velocity_std_m_s=0.05, attitude_std_rad=(1e-3, 1e-3, 5e-3))
    return quiet_config(gnss_lever_arm_m=lever), init, imu, gnss


def test_gnss_position_std_floor(exact_drive_records):
    """gnss_position_std_floor_m (the setting added through the table, docs/contributing.md):
    GNSS stds reported below the floor are used as the floor, so a run with stds of 1 mm and
    a floor of (3, 4, 6) cm is the run with stds of exactly (3, 4, 6) cm, bit for bit; above
    the floor the reported stds stand."""
    cfg, init, imu, gnss = exact_drive_records
    floor = (0.03, 0.04, 0.06)
    tiny = Rec(**{**gnss.__dict__, "pos_std_m": np.full_like(gnss.pos_std_m, 1e-3)})
    exact = Rec(**{**gnss.__dict__, "pos_std_m": np.tile(floor, (len(gnss.t_s), 1))})

    def run(c, g):
        return IntegratedNavigator(c, init).run(imu, g)

    a = run(dataclasses.replace(cfg, gnss_position_std_floor_m=floor), tiny)
    b = run(cfg, exact)
    c = run(cfg, tiny)
    assert np.array_equal(a.lat_rad, b.lat_rad) and np.array_equal(a.std, b.std)
    assert not np.array_equal(a.std, c.std)
    d = run(dataclasses.replace(cfg, gnss_position_std_floor_m=(1e-4, 1e-4, 1e-4)), exact)
    assert np.array_equal(d.std, b.std)


def test_bias_noise_from_the_datasheet_terms_in_closed_form():
    """noise_si's bias terms, written out: a rate random walk K enters as the stationary
    variance K^2 tau / 2 of a first-order Gauss-Markov process driven by white noise of
    PSD K^2 with the same correlation time, added in variance to the bias instability;
    tau = 3600 s when only K is given; neither term: no bias noise (tau 0). Units:
    deg/h/sqrt(h) -> rad/s/sqrt(s) is (pi/180/3600)/60, 1 ug = 9.80665e-6 m/s^2.
    Relative 1e-14: the same few operations in another order."""
    from gfins_fmi.nav.imu_errors import ImuNoise
    deg_h, ug = math.pi / 180 / 3600, 9.80665e-6
    kg, ka = 5.0 * deg_h / 60.0, 2.0 * ug

    def si(**kw):
        return FilterConfig(imu=ImuNoise(**kw)).noise_si()
    both = si(gyro_bias_instability_deg_h=3.0, gyro_correlation_time_s=200.0,
              gyro_rrw_deg_h_sqrt_h=5.0, accel_bias_instability_ug=40.0,
              accel_correlation_time_s=300.0, accel_rrw_ug_sqrt_s=2.0)
    only_rw = si(gyro_rrw_deg_h_sqrt_h=5.0, accel_rrw_ug_sqrt_s=2.0)
    only_bi = si(gyro_bias_instability_deg_h=3.0, gyro_correlation_time_s=200.0,
                 accel_bias_instability_ug=40.0, accel_correlation_time_s=300.0)
    neither = si(gyro_correlation_time_s=200.0, accel_correlation_time_s=300.0)
    for got, g_std, g_tau, a_std, a_tau in [
            (both, math.hypot(3.0 * deg_h, kg * math.sqrt(100.0)), 200.0,
             math.hypot(40.0 * ug, ka * math.sqrt(150.0)), 300.0),
            (only_rw, kg * math.sqrt(1800.0), 3600.0, ka * math.sqrt(1800.0), 3600.0),
            (only_bi, 3.0 * deg_h, 200.0, 40.0 * ug, 300.0),
            (neither, 0.0, 0.0, 0.0, 0.0)]:
        assert got["gyro_bias_tau_s"] == g_tau and got["accel_bias_tau_s"] == a_tau
        assert math.isclose(got["gyro_bias_std_rad_s"], g_std, rel_tol=1e-14, abs_tol=0.0)
        assert math.isclose(got["accel_bias_std_m_s2"], a_std, rel_tol=1e-14, abs_tol=0.0)


def test_filter_config_bounds_at_their_edges():
    """The Python checks at the edges of the table's bounds (the C core checks again; these
    must refuse with the Python message): a count may be 0, subsamples 1..4, one number
    for a 3-vector means all three axes but not for the 2-element boresight, whose angles
    lie inside (-pi/2, pi/2)."""
    assert FilterConfig(gate_reset_count=0).gate_reset_count == 0
    assert FilterConfig(subsamples=1).subsamples == 1
    for bad in (0, 5):
        with pytest.raises(ValueError, match=rf"^FilterConfig.subsamples = {bad}: must be "):
            FilterConfig(subsamples=bad)
    assert FilterConfig(gnss_lever_arm_m=0.5).gnss_lever_arm_m == (0.5, 0.5, 0.5)
    with pytest.raises(ValueError, match=r"^FilterConfig.odometer_mount_rad = 0.1 rad: must be .*\(2 values\)"):
        FilterConfig(odometer_mount_rad=0.1)
    assert FilterConfig(odometer_mount_rad=(1.5, -1.5)).odometer_mount_rad == (1.5, -1.5)
    with pytest.raises(ValueError, match=r"^FilterConfig.odometer_mount_rad = .*: must be "):
        FilterConfig(odometer_mount_rad=(1.6, 0.0))


def test_a_one_number_block_refuses_several():
    nav = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), 0.61, 1.9, 320.0, 0.0)
    cfg = FilterConfig(baro_bias=True, odometer_scale=True)
    for name in ("baro_bias_std_m", "odometer_scale_std"):
        for value in ([1.0], [1.0, 2.0]):
            with pytest.raises(ValueError, match=rf"InitialState.{name} must be one number"):
                InitialState(nav, **{name: value}).std_blocks(cfg)


def test_initial_std_limits_and_the_bias_hint():
    """InitialState's largest 1-sigma per block is allowed, above it refused naming the
    limit (issue 21); a bias std that defaults to an IMU model's bias instability of 0
    is refused with the hint to give it, an explicit 0 without it."""
    from gfins_fmi.nav.imu_errors import ImuNoise
    nav = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), 0.61, 1.9, 320.0, 0.0)
    cfg = FilterConfig()
    assert InitialState(nav, position_std_m=1e7).std_blocks(cfg)["position_std_m"] == [1e7] * 3
    assert InitialState(nav, attitude_std_rad=math.pi).std_blocks(cfg)["attitude_std_rad"] == [math.pi] * 3
    with pytest.raises(ValueError, match=r"InitialState.position_std_m = .* is above 1e\+07 m"):
        InitialState(nav, position_std_m=(1.0, 2e7, 1.0)).std_blocks(cfg)
    bare = FilterConfig(imu=ImuNoise(gyro_arw_deg_sqrt_h=0.1, accel_vrw_ug_sqrt_hz=50.0))
    with pytest.raises(ValueError, match=r"InitialState.gyro_bias_std_rad_s = .*: every element "
                                         r"must be finite and > 0 \(it defaults to the IMU model"):
        InitialState(nav, accel_bias_std_m_s2=1e-3).covariance(bare)
    with pytest.raises(ValueError, match=r"InitialState.gyro_bias_std_rad_s = \[0.0, 0.0, 0.0\]: every element "
                                         r"must be finite and > 0$"):
        InitialState(nav, gyro_bias_std_rad_s=0.0, accel_bias_std_m_s2=1e-3).covariance(bare)
