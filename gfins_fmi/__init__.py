"""gfins_fmi — gyro-free and strapdown inertial navigation: a C core used from Python
through cffi, packaged as FMI 2.0 / 3.0 co-simulation FMUs, with error analysis.

Quantities carry their SI unit in their name (``_m``, ``_s``, ``_m_s2``, ``_rad_s``).
"""
from gfins_fmi._lib import GfinsError, NonFiniteInputError
from gfins_fmi.accel_array import (FLAG_NEG_OMEGA_SQ, FLAG_SIGN_UNKNOWN, MAX_SENSORS,
                                   Accel9Solution, Accel9Solver, ArrayGeometry,
                                   accel9_geometry, forward_model, solve_accel9)
from gfins_fmi.fmu import FmuRunError, fmu_path, run_accel9_fmu
from gfins_fmi.array_errors import ArraySensorErrors
from gfins_fmi.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.gyrofree import (GeometryReport, GyroFreeNavigator, RateSolution, RateSolver,
                                geometry_report, hermite_increments, layout)
from gfins_fmi.sins import (NavSolution, NavState, SampleError, SinsConfig, Strapdown,
                            euler_to_quat, quat_to_euler)

__version__ = "0.1.0"

__all__ = [
    "GfinsError", "NonFiniteInputError", "FmuRunError",
    "ArrayGeometry", "accel9_geometry", "forward_model",
    "Accel9Solution", "Accel9Solver", "solve_accel9",
    "FLAG_NEG_OMEGA_SQ", "FLAG_SIGN_UNKNOWN", "MAX_SENSORS",
    "fmu_path", "run_accel9_fmu",
    "layout", "geometry_report", "GeometryReport", "RateSolver", "RateSolution",
    "GyroFreeNavigator", "hermite_increments", "ArraySensorErrors", "ImuErrors", "ImuNoise",
    "SinsConfig", "NavState", "NavSolution", "Strapdown", "SampleError",
    "euler_to_quat", "quat_to_euler", "__version__",
]
