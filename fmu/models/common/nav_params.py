"""Variables shared by the navigation FMU specs (SINS and gyro-free navigators): the
vertical channel and the initial state. Each entry is a spec variable dict (see
fmu/tools/fmugen.py); ModelData field names are the same in every navigation model."""


def vertical_channel() -> list:
    return [
        dict(name="vertical_mode", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=0, field="vertical_mode",
             description="0: free; 1: height held at hold_height; 2: damped by h_ext "
                         "(third-order loop, triple pole at -1/baro_tau)"),
        dict(name="hold_height", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="m", start=0.0, field="hold_height_m",
             description="Height held when vertical_mode = 1"),
        dict(name="baro_tau", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="s", start=10.0, field="baro_tau_s",
             description="Time constant of the baro loop (vertical_mode = 2), > 0"),
    ]


def initial_state() -> list:
    return [
        dict(name="q0", causality="parameter", variability="fixed", type="Float64",
             shape=(4,), start=[1.0, 0.0, 0.0, 0.0], field="q0",
             description="Initial attitude quaternion q_b^n (scalar first; normalised)"),
        dict(name="v0", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="m/s", start=0.0, field="v0_m_s",
             description="Initial velocity, East-North-Up"),
        dict(name="lat0", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="rad", start=0.5235987755982988, field="lat0_rad",
             description="Initial geodetic latitude, |lat0| < pi/2"),
        dict(name="lon0", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="rad", start=1.9896753472735356, field="lon0_rad",
             description="Initial longitude"),
        dict(name="h0", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="m", start=0.0, field="h0_m",
             description="Initial height above the WGS-84 ellipsoid"),
    ]


def external_height() -> dict:
    return dict(name="h_ext", causality="input", variability="continuous", type="Float64",
                shape=(), unit="m", start=float("nan"), field="h_ext_m",
                description="External (barometric) height at the communication point for "
                            "vertical_mode = 2; NaN (the start value): none")
