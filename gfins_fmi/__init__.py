"""gfins_fmi — gyro-free and strapdown inertial navigation: a C core used from Python
through cffi, packaged as FMI 2.0 / 3.0 co-simulation FMUs, with error analysis.

Quantities carry their SI unit in their name (``_m``, ``_s``, ``_m_s2``, ``_rad_s``).

The package by domain, imports pointing one way (``cli``, ``experiments`` -> ``fmi``,
``analysis`` -> ``estimation``, ``calibration`` -> ``nav``, ``gyrofree``, ``sim`` ->
``_lib``, ``io``): ``nav`` (Earth model, strapdown, IMU errors), ``gyrofree``
(accelerometer arrays), ``sim`` (trajectories, vehicle, rotating IMU, drives),
``estimation`` (integrated navigation), ``calibration``, ``analysis`` (error models,
Monte Carlo), ``fmi`` (FMUs and co-simulation), ``io`` (records and tables), ``cli``
(the ``gfins`` command), ``experiments`` (demo, reproductions). The names below are the
most used ones, re-exported from their homes.
"""
from gfins_fmi._lib import GfinsError, NonFiniteInputError
from gfins_fmi._version import __version__
from gfins_fmi.fmi.models import run_accel9_fmu
from gfins_fmi.fmi.paths import FmuRunError, fmu_path
from gfins_fmi.gyrofree.array import (FLAG_NEG_OMEGA_SQ, FLAG_SIGN_UNKNOWN, MAX_SENSORS,
                                      Accel9Solution, Accel9Solver, ArrayGeometry,
                                      accel9_geometry, forward_model, solve_accel9)
from gfins_fmi.gyrofree.array_errors import ArraySensorErrors
from gfins_fmi.gyrofree.geometry import layout
from gfins_fmi.gyrofree.navigator import GyroFreeNavigator, hermite_increments
from gfins_fmi.gyrofree.rate_solver import RateSolution, RateSolver
from gfins_fmi.gyrofree.report import GeometryReport, geometry_report
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.nav.plausibility import PlausibilityWarning
from gfins_fmi.nav.strapdown import (NavSolution, NavState, SampleError, SinsConfig, Strapdown,
                                     euler_to_quat, quat_to_euler)

__all__ = [
    "GfinsError", "NonFiniteInputError", "FmuRunError",
    "ArrayGeometry", "accel9_geometry", "forward_model",
    "Accel9Solution", "Accel9Solver", "solve_accel9",
    "FLAG_NEG_OMEGA_SQ", "FLAG_SIGN_UNKNOWN", "MAX_SENSORS",
    "fmu_path", "run_accel9_fmu",
    "layout", "geometry_report", "GeometryReport", "RateSolver", "RateSolution",
    "GyroFreeNavigator", "hermite_increments", "ArraySensorErrors", "ImuErrors", "ImuNoise",
    "SinsConfig", "NavState", "NavSolution", "Strapdown", "SampleError",
    "euler_to_quat", "quat_to_euler", "PlausibilityWarning", "__version__",
]
