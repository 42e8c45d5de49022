"""Gyro-free navigation with accelerometer arrays: the array and the 9-accelerometer
solver of seed 000 (``array``), what an array measures (``geometry``: layouts, solver
maps; ``stability``: the rate loop; ``report``: all of it in words), the rate solver
(``rate_solver``), the navigator (``navigator``) and the array's sensor errors
(``array_errors``). Model and strategies: ``csrc/gf_gfins.h``."""
from gfins_fmi.gyrofree.array import (FLAG_NEG_OMEGA_SQ, FLAG_SIGN_UNKNOWN, MAX_SENSORS,
                                      MIN_LEVER_ARM_M, Accel9Solution, Accel9Solver,
                                      ArrayGeometry, accel9_geometry, forward_model, solve_accel9)
from gfins_fmi.gyrofree.array_errors import ArraySensorErrors
from gfins_fmi.gyrofree.geometry import STRATEGIES, SolverMaps, layout, solver_maps
from gfins_fmi.gyrofree.navigator import GyroFreeNavigator, hermite_increments
from gfins_fmi.gyrofree.rate_solver import RateSolution, RateSolver, UnstableRateLoopWarning
from gfins_fmi.gyrofree.report import GeometryReport, geometry_report
from gfins_fmi.gyrofree.stability import LoopStability, rate_loop_stability

__all__ = ["ArrayGeometry", "accel9_geometry", "forward_model", "Accel9Solution", "Accel9Solver",
           "solve_accel9", "FLAG_NEG_OMEGA_SQ", "FLAG_SIGN_UNKNOWN", "MAX_SENSORS",
           "MIN_LEVER_ARM_M", "ArraySensorErrors", "STRATEGIES", "SolverMaps", "layout",
           "solver_maps", "GyroFreeNavigator", "hermite_increments", "RateSolution", "RateSolver",
           "UnstableRateLoopWarning", "GeometryReport", "geometry_report", "LoopStability",
           "rate_loop_stability"]
