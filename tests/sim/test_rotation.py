"""The rotating IMU (gfins_fmi.sim.rotation over C gf_rotation): seed 001's path table, the
modulation property of the indexing schemes, the simulated outputs at rest and the
checks of bad schedules. Independent truth: the patent's published table, rotation
matrices written here, the closed-form specific force at rest. (The C test
tests/c/test_rotation.c checks the kinematics against difference quotients and closed
forms of turning increments.)"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.nav import earth, rotating
from gfins_fmi.sim import rotation as rot


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _dcm(q):
    a, b, c, d = q
    return np.array([[a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)],
                     [2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)],
                     [2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d]])


def test_every_row_of_the_seed001_table_follows_from_the_previous():
    rows = rot.check_seed001_table()
    assert len(rows) == 19
    bad = [r for r in rows if not r["agrees"]]
    assert not bad, f"rows that do not follow from the mechanism: {bad}"


def test_seed001_table_against_rotation_matrices_written_here():
    """C_m^n = R_x(alpha) R_z(beta) (base ENU), alpha, beta the sums of the turns."""
    names = {"E": [1, 0, 0], "W": [-1, 0, 0], "N": [0, 1, 0], "S": [0, -1, 0], "U": [0, 0, 1],
             "D": [0, 0, -1]}
    a = b = 0.0
    sched = rot.seed001_path(repeats=1, align_s=10.0, dwell_s=5.0)
    ends = sched.turn_end_times_s - 0.5
    poses = sched.poses(ends)
    for k, (axis, angle, dirs) in enumerate(rot.SEED001_TABLE):
        a += np.radians(angle) if axis == "middle" else 0.0
        b += np.radians(angle) if axis == "inner" else 0.0
        C = _rx(a) @ _rz(b)
        want = np.array([names[c] for c in dirs]).T
        np.testing.assert_allclose(C, want, atol=1e-12, err_msg=f"row {k} (matrices)")
        np.testing.assert_allclose(_dcm(poses["q_mb"][k]), want, atol=1e-12, err_msg=f"row {k} (C core)")
        # gimbal angles as the encoders would read them
        g = poses["gimbal_rad"][k]
        np.testing.assert_allclose(np.exp(1j * g), np.exp(1j * np.array([a, b])), atol=1e-12)


def test_seed001_path_duration():
    """18 dwells of 180 s, 12 turns of 90 deg and 6 of 180 deg at 5 deg/s (+1 s ramp each)
    after 600 s: 61.2 min per pass plus the ramps; the seed says "within 1 hour"."""
    s = rot.seed001_path(repeats=1)
    assert s.duration_s == pytest.approx(600 + 18 * 180 + 12 * 19 + 6 * 37, abs=1e-9)
    assert rot.seed001_path(repeats=2).duration_s == pytest.approx(600 + 2 * (18 * 180 + 12 * 19 + 6 * 37))
    assert s.is_mechanism


@pytest.mark.parametrize("positions", [8, 16])
def test_indexing_schemes_average_the_imu_axes_to_zero(positions):
    """Modulation: over the dwells of one cycle every IMU axis spends equal time along
    +d and -d for each direction d, so a constant bias averages to zero in n."""
    s = rot.indexing_scheme(positions, dwell_s=10.0)
    ends = s.turn_end_times_s - 1.0
    C = np.array([_dcm(q) for q in s.poses(ends)["q_mb"]])
    np.testing.assert_allclose(C.mean(axis=0), 0.0, atol=1e-12)
    # the cycle closes: the pose repeats
    t = np.array([3.3, 3.3 + 5 * s.duration_s])
    q = s.poses(t)["q_mb"]
    assert min(np.abs(q[0] - q[1]).max(), np.abs(q[0] + q[1]).max()) < 1e-9


@pytest.mark.parametrize("positions, want_urad", [(8, 4e6 * np.pi * 10e-6), (16, 0.0)])
def test_indexing_schemes_and_the_turns_scale_factor_error(positions, want_urad):
    """A z-gyro scale factor error dK (10 ppm) adds dK dtheta_z to every increment; the
    attitude error it leaves after one cycle is the sum of C_m^n dK dtheta_z (the
    increments' own rotation and the Earth rate's share: 10 ppm x 15 deg/h x 4 min =
    0.05 urad). In the 8-position sequence the inner axis points down for both of its
    -180 deg turns, so the four inner turns all turn the IMU by +180 deg about the vertical:
    4 pi dK of heading per cycle (126 urad), derived by hand; the 16-position sequence
    cancels it. Tolerance 0.5 urad: the Earth-rate share and the 1 s ramps' quadrature."""
    s = rot.indexing_scheme(positions, dwell_s=10.0)
    tr = rot.simulate_static(s, s.duration_s, 0.01, np.radians(40.0), 0.0)
    C = np.array([_dcm(q) for q in tr.q_mn])
    err = (C[:, :, 2] * (10e-6 * tr.dtheta_rad[:, 2])[:, None]).sum(axis=0)     # sum of C e_z dK dtheta_z
    np.testing.assert_allclose(err[2] * 1e6, want_urad, atol=0.5)
    np.testing.assert_allclose(err[:2] * 1e6, 0.0, atol=0.5)


def test_continuous_scheme_rates():
    s = rot.continuous_scheme(inner_rate_deg_s=6.0, middle_rate_deg_s=3.0, half_cycle_s=120.0)
    p = s.poses([60.0])
    # mid-turn: inner rate 6 deg/s about IMU z, middle 3 deg/s
    np.testing.assert_allclose(np.degrees(p["gimbal_rad"][0]) % 360,
                               [(3.0 * (60 - 0.5)) % 360, (6.0 * (60 - 0.5)) % 360], atol=1e-9)
    with pytest.raises(ValueError, match="whole turns"):
        rot.continuous_scheme(inner_rate_deg_s=5.0, half_cycle_s=100.0)


def test_static_simulation_at_rest_is_gravity_and_earth_rate():
    lat, h = np.radians(40.0), 50.0
    s = rot.RotationSchedule((rot.rest(2.0),))
    r = rot.simulate_static(s, 1.0, 0.01, lat, h, heading_rad=np.radians(30.0))
    W = 7.292115e-5
    # body x = cos(psi) E - sin(psi) N, y = sin(psi) E + cos(psi) N (heading clockwise)
    psi = np.radians(30.0)
    w_b = W * np.array([-np.sin(psi) * np.cos(lat), np.cos(psi) * np.cos(lat), np.sin(lat)])
    np.testing.assert_allclose(r.dtheta_rad, np.tile(w_b * 0.01, (100, 1)), rtol=0, atol=1e-19)
    assert np.allclose(r.dv_m_s[:, :2], 0.0, atol=1e-16)
    assert r.dv_m_s[0, 2] == pytest.approx(0.01 * 9.80167, rel=1e-4)   # g at 40 deg, 50 m


def test_vehicle_attitude_roundtrip():
    rng = np.random.default_rng(3)
    g = rng.uniform(-np.pi, np.pi, (20, 2))
    qb = rng.normal(size=(20, 4))
    qb /= np.linalg.norm(qb, axis=1)[:, None]
    # C_m^n = C_b^n R_x(alpha) R_z(beta), written here
    Cm = np.array([_dcm(q) @ _rx(a) @ _rz(b) for q, (a, b) in zip(qb, g)])
    from scipy.spatial.transform import Rotation
    q_mn = Rotation.from_matrix(Cm).as_quat()[:, [3, 0, 1, 2]]
    out = rotating.vehicle_attitude(q_mn, g)
    for k in range(20):
        np.testing.assert_allclose(_dcm(out[k]), _dcm(qb[k]), atol=1e-12)


def test_bad_schedules_are_refused_with_the_reason():
    with pytest.raises(ValueError, match="bring the IMU back"):
        rot.RotationSchedule((rot.middle(90.0, 1.0),), repeat=True)
    with pytest.raises(ValueError, match="ramp"):
        rot.RotationSchedule((rot.middle(2.0, 1.0, rate_deg_s=5.0, ramp_s=1.0),))
    with pytest.raises(ValueError, match=r"turns\[0\].rate_deg_s"):
        rot.RotationSchedule((rot.middle(90.0, 1.0, rate_deg_s=0.0),))
    with pytest.raises(ValueError, match="600 deg/s"):
        rot.RotationSchedule((rot.middle(180.0, 1.0, rate_deg_s=1000.0, ramp_s=0.0),))
    with pytest.raises(ValueError, match="x, y or z"):
        rot.about_imu("w", 90.0)
    with pytest.raises(ValueError, match="repeats"):
        rot.seed001_path(repeats=4)
    with pytest.raises(ValueError, match="accel_delay_s"):
        rot.simulate_static(rot.seed001_path(1), 10.0, 0.01, 0.5, 0.0, accel_delay_s=0.1)
    with pytest.raises(ValueError, match="lat_rad"):
        rot.simulate_static(rot.seed001_path(1), 10.0, 0.01, np.radians(89.5), 0.0)


@pytest.mark.parametrize("version", [2, 3])
def test_vehicle_fmu_carries_the_rotating_imu(version):
    """The vehicle FMU with rotation = 1 against the cffi simulation of the same schedule
    on the same vehicle: the master's communication points accumulate t + h, the direct
    run computes t0 + k h, so the phase boundaries fall a few ulp apart: 1e-12 relative
    to the increment (measured 1.5e-12 relative on dtheta at 30 deg/s, 7e-15 rad)."""
    from gfins_fmi.fmi.runner import run_fmu
    from gfins_fmi.sim.vehicle import VehicleProfile
    prof = VehicleProfile.seed001(align_s=10.0, turn_times_s=(25.0,), turn_s=10.0)
    sched = rot.indexing_scheme(16, dwell_s=2.0, rate_deg_s=30.0)
    n, dt = 3000, 0.01
    ref = rot.simulate_on_vehicle(sched, prof, n * dt, dt)
    r = run_fmu("vehicle", {"speed_cmd": np.zeros(n)}, ["dtheta", "dv", "gimbal", "q_mb", "q"], dt,
                parameters={**prof.as_parameters(), **sched.fmu_parameters()}, fmi_version=version)
    np.testing.assert_allclose(r["dtheta"], ref.dtheta_rad, rtol=0, atol=2e-14)
    np.testing.assert_allclose(r["dv"], ref.dv_m_s, rtol=0, atol=1e-12 * 0.1)   # dv ~ g dt
    np.testing.assert_allclose(r["gimbal"], ref.gimbal_rad, rtol=0, atol=1e-13)
    # C_m^n of the cffi record = vehicle q_bn (x) q_mb of the FMU
    qmn = np.array([earth.quat_multiply(a, b) for a, b in zip(r["q"], r["q_mb"])])
    assert np.allclose(np.abs(np.sum(qmn * ref.q_mn, axis=1)), 1.0, atol=1e-12)
    with pytest.raises(ValueError, match="zero position"):
        rot.RotationSchedule((rot.rest(1.0),), q_mb0=(0.0, 1.0, 0.0, 0.0)).fmu_parameters()


@pytest.mark.parametrize("version", [2, 3])
def test_sins_fmu_navigates_the_rotating_imu_with_compensation(version):
    """The SINS FMU with rotating = 1 and the calibrated error model as parameters (seed
    001 S6: dynamic error suppression in the FMU) equals nav.rotating.navigate through cffi:
    compensation, mechanization and the vehicle attitude from the gimbal angles. The
    FMU compensates increments as mean rates, as ImuErrors.compensate_increments does:
    same operations, so 1e-12 relative covers the compiler's freedom between the two
    builds (measured: 0)."""
    from gfins_fmi.fmi.models import run_sins_fmu
    from gfins_fmi.nav.imu_errors import ImuErrors
    from gfins_fmi.nav.strapdown import SinsConfig
    from gfins_fmi.sim.vehicle import VehicleProfile
    prof = VehicleProfile.seed001(align_s=5.0, turn_times_s=(22.0,), turn_s=8.0)
    sched = rot.indexing_scheme(8, dwell_s=2.0, rate_deg_s=30.0)
    rec = rot.simulate_on_vehicle(sched, prof, 40.0, 0.01)
    e = ImuErrors(gyro_bias_deg_h=[0.01, -0.01, 0.02], gyro_scale_ppm=[30, -20, 10],
                  accel_bias_ug=[500, -300, 200], accel_k2_ug_g2=[20, -20, 20], lever_arm_cm=[3, 3, -3])
    th, dv = e.apply_increments(rec.dtheta_rad, rec.dv_m_s, rec.dt_s)
    cfg = SinsConfig(vertical="hold")
    want = rotating.navigate(rec, th, dv, compensation=e, config=cfg)
    got = run_sins_fmu(th, dv, rec.dt_s, rec.initial, config=cfg, imu_errors=e,
                       gimbal_rad=rec.gimbal_rad, fmi_version=version)
    np.testing.assert_allclose(got.imu.q_bn, want.imu.q_bn, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.imu.v_n_m_s, want.imu.v_n_m_s, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.q_bn_vehicle, want.q_bn_vehicle, rtol=0, atol=1e-12)
    # and the vehicle attitude is the truth's (compensation with the true model)
    assert np.max(np.abs(np.abs(np.sum(got.q_bn_vehicle * rec.vehicle["q_bn"], axis=1)) - 1)) < 1e-9
