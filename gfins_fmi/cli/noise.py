"""The IMU noise model of the estimation commands' ``--grade`` (the models of
:data:`gfins_fmi.sim.scenarios.GRADES`) or ``--noise``."""
from __future__ import annotations

from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim.scenarios import GRADES

__all__ = ["imu_noise"]


def imu_noise(grade: str, noise=None) -> ImuNoise:
    """The IMU noise model of ``--grade``, or of ``--noise`` ARW,VRW,GB,AB,TAU
    (deg/sqrt(h), ug/sqrt(Hz), deg/h, ug, s) when given."""
    if noise:
        arw, vrw, gb, ab, tau = noise
        return ImuNoise(gyro_arw_deg_sqrt_h=arw, accel_vrw_ug_sqrt_hz=vrw, gyro_bias_instability_deg_h=gb,
                        accel_bias_instability_ug=ab, gyro_correlation_time_s=tau,
                        accel_correlation_time_s=tau)
    return GRADES[grade]
