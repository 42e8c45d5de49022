"""The IMU noise model of the estimation commands' ``--grade`` (the models of
:data:`gfins_fmi.sim.scenarios.GRADES`), ``--noise`` or ``--noise-file`` (a noise block,
:mod:`gfins_fmi.estimation.noise_file`, as ``gfins noise`` writes it)."""
from __future__ import annotations

from gfins_fmi.estimation.noise_file import read_noise_file
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim.scenarios import GRADES

__all__ = ["imu_noise"]


def imu_noise(grade: str, noise=None, noise_file=None) -> ImuNoise:
    """The IMU noise model of ``--noise-file`` when given, else of ``--noise``
    ARW,VRW,GB,AB,TAU (deg/sqrt(h), ug/sqrt(Hz), deg/h, ug, s), else of ``--grade``."""
    if noise_file:
        return read_noise_file(noise_file)
    if noise:
        arw, vrw, gb, ab, tau = noise
        return ImuNoise(gyro_arw_deg_sqrt_h=arw, accel_vrw_ug_sqrt_hz=vrw, gyro_bias_instability_deg_h=gb,
                        accel_bias_instability_ug=ab, gyro_correlation_time_s=tau,
                        accel_correlation_time_s=tau)
    return GRADES[grade]
