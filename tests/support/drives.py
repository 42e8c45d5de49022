"""Simulated records for the integrated navigator's tests: exact truth of a vehicle drive
(gf_vehicle, checked against the independent trajectory generator), IMU increments
summed from it, GNSS epochs at an antenna, and a quiet filter configuration."""
from __future__ import annotations

import numpy as np

import gfins_fmi as gf
from gfins_fmi.estimation import FilterConfig
from gfins_fmi.nav import earth
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle
from support.truth import OMEGA, radii


class Rec:
    """A minimal record (the io records have the same fields)."""

    def __init__(self, **kw):
        self.__dict__.update(kw)


def drive(duration_s=120.0, fine=0.001, step=10, seed_profile=0):
    """Exact truth at `fine` and IMU increments summed over `step` fine intervals."""
    prof = VehicleProfile(lat0_rad=0.52, speed0_m_s=8.0, segments=[
        Segment(10), Segment(15, dspeed_m_s=4, dheading_rad=np.pi / 2), Segment(20),
        Segment(10, dheading_rad=-np.pi), Segment(25, dspeed_m_s=-3), Segment(12, dheading_rad=1.0)])
    tr = simulate_vehicle(prof, duration_s, fine)
    n = (len(tr.t_s) - 1) // step
    dth = tr.dtheta_rad[:n * step].reshape(n, step, 3).sum(1)
    dv = tr.dv_m_s[:n * step].reshape(n, step, 3).sum(1)
    imu = Rec(t_s=tr.t_s[step::step][:n].copy(), gyro=dth, accel=dv, kind="increments")
    return tr, imu


def antenna(tr, k, lever):
    """Antenna position (lat, lon, h) and velocity (ENU) of the truth rows k, numpy."""
    lat, h = tr.lat_rad[k], tr.h_m[k]
    C = np.array(earth.quat_to_dcm(tr.q_bn[k]))
    cl = C @ lever
    RM, RN = radii(lat)
    pos = np.c_[lat + cl[:, 1] / (RM + h), tr.lon_rad[k] + cl[:, 0] / ((RN + h) * np.cos(lat)), h + cl[:, 2]]
    w_ie = np.c_[np.zeros_like(lat), OMEGA * np.cos(lat), OMEGA * np.sin(lat)]
    w_eb = tr.gyro_rad_s[k] - np.einsum("kji,kj->ki", C, w_ie)
    vel = tr.v_n_m_s[k] + np.einsum("kij,kj->ki", C, np.cross(w_eb, lever))
    return pos, vel


def gnss_record(tr, k, lever=np.zeros(3), std=(0.01, 0.01, 0.02), vstd=0.005):
    pos, vel = antenna(tr, k, lever)
    m = len(k)
    return Rec(t_s=tr.t_s[k].copy(), lat_rad=pos[:, 0].copy(), lon_rad=pos[:, 1].copy(), h_m=pos[:, 2].copy(),
               pos_std_m=np.tile(std, (m, 1)), vel_enu_m_s=vel, vel_std_m_s=np.full((m, 3), vstd))


def quiet_config(**kw):
    noise = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.01, accel_vrw_ug_sqrt_hz=10, gyro_bias_instability_deg_h=0.1,
                        gyro_correlation_time_s=3600, accel_bias_instability_ug=20,
                        accel_correlation_time_s=3600)
    return FilterConfig(imu=noise, **kw)


def town_drive_with_outage(T: float = 420.0):
    """A seeded town drive of ``T`` s (the scenario generator's) with a tactical-grade IMU's
    receiver: 1 Hz GNSS valid 0.37 s into each second, a 60 s outage from 200 s; returns
    (profile, T, receiver, exact truth at 100 Hz)."""
    from gfins_fmi.sim.scenarios import town_drive
    from gfins_fmi.sim.vehicle import GnssReceiver
    prof = town_drive(T)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1),
                      outages_s=((200.0, 260.0),))
    return prof, T, rx, simulate_vehicle(prof, T, 0.01)


def drive_start(d, **kw):
    """The filter's start at a simulated drive's initial state, with 1-sigma 1 m (2 m up),
    0.1 m/s and 0.005/0.005/0.02 rad (tilt, heading)."""
    from gfins_fmi.estimation import InitialState
    return InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                        attitude_std_rad=(0.005, 0.005, 0.02), **kw)


def kfgins_drive(folder, seconds: float, seed: int, lever_arm_m=(-0.3, 0.2, 1.2), truth: bool = False):
    """A seeded town drive of ``seconds`` written in KF-GINS's formats into ``folder``:
    200 Hz navigation-grade IMU increments (imu.txt), 1 Hz RTK GNSS at the antenna
    ``lever_arm_m`` (right, front, up m; gnss.txt) and, with ``truth``, the truth as a
    KF-GINS .nav and a TruthRecord CSV; returns the simulated drive."""
    from gfins_fmi import io
    from gfins_fmi.io.kfgins import (KFGINS_GNSS_FORMAT, KFGINS_IMU_FORMAT, KFGINS_NAV_FORMAT,
                                     kfgins_gnss_table, kfgins_imu_table, kfgins_nav_table)
    from gfins_fmi.sim.scenarios import NAVIGATION, simulate_drive, town_drive
    from gfins_fmi.sim.vehicle import GnssReceiver
    rx = GnssReceiver(rate_hz=1.0, lever_arm_m=tuple(lever_arm_m), pos_std_m=(0.02, 0.02, 0.04),
                      vel_std_m_s=(0.01, 0.01, 0.02))
    d = simulate_drive(town_drive(seconds), seconds, 0.005, imu=NAVIGATION, gnss=rx, seed=seed)
    np.savetxt(folder / "imu.txt", kfgins_imu_table(d.imu), fmt=KFGINS_IMU_FORMAT)
    np.savetxt(folder / "gnss.txt", kfgins_gnss_table(d.gnss), fmt=KFGINS_GNSS_FORMAT)
    if truth:
        tr = d.truth
        np.savetxt(folder / "truth.nav", kfgins_nav_table(tr.t_s, tr.lat_rad, tr.lon_rad, tr.h_m, tr.v_n_m_s,
                                                          tr.euler_rad), fmt=KFGINS_NAV_FORMAT)
        io.TruthRecord(tr.t_s, tr.lat_rad, tr.lon_rad, tr.h_m, tr.v_n_m_s, tr.euler_rad).to_csv(folder / "truth.csv")
    return d

