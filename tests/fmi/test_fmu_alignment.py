"""The integrated navigator FMU's alignment phase (align_time): levelling and gyrocompassing
at rest, or levelling and the heading from the GNSS direction of travel, then the filter.
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.evaluation import attitude_difference_rad
from gfins_fmi.fmi.ins_gnss import run_ins_gnss_fmu
from gfins_fmi.fmi.paths import FmuRunError
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import NavState
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.sim.vehicle import VehicleProfile, simulate_vehicle

DEG = np.pi / 180
NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
G_BIAS, A_BIAS = 0.01 * DEG / 3600, 50 * 9.80665e-6


def config(**kw):
    return FilterConfig(imu=NOISE, gate_probability=0.9999, gate_reset_count=0, **kw)


def test_fmu_alignment_phase():
    """The integrated-navigator FMU with align_time = 5 s on a record at rest (exact
    increments of gravity and the Earth rate, trajectory.Stationary): the attitude found
    at the end of the phase is the truth's to round-off (the means of exact increments;
    bound 1e-9 rad for the 1e-13 relative error of dtheta/dt), and from there the FMU is
    the batch filter started with that attitude (1e-12: the two starts normalise the same
    quaternion once more or once less). A turning vehicle in the phase is refused."""
    tr = tj.sample(tj.Stationary(heading=37 * DEG, pitch=1.5 * DEG, roll=-2 * DEG, lat=30 * DEG), 12.0, 0.01)
    imu = ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad, accel=tr.dv_m_s, kind="increments")
    nav0 = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), tr.lat_rad[0], tr.lon_rad[0], tr.h_m[0], tr.t_s[0])
    stds = dict(attitude_std_rad=(1e-3, 1e-3, 1e-2), velocity_std_m_s=0.01, gyro_bias_std_rad_s=G_BIAS,
                accel_bias_std_m_s2=A_BIAS)
    cfg = config()
    out = run_ins_gnss_fmu(imu, config=cfg, initial=InitialState(nav0, **stds), parameters={"align_time": 5.0})
    k = int(np.flatnonzero(np.isclose(out.t_s, 5.0))[0])
    assert np.all(out.q_bn[:k] == nav0.q_bn)                     # the initial state while aligning
    assert np.linalg.norm(attitude_difference_rad(out.q_bn[k], tr.q_bn[k + 1])) < 1e-9
    start = NavState(out.q_bn[k], np.zeros(3), tr.lat_rad[0], tr.lon_rad[0], tr.h_m[0], out.t_s[k])
    rest = ImuRecord(t_s=imu.t_s[k + 1:], gyro=imu.gyro[k + 1:], accel=imu.accel[k + 1:], kind="increments")
    ref = IntegratedNavigator(cfg, InitialState(start, **stds)).run(rest)
    assert np.allclose(out.q_bn[k + 1:], ref.q_bn, rtol=0, atol=1e-12)
    assert np.allclose(out.v_n_m_s[k + 1:], ref.v_n_m_s, rtol=0, atol=1e-12)
    turning = simulate_vehicle(VehicleProfile.circle(radius_m=50.0, speed_m_s=5.0), 8.0, 0.01)
    imu2 = ImuRecord(t_s=turning.t_s[1:], gyro=turning.dtheta_rad, accel=turning.dv_m_s, kind="increments")
    nav2 = NavState(np.array([1.0, 0, 0, 0]), np.zeros(3), turning.lat_rad[0], turning.lon_rad[0],
                    turning.h_m[0], turning.t_s[0])
    with pytest.raises(FmuRunError, match="motion during the alignment phase"):
        run_ins_gnss_fmu(imu2, config=cfg, initial=InitialState(nav2, **stds), parameters={"align_time": 5.0})

