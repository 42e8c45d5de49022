"""Estimation on the one Kalman engine of the C core: integrated navigation (INS/GNSS
with barometer, odometer, non-holonomic and zero-velocity aiding; EKF or UKF; RTS
smoother) and the tools to evaluate it. See docs/estimation.md.

Modules: ``config`` (FilterConfig, InitialState, the names of measurement kinds and
sensor estimates), ``error_model`` (the filter's error model in numpy: its definition),
``measurements`` (the C structs as numpy dtypes, gathering the aiding records),
``measurement_checks`` (records a run cannot use, found before it),
``navigator`` (IntegratedNavigator), ``solution`` (IntegratedSolution and the smoother),
``smoother_stream`` (StreamingSmoother: the smoother with flat memory, epochs on disk),
``alignment`` (coarse alignment), ``fine_alignment`` (with the filter: at rest, in motion),
``evaluation`` (errors against a reference, consistency, outages, figures).
"""
from gfins_fmi.estimation.config import (MEAS_TYPES, SENSOR_NAMES, UPDATE_STATUS, FilterConfig,
                                         FilterError, InitialState, state_names)
from gfins_fmi.estimation.measurement_checks import UnusableMeasurementError, UnusableMeasurementWarning
from gfins_fmi.estimation.navigator import IntegratedNavigator, integrate
from gfins_fmi.estimation.solution import IntegratedSolution, SmoothedSolution
from gfins_fmi.estimation.smoother_stream import StreamingSmoother

__all__ = ["FilterConfig", "InitialState", "IntegratedNavigator", "IntegratedSolution",
           "SmoothedSolution", "StreamingSmoother", "FilterError", "integrate", "state_names", "MEAS_TYPES",
           "SENSOR_NAMES", "UPDATE_STATUS", "UnusableMeasurementError", "UnusableMeasurementWarning"]
