"""Estimation on the one Kalman engine of the C core: integrated navigation (INS/GNSS
with barometer, odometer, non-holonomic and zero-velocity aiding; EKF or UKF; RTS
smoother) and the tools to evaluate it. See docs/estimation.md."""
from gfins_fmi.estimation.ins_gnss import (MEAS_TYPES, SENSOR_NAMES, UPDATE_STATUS, FilterConfig,
                                           FilterError, InitialState, IntegratedNavigator,
                                           IntegratedSolution, SmoothedSolution, integrate,
                                           state_names)

__all__ = ["FilterConfig", "InitialState", "IntegratedNavigator", "IntegratedSolution",
           "SmoothedSolution", "FilterError", "integrate", "state_names", "MEAS_TYPES",
           "SENSOR_NAMES", "UPDATE_STATUS"]
