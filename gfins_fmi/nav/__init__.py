"""Strapdown navigation: the Earth model and rotation helpers in numpy (``earth``, the
truth of the tests), the mechanization on the C core (``strapdown``), the IMU error and
noise models (``imu_errors``, ``noise``) and signal conditioning of inertial records
(``signal_conditioning``: the Chebyshev/biquad low-pass, not a Kalman filter).

Import from the modules: this package's ``__init__`` imports nothing (``import gfins_fmi``
loads only what its own names need).
"""
