"""The AUV-like run shared by the alignment tests (tests/estimation/test_alignment.py,
tests/cli/test_align_command.py): the vehicle simulator's exact truth (gf_vehicle,
independent of the filter) and the IMU, tachometer and depth records made from it with
seeded sensor errors, and the filter's start offset from the truth."""
from __future__ import annotations

import numpy as np

from gfins_fmi.estimation import InitialState
from gfins_fmi.io.records import BaroRecord, ImuRecord, OdometerRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import NavState, euler_to_quat, quat_to_euler
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle

__all__ = ["DEG", "DT", "NOISE", "G_BIAS", "A_BIAS", "auv_truth", "records"]

DEG = np.pi / 180
DT = 0.02
NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
G_BIAS, A_BIAS = 0.01 * DEG / 3600, 50 * 9.80665e-6


def auv_truth():
    """An AUV-like run: 4.5 m/s, 50 m deep, 90 deg turns and speed changes, 200 s at 50 Hz."""
    segs = [Segment(20.0), Segment(30.0, dheading_rad=np.pi / 2), Segment(20.0, dspeed_m_s=1.0),
            Segment(30.0, dheading_rad=-np.pi / 2), Segment(30.0, dspeed_m_s=-1.0)] * 2
    prof = VehicleProfile(lat0_rad=30 * DEG, lon0_rad=114 * DEG, h0_m=-50.0, heading0_rad=40 * DEG,
                          speed0_m_s=4.5, segments=segs)
    return simulate_vehicle(prof, 200.0, DT)


def records(truth, seed=7, t_end=200.0, tach_scale=1.0, heading_err=2 * DEG):
    rng = np.random.default_rng(seed)
    n = int(round(t_end / DT))
    bg, ba = rng.normal(0, G_BIAS, 3), rng.normal(0, A_BIAS, 3)
    wn, an = NOISE.sample(n, DT, rng)
    imu = ImuRecord(t_s=truth.t_s[1:n + 1], gyro=truth.dtheta_rad[:n] + (bg + wn) * DT,
                    accel=truth.dv_m_s[:n] + (ba + an) * DT, kind="increments")
    ks = np.arange(5, n + 1, 5)
    vh = np.hypot(truth.v_n_m_s[ks, 0], truth.v_n_m_s[ks, 1])
    tach = OdometerRecord(t_s=truth.t_s[ks], speed_m_s=tach_scale * vh + rng.normal(0, 0.05, len(ks)),
                          std_m_s=np.full(len(ks), 0.05))
    kd = np.arange(50, n + 1, 50)
    depth = BaroRecord(t_s=truth.t_s[kd], h_m=truth.h_m[kd] + rng.normal(0, 0.1, len(kd)),
                       std_m=np.full(len(kd), 0.1))
    e0 = quat_to_euler(truth.q_bn[0]) + np.array([heading_err, 0.2 * DEG, -0.2 * DEG])
    v0 = 4.5 * np.array([np.sin(e0[0]), np.cos(e0[0]), 0.0])
    nav = NavState(euler_to_quat(e0), v0, truth.lat_rad[0], truth.lon_rad[0], truth.h_m[0], truth.t_s[0])
    init = InitialState(nav, position_std_m=1.0, velocity_std_m_s=(0.4, 0.4, 0.05),
                        attitude_std_rad=(0.6 * DEG, 0.6 * DEG, 6 * DEG), gyro_bias_std_rad_s=G_BIAS,
                        accel_bias_std_m_s2=A_BIAS)
    return imu, tach, depth, init
