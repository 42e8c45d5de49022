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
import importlib

from gfins_fmi._version import __version__

#: the most used names, re-exported from their homes: imported when first used (PEP 562),
#: so that ``import gfins_fmi`` (and every command's start) does not load the FMU
#: runners, the gyro-free solvers and the strapdown for a command that needs none of them
_EXPORTS = {
    "GfinsError": "gfins_fmi._lib",
    "NonFiniteInputError": "gfins_fmi._lib",
    "run_accel9_fmu": "gfins_fmi.fmi.models",
    "FmuRunError": "gfins_fmi.fmi.paths",
    "fmu_path": "gfins_fmi.fmi.paths",
    "FLAG_NEG_OMEGA_SQ": "gfins_fmi.gyrofree.array",
    "FLAG_SIGN_UNKNOWN": "gfins_fmi.gyrofree.array",
    "MAX_SENSORS": "gfins_fmi.gyrofree.array",
    "Accel9Solution": "gfins_fmi.gyrofree.array",
    "Accel9Solver": "gfins_fmi.gyrofree.array",
    "ArrayGeometry": "gfins_fmi.gyrofree.array",
    "accel9_geometry": "gfins_fmi.gyrofree.array",
    "forward_model": "gfins_fmi.gyrofree.array",
    "solve_accel9": "gfins_fmi.gyrofree.array",
    "ArraySensorErrors": "gfins_fmi.gyrofree.array_errors",
    "layout": "gfins_fmi.gyrofree.geometry",
    "GyroFreeNavigator": "gfins_fmi.gyrofree.navigator",
    "hermite_increments": "gfins_fmi.gyrofree.navigator",
    "RateSolution": "gfins_fmi.gyrofree.rate_solver",
    "RateSolver": "gfins_fmi.gyrofree.rate_solver",
    "GeometryReport": "gfins_fmi.gyrofree.report",
    "geometry_report": "gfins_fmi.gyrofree.report",
    "ImuErrors": "gfins_fmi.nav.imu_errors",
    "ImuNoise": "gfins_fmi.nav.imu_errors",
    "PlausibilityWarning": "gfins_fmi.nav.plausibility",
    "NavSolution": "gfins_fmi.nav.strapdown",
    "NavState": "gfins_fmi.nav.strapdown",
    "SampleError": "gfins_fmi.nav.strapdown",
    "SinsConfig": "gfins_fmi.nav.strapdown",
    "Strapdown": "gfins_fmi.nav.strapdown",
    "euler_to_quat": "gfins_fmi.nav.strapdown",
    "quat_to_euler": "gfins_fmi.nav.strapdown",
}


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'gfins_fmi' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted(set(globals()) | set(_EXPORTS))

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
