"""Interface of the strapdown navigator FMU (ENU quaternion mechanization, gf_sins) —
the one place its variables are listed; fmu/tools/fmugen.py makes the FMI 2.0 and 3.0
modelDescription.xml and the C table from it."""

import pathlib
import runpy

_RAD = "rad"
_COMMON = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "common" / "nav_params.py"))

MODEL = dict(
    model_name="gfins.StrapdownINS",
    model_identifier="gfins_sins",
    description=(
        "Strapdown INS: ENU quaternion mechanization on WGS-84 (seed 002), two-sample "
        "coning/sculling, free/held/baro-damped vertical channel. doStep(t, h) takes the "
        "sample set at t (an increment covers the step that ends at t; at the start time "
        "there is none); the outputs after it describe t."
    ),
    default_experiment=dict(start_time=0.0, stop_time=60.0, step_size=0.01),
    variables=[
        dict(name="input_mode", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=0, field="input_mode",
             description="0: increments (dtheta, dv); 1: rates (gyro_rate, specific_force)"),
        dict(name="coning", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=1, field="coning",
             description="1: two-sample coning and sculling corrections; 0: none"),
        *_COMMON["vertical_channel"](),
        dict(name="max_rate", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="rad/s", start=50.0, field="max_rate_rad_s",
             description="Samples with a larger angular rate are refused as absurd"),
        dict(name="max_specific_force", causality="parameter", variability="fixed",
             type="Float64", shape=(), unit="m/s2", start=1000.0,
             field="max_specific_force_m_s2",
             description="Samples with a larger specific force are refused as absurd"),
        *_COMMON["initial_state"](),
        _COMMON["skip_steps"](),
        dict(name="imu_comp", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=0, field="imu_comp",
             description="1: compensate the inputs with the IMU error model below "
                         "(gf_imu_error; the model of gfins_fmi.ImuErrors, in SI units)"),
        *_COMMON["imu_error_parameters"](),
        dict(name="lowpass_sections", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=0, field="lowpass_sections",
             description="Number of second-order sections of the input low-pass (0: off, max 8)"),
        dict(name="lowpass_sos", causality="parameter", variability="fixed", type="Float64",
             shape=(48,), start=0.0, field="lowpass_sos",
             description="Low-pass sections [b0 b1 b2 1 a1 a2] x lowpass_sections (e.g. "
                         "gfins_fmi.signal_conditioning.design_cheby2), applied after the compensation"),
        dict(name="rotating", causality="parameter", variability="fixed", type="Int32",
             shape=(), start=0, field="rotating",
             description="1: the inputs come from an IMU on seed 001's two-axis mechanism (the "
                         "IMU frame m is navigated: q, euler describe it); q_vehicle and "
                         "euler_vehicle give the vehicle from it and the input gimbal "
                         "(sim/gf_rot.h: C_b^n = C_m^n (R_x(middle) R_z(inner))^T)"),
        *_COMMON["imu_inputs"](),
        _COMMON["external_height"](),
        dict(name="gimbal", causality="input", variability="continuous", type="Float64",
             shape=(2,), unit=_RAD, start=0.0, field="gimbal_rad",
             description="rotating = 1: middle and inner gimbal angles (encoders) at the sample"),
        dict(name="q", causality="output", variability="discrete", type="Float64",
             shape=(4,), field="q_bn", description="Attitude quaternion q_b^n"),
        dict(name="euler", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit=_RAD, field="euler_rad",
             description="Heading (clockwise from north, [0, 2 pi)), pitch, roll"),
        dict(name="v", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit="m/s", field="v_n_m_s", description="Velocity, East-North-Up"),
        dict(name="lat", causality="output", variability="discrete", type="Float64",
             shape=(), unit=_RAD, field="lat_rad", description="Geodetic latitude"),
        dict(name="lon", causality="output", variability="discrete", type="Float64",
             shape=(), unit=_RAD, field="lon_rad", description="Longitude"),
        dict(name="h", causality="output", variability="discrete", type="Float64",
             shape=(), unit="m", field="h_m", description="Height above the ellipsoid"),
        dict(name="time_s", causality="output", variability="discrete", type="Float64",
             shape=(), unit="s", field="nav_time_s",
             description="Time that the navigation outputs describe"),
        dict(name="q_vehicle", causality="output", variability="discrete", type="Float64",
             shape=(4,), field="q_vehicle",
             description="Vehicle attitude q_b^n (rotating = 1: from q and gimbal; else q)"),
        dict(name="euler_vehicle", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit=_RAD, field="euler_vehicle_rad",
             description="Vehicle heading, pitch, roll (rotating = 1; else euler)"),
    ],
)
