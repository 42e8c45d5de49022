"""Strapdown navigation: the Earth model and rotation helpers in numpy (``earth``, the
truth of the tests), the mechanization on the C core (``strapdown``), the IMU error and
noise models (``imu_errors``, ``noise``) and signal conditioning of inertial records
(``signal_conditioning``: the Chebyshev/biquad low-pass, not a Kalman filter)."""
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.nav.strapdown import (NavSolution, NavState, SampleError, SinsConfig, Strapdown,
                                     euler_to_quat, quat_to_euler)

__all__ = ["SinsConfig", "NavState", "NavSolution", "Strapdown", "SampleError", "euler_to_quat",
           "quat_to_euler", "ImuErrors", "ImuNoise"]
