"""Simulated drives for the integrated-navigation filter: the truth of the vehicle
(gf_vehicle), an IMU whose errors follow the filter's own noise model (ImuNoise: white
noise plus Gauss–Markov biases started in steady state), and the aiding sensors of
gf_aiding_sim (GNSS receiver, barometer, odometer). The filter's consistency checks, the
outage protocol, the documentation's figures and the benchmarks all use these.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional

import numpy as np

from gfins_fmi.io.records import BaroRecord, GnssRecord, ImuRecord, OdometerRecord
from gfins_fmi.nav.earth import euler_to_quat, quat_multiply, quat_to_dcm
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import NavState, quat_to_euler
from gfins_fmi.sim.vehicle import (Barometer, GnssReceiver, Odometer, Segment, VehicleProfile,
                                   VehicleRecord, simulate_vehicle)

__all__ = ["SimulatedDrive", "simulate_drive", "town_drive", "TACTICAL", "NAVIGATION",
           "CONSUMER", "GRADES"]

#: a tactical-grade IMU (fibre-optic gyros, servo accelerometers)
TACTICAL = ImuNoise(gyro_arw_deg_sqrt_h=0.05, gyro_bias_instability_deg_h=1.0,
                    gyro_correlation_time_s=3600.0, accel_vrw_ug_sqrt_hz=50.0,
                    accel_bias_instability_ug=100.0, accel_correlation_time_s=3600.0)
#: a navigation-grade IMU with the issue's figures: ARW 0.003 deg/sqrt(h), VRW
#: 0.03 m/s/sqrt(h) (= 0.03 / 60 m/s/sqrt(s) = ASD / sqrt(2) -> ASD 72 ug/sqrt(Hz)),
#: gyro bias 0.027 deg/h, accelerometer bias 15 mGal = 15.3 ug
NAVIGATION = ImuNoise(gyro_arw_deg_sqrt_h=0.003, gyro_bias_instability_deg_h=0.027,
                      gyro_correlation_time_s=3600.0,
                      accel_vrw_ug_sqrt_hz=0.03 / 60.0 * np.sqrt(2.0) / 9.80665e-6,
                      accel_bias_instability_ug=15e-5 / 9.80665e-6,
                      accel_correlation_time_s=3600.0)
#: a consumer MEMS IMU
CONSUMER = ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=10.0,
                    gyro_correlation_time_s=300.0, accel_vrw_ug_sqrt_hz=100.0,
                    accel_bias_instability_ug=500.0, accel_correlation_time_s=300.0)


#: the noise models by grade name (``--grade`` of the estimation commands)
GRADES = {"consumer": CONSUMER, "tactical": TACTICAL, "navigation": NAVIGATION}


@dataclass
class SimulatedDrive:
    """A simulated drive: records as a user would have them, and the truth.

    Attributes
    ----------
    truth : VehicleRecord (samples at the IMU times, the first at the start)
    imu : ImuRecord of increments over (t_(k-1), t_k], k = 1..n
    gnss, baro, odometer : records (None when not simulated)
    gyro_bias_rad_s, accel_bias_m_s2 : (n, 3) the IMU's true bias at each IMU sample
        (the part the filter models: Gauss–Markov and random walk)
    initial : NavState, the true state at the start
    """

    truth: VehicleRecord
    imu: ImuRecord
    gnss: Optional[GnssRecord]
    baro: Optional[BaroRecord]
    odometer: Optional[OdometerRecord]
    gyro_bias_rad_s: np.ndarray
    accel_bias_m_s2: np.ndarray
    initial: NavState
    imu_noise: ImuNoise


def town_drive(duration_s: float = 1800.0, speed_m_s: float = 12.0, **start) -> VehicleProfile:
    """A drive through town: starts, stops, right and left turns, speed changes, repeated
    until ``duration_s`` (at most the profile's 32 segments; the vehicle cruises after)."""
    block = [Segment(8.0, dspeed_m_s=speed_m_s), Segment(40.0), Segment(10.0, dheading_rad=np.pi / 2),
             Segment(30.0, dspeed_m_s=4.0), Segment(12.0, dheading_rad=-np.pi / 2),
             Segment(25.0), Segment(8.0, dspeed_m_s=-4.0 - speed_m_s), Segment(7.0),
             Segment(10.0, dspeed_m_s=speed_m_s, dheading_rad=np.pi), Segment(20.0)]
    segs, t = [], 0.0
    while t < duration_s and len(segs) + len(block) <= 32:
        segs += block
        t += sum(s.duration_s for s in block)
    return VehicleProfile(segments=segs, **start)


def mount_imu(truth: VehicleRecord, imu_mount_rad=(0.0, 0.0)) -> VehicleRecord:
    """The truth of an IMU mounted off the vehicle's axes (see :func:`simulate_drive`,
    ``imu_mount_rad``); the record itself for (0, 0)."""
    m = np.asarray(imu_mount_rad, dtype=float)
    if m.shape != (2,) or not np.all(np.abs(m) < np.pi / 2):
        raise ValueError(f"imu_mount_rad must be (pitch, heading) in rad, each inside "
                         f"(-pi/2, pi/2); got {imu_mount_rad!r}")
    if not np.any(m):
        return truth
    q_mb = euler_to_quat(m[1], m[0], 0.0)           # C_m^b
    C_mb = quat_to_dcm(q_mb)
    q_bm = q_mb * np.array([1.0, -1.0, -1.0, -1.0])   # conjugate: C_b^m
    q = quat_multiply(np.asarray(truth.q_bn, dtype=float), q_bm)
    rot = lambda a: None if a is None else np.asarray(a) @ C_mb.T
    return dataclasses.replace(truth, q_bn=q, gyro_rad_s=rot(truth.gyro_rad_s),
                               accel_m_s2=rot(truth.accel_m_s2), dtheta_rad=rot(truth.dtheta_rad),
                               dv_m_s=rot(truth.dv_m_s), gyro_dot_rad_s2=rot(truth.gyro_dot_rad_s2),
                               euler_rad=quat_to_euler(q), motion=None)


def simulate_drive(profile: VehicleProfile, duration_s: float, dt_s: float = 0.01, *,
                   imu: ImuNoise = TACTICAL, gnss: Optional[GnssReceiver] = None,
                   baro: Optional[Barometer] = None, odometer: Optional[Odometer] = None,
                   seed: int = 0, truth: Optional[VehicleRecord] = None,
                   imu_mount_rad=(0.0, 0.0)) -> SimulatedDrive:
    """Simulate a drive: the vehicle, its IMU increments with ``imu`` errors (seeded by
    ``seed``) and the aiding sensors (seeded by ``seed`` too, through gf_aiding_sim).

    ``truth`` reuses a vehicle run made with the same profile, duration and dt_s (Monte
    Carlo runs share it; only the sensor errors change).

    ``imu_mount_rad`` = (pitch, heading), rad, |.| < pi/2: the IMU is mounted off the
    vehicle's axes so that the vehicle's axes (along which it rolls, the odometer
    measures and the non-holonomic constraints hold) have this pitch (nose-up +) and
    heading (clockwise +) in the IMU's axes: C_m^b = Rz(-heading) Rx(pitch) (vehicle m ->
    IMU b, the Euler convention of :func:`gfins_fmi.nav.earth.euler_to_quat`), the
    boresight that ``FilterConfig.odometer_mount_rad`` describes. The truth record is
    then the IMU's: attitude C_b^n = C_m^n (C_m^b)^T, rates, specific forces and
    increments rotated by C_m^b (exact for a fixed rotation); positions, velocities and
    the aiding sensors (GNSS antenna and odometer lever arms in the vehicle's axes,
    ``C_m^b l`` in the IMU's) are the vehicle's.
    """
    if truth is None or gnss is not None or baro is not None or odometer is not None:
        truth = simulate_vehicle(profile, duration_s, dt_s, gnss=gnss, baro=baro,
                                 odometer=odometer, seed=seed)
    truth = mount_imu(truth, imu_mount_rad)
    n = len(truth.t_s) - 1
    rng = np.random.default_rng(seed)
    parts = imu.sample_parts(n, dt_s, rng)
    gyro_err = parts["gyro_white"] + parts["gyro_bias"] + parts["gyro_band"]
    accel_err = parts["accel_white"] + parts["accel_bias"] + parts["accel_band"]
    rec = ImuRecord(t_s=truth.t_s[1:], gyro=truth.dtheta_rad + gyro_err * dt_s,
                    accel=truth.dv_m_s + accel_err * dt_s, kind="increments",
                    source=f"simulate_drive(seed={seed})")
    g = getattr(truth, "gnss", None)
    gnss_rec = None if g is None or len(g.t_s) == 0 else GnssRecord(
        t_s=g.t_s, lat_rad=g.lat_rad, lon_rad=g.lon_rad, h_m=g.h_m, pos_std_m=g.pos_std_m,
        vel_enu_m_s=g.vel_enu_m_s, vel_std_m_s=g.vel_std_m_s, quality=g.quality)
    b = getattr(truth, "baro", None)
    baro_rec = None if b is None or len(b.t_s) == 0 else BaroRecord(t_s=b.t_s, h_m=b.h_m, std_m=b.std_m)
    o = getattr(truth, "odometer", None)
    odo_rec = None if o is None or len(o.t_s) == 0 else OdometerRecord(
        t_s=o.t_s, speed_m_s=o.speed_m_s, std_m_s=o.std_m_s)
    return SimulatedDrive(truth, rec, gnss_rec, baro_rec, odo_rec, parts["gyro_bias"],
                          parts["accel_bias"], NavState.from_trajectory(truth, 0), imu)
