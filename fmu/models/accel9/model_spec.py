"""Interface of the 9-accelerometer solver FMU — the one place its variables are listed.

``fmu/tools/fmugen.py`` turns this into the FMI 2.0 and FMI 3.0 modelDescription.xml
files and into the C table (``model_vars.h``) through which the generic glue gets and
sets values. ``field`` is the member of ``ModelData`` (``model.h``) behind a variable.
FMI 2.0 sees each array element as a scalar named ``name[i]`` (structured naming,
1-based); FMI 3.0 sees one array variable.
"""

MODEL = dict(
    model_name="gfins.Accel9Solver",
    model_identifier="gfins_accel9",
    description=(
        "Gyro-free 9-accelerometer kinematic solver (Qin, Xu, Li; seed 000 eq. 3, 4, 6): "
        "accelerometer outputs -> specific force, angular rate, angular acceleration. "
        "doStep(t, h) solves the input sample set at t; the outputs after it describe t."
    ),
    default_experiment=dict(start_time=0.0, stop_time=10.0, step_size=0.01),
    variables=[
        dict(name="l", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="m", start=0.1, field="lever_arm_m",
             description="Lever arm l of the array (distance of sensors 1-6 from the centre), > 0"),
        dict(name="omega_init", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="rad/s", start=0.0, field="omega_init_rad_s",
             description="Angular rate at the first sample: first signs, and the start of "
                         "the omega_dot integral that gives the signs"),
        dict(name="A", causality="input", variability="continuous", type="Float64",
             shape=(9,), unit="m/s2", start=0.0, field="A_m_s2",
             description="Outputs of accelerometers 1..9 (layout of seed 000)"),
        dict(name="f", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit="m/s2", field="f_m_s2",
             description="Specific force at the array centre, body axes (eq. 3)"),
        dict(name="omega", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit="rad/s", field="omega_rad_s",
             description="Angular rate, body axes: magnitude from eq. 4, sign from eq. 6 "
                         "integrated from omega_init"),
        dict(name="omega_dot", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit="rad/s2", field="omega_dot_rad_s2",
             description="Angular acceleration, body axes (eq. 6)"),
        dict(name="omega_sq", causality="output", variability="discrete", type="Float64",
             shape=(3,), unit="rad2/s2", field="omega_sq_rad2_s2",
             description="Squared angular rates as measured (eq. 4); < 0 under noise"),
        dict(name="flags", causality="output", variability="discrete", type="Int32",
             shape=(), field="flags",
             description="Per-sample flags: 1,2,4 = omega_x,y,z^2 < 0 (rate = integrated "
                         "reference); "
                         "8,16,32 = sign of omega_x,y,z unknown (taken positive)"),
    ],
)
