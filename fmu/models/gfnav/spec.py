"""Interface of the gyro-free navigator FMUs, one per array layout (the layout fixes the
number of inputs, which FMI 2.0 cannot change at run time). ``make(layout, n)`` returns
the spec; ``fmu/models/gfnav_<layout>/model_spec.py`` call it."""

import pathlib
import runpy

_COMMON = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "common" / "nav_params.py"))

_NAMES = {"cube6": "6-accelerometer cube (Tan & Park)", "qin9": "9-accelerometer layout of "
          "Qin, Xu, Li (seed 000)", "12": "12-accelerometer layout (Qin's nine plus three "
          "tangential sensors)"}
_DEFAULT_STRATEGY = {"cube6": 0, "qin9": 1, "12": 2}


def make(layout: str, n: int) -> dict:
    return dict(
        model_name=f"gfins.GyroFreeNavigator_{layout}",
        model_identifier=f"gfins_gfnav_{layout}",
        description=(
            f"Gyro-free navigator, {_NAMES[layout]}: accelerometer outputs -> (angular rate, "
            "specific force) by least squares and a rate strategy -> strapdown mechanization. "
            "doStep(t, h) takes the outputs sampled at t; the outputs after it describe t."),
        default_experiment=dict(start_time=0.0, stop_time=60.0, step_size=0.01),
        variables=[
            dict(name="l", causality="parameter", variability="fixed", type="Float64", shape=(),
                 unit="m", start=0.1, field="lever_arm_m",
                 description="Lever arm of the layout, >= 1e-6 m"),
            dict(name="strategy", causality="parameter", variability="fixed", type="Int32",
                 shape=(), start=_DEFAULT_STRATEGY[layout], field="strategy",
                 description="Rate strategy: 0 integrate w_dot, 1 sqrt of w^2 with sign from "
                             "integrated w_dot, 2 eigenpair of w w^T, 3 fused EKF"),
            dict(name="accel_noise", causality="parameter", variability="fixed", type="Float64",
                 shape=(), unit="m/s2", start=1e-4, field="accel_noise_m_s2",
                 description="White-noise std of each accelerometer (fused strategy), > 0"),
            dict(name="omega_init", causality="parameter", variability="fixed", type="Float64",
                 shape=(3,), unit="rad/s", start=0.0, field="omega_init_rad_s",
                 description="Angular rate at the first sample (signs, start of the w_dot integral)"),
            dict(name="earth", causality="parameter", variability="fixed", type="Int32",
                 shape=(), start=0, field="earth",
                 description="0: WGS-84 (lat0, lon0, h0); 1: fixed frame with constant gravity "
                             "flat_gravity along -z (position pos_m)"),
            dict(name="flat_gravity", causality="parameter", variability="fixed", type="Float64",
                 shape=(), unit="m/s2", start=0.0, field="flat_gravity_m_s2",
                 description="Gravity of the fixed frame (earth = 1), >= 0"),
            *_COMMON["vertical_channel"](),
            *_COMMON["initial_state"](),
            _COMMON["skip_steps"](),
            dict(name="pos0", causality="parameter", variability="fixed", type="Float64",
                 shape=(3,), unit="m", start=0.0, field="pos0_m",
                 description="Initial position in the fixed frame (earth = 1)"),
            dict(name="A", causality="input", variability="continuous", type="Float64",
                 shape=(n,), unit="m/s2", start=0.0, field="A_m_s2",
                 description=f"Outputs of accelerometers 1..{n} of the layout"),
            _COMMON["external_height"](),
            dict(name="q", causality="output", variability="discrete", type="Float64",
                 shape=(4,), field="q_bn", description="Attitude quaternion q_b^n"),
            dict(name="euler", causality="output", variability="discrete", type="Float64",
                 shape=(3,), unit="rad", field="euler_rad",
                 description="Heading (clockwise from north), pitch, roll"),
            dict(name="v", causality="output", variability="discrete", type="Float64",
                 shape=(3,), unit="m/s", field="v_n_m_s", description="Velocity"),
            dict(name="lat", causality="output", variability="discrete", type="Float64",
                 shape=(), unit="rad", field="lat_rad", description="Latitude (earth = 0)"),
            dict(name="lon", causality="output", variability="discrete", type="Float64",
                 shape=(), unit="rad", field="lon_rad", description="Longitude (earth = 0)"),
            dict(name="h", causality="output", variability="discrete", type="Float64",
                 shape=(), unit="m", field="h_m", description="Height (earth = 0)"),
            dict(name="pos", causality="output", variability="discrete", type="Float64",
                 shape=(3,), unit="m", field="pos_m", description="Position (earth = 1)"),
            dict(name="omega", causality="output", variability="discrete", type="Float64",
                 shape=(3,), unit="rad/s", field="omega_rad_s", description="Solved angular rate"),
            dict(name="f", causality="output", variability="discrete", type="Float64",
                 shape=(3,), unit="m/s2", field="f_m_s2", description="Solved specific force"),
            dict(name="flags", causality="output", variability="discrete", type="Int32",
                 shape=(), field="flags",
                 description="Rate flags: 1,2,4 negative w_k^2 (or eigenvalue); 8 sign unknown; "
                             "16 fused update skipped"),
            dict(name="time_s", causality="output", variability="discrete", type="Float64",
                 shape=(), unit="s", field="nav_time_s",
                 description="Time that the navigation outputs describe"),
        ],
    )
