"""The vehicle truth source (C gf_vehicle via gfins_fmi.sim.vehicle) against the Python
trajectory generator, an independent implementation (closed forms, complex-step
derivatives, its own WGS-84): seed 001's vehicle run and seed 000's circle."""
import numpy as np
import pytest

from gfins_fmi.sim.trajectory import Circle, VehicleRun, sample
from gfins_fmi.nav.earth import attitude_error_rad
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle


def _compare(rec, traj, gyro_dot):
    # rates and positions: both are closed forms of the same path, evaluated at the same
    # times (t_k = k dt in both): round-off, 1e-13 relative of each quantity's scale
    for name in ("lat_rad", "lon_rad", "v_n_m_s", "gyro_rad_s", "accel_m_s2"):
        a, b = getattr(rec, name), getattr(traj, name)
        scale = max(np.max(np.abs(b)), 1.0 if name == "v_n_m_s" else 1e-3)
        assert np.max(np.abs(a - b)) <= 1e-13 * scale, name
    assert np.max(attitude_error_rad(rec.q_bn, traj.q_bn)) <= 1e-13
    assert np.max(np.abs(rec.gyro_dot_rad_s2 - gyro_dot)) <= 1e-13
    # increments: two Gauss-Legendre quadratures of the same integrand, the Python one
    # over [t_k, t_k + dt], the C one over [t_k, t_(k+1)]: these differ by an ulp of t
    # (1.1e-13 s at 550 s), 1e-11 of a 0.01 s increment; measured 1e-11, bound 1e-10
    for name in ("dtheta_rad", "dv_m_s"):
        a, b = getattr(rec, name), getattr(traj, name)
        assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(b)), name


def test_seed001_vehicle_run_equals_trajectory_generator():
    motion = VehicleRun(align_s=30.0)
    rec = simulate_vehicle(VehicleProfile.seed001(align_s=30.0), 560.0, 0.02)
    traj = sample(motion, 560.0, 0.02)
    assert rec.t_s.shape == traj.t_s.shape and np.array_equal(rec.t_s, traj.t_s)
    _compare(rec, traj, motion.gyro_dot(traj.t_s))
    # two 180 deg turns: heading back to north, speed 15 m/s
    assert abs(np.sin(rec.euler_rad[-1, 0])) < 1e-12 and np.cos(rec.euler_rad[-1, 0]) > 0
    assert rec.speed_m_s[-1] == pytest.approx(15.0, abs=1e-12)


def test_circle_equals_trajectory_generator():
    motion = Circle(radius_m=50.0, speed_m_s=5.0, pitch_amplitude_rad=0.0, roll_rad=0.0)
    rec = simulate_vehicle(VehicleProfile.circle(50.0, 5.0), 80.0, 0.01)
    traj = sample(motion, 80.0, 0.01)
    _compare(rec, traj, motion.gyro_dot(traj.t_s))


def test_array_outputs_match_trajectory():
    from gfins_fmi.gyrofree.geometry import layout
    motion = VehicleRun(align_s=1.0, accel_s=3.0, turn_times_s=(5.0,), turn_s=4.0)
    prof = VehicleProfile.seed001(align_s=1.0, accel_s=3.0, turn_times_s=(5.0,), turn_s=4.0)
    rec = simulate_vehicle(prof, 12.0, 0.01)
    traj = sample(motion, 12.0, 0.01)
    g = layout("qin9", 0.1)
    assert np.max(np.abs(rec.array_outputs(g) - traj.array_outputs(g))) <= 1e-13 * 10


def test_bad_profiles_say_what_to_change():
    with pytest.raises(ValueError, match="segment 1"):
        simulate_vehicle(VehicleProfile(segments=[Segment(1.0, 2.0), Segment(1.0, -3.0)]), 3, 0.1)
    with pytest.raises(ValueError, match="lat0_rad"):
        simulate_vehicle(VehicleProfile(lat0_rad=1.56), 1, 0.1)
    with pytest.raises(ValueError, match="at most"):
        VehicleProfile(segments=[Segment(1.0)] * 40).to_c()
    with pytest.raises(ValueError, match="dt_s"):
        simulate_vehicle(VehicleProfile(), 1.0, 0.0)
    with pytest.raises(ValueError, match="turn_times_s"):
        VehicleProfile.seed001(turn_times_s=(10.0,))
