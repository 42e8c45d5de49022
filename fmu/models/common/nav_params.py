"""Variables shared by the navigation FMU specs (SINS and gyro-free navigators): the
vertical channel and the initial state. Each entry is a spec variable dict (see
fmu/tools/fmugen.py); ModelData field names are the same in every navigation model."""


def parameter(name, unit, start, field, description, type_="Float64", shape=()) -> dict:
    """A fixed parameter (unit None or '' for a dimensionless one)."""
    d = dict(name=name, causality="parameter", variability="fixed", type=type_, shape=shape,
             start=start, field=field, description=description)
    if unit:
        d["unit"] = unit
    return d


def model_input(name, unit, start, field, description, type_="Float64", shape=()) -> dict:
    """An input: continuous when Float64, else discrete."""
    d = dict(name=name, causality="input", variability="continuous" if type_ == "Float64"
             else "discrete", type=type_, shape=shape, start=start, field=field,
             description=description)
    if unit:
        d["unit"] = unit
    return d


def model_output(name, unit, shape, field, description, type_="Float64") -> dict:
    """A discrete output."""
    d = dict(name=name, causality="output", variability="discrete", type=type_,
             shape=shape, field=field, description=description)
    if unit:
        d["unit"] = unit
    return d


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
             description="Initial geodetic latitude, |lat0| < 89.9 deg (the latitude limit "
                         "of the ENU mechanization; earth = 0)"),
        dict(name="lon0", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="rad", start=1.9896753472735356, field="lon0_rad",
             description="Initial longitude"),
        dict(name="h0", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="m", start=0.0, field="h0_m",
             description="Initial height above the WGS-84 ellipsoid"),
    ]


def skip_steps() -> dict:
    return dict(name="skip_steps", causality="parameter", variability="fixed", type="Int32",
                shape=(), start=0, field="skip_steps",
                description="Number of first doSteps whose inputs are ignored: navigation "
                            "starts at the sample after them, from the initial state given. "
                            "1 for masters that pass no connected outputs before the first "
                            "step (fmpy's SSP simulator starts every connection at 0)")


def imu_inputs() -> list:
    """The strapdown navigators' IMU sample (SINS, integrated navigator): increments or
    rates, body right-front-up, chosen by the parameter input_mode."""
    return [
        dict(name="dtheta", causality="input", variability="continuous", type="Float64",
             shape=(3,), unit="rad", start=0.0, field="dtheta_rad",
             description="Gyro angle increment over the interval since the previous sample, "
                         "ending now, body axes (right-front-up); used when input_mode = 0"),
        dict(name="dv", causality="input", variability="continuous", type="Float64",
             shape=(3,), unit="m/s", start=0.0, field="dv_m_s",
             description="Accelerometer velocity increment over the interval since the "
                         "previous sample, ending now, body axes; used when input_mode = 0"),
        dict(name="gyro_rate", causality="input", variability="continuous", type="Float64",
             shape=(3,), unit="rad/s", start=0.0, field="gyro_rad_s",
             description="Angular rate w_ib^b now; used when input_mode = 1"),
        dict(name="specific_force", causality="input", variability="continuous",
             type="Float64", shape=(3,), unit="m/s2", start=0.0, field="accel_m_s2",
             description="Specific force f^b now; used when input_mode = 1"),
    ]


def external_height() -> dict:
    return dict(name="h_ext", causality="input", variability="continuous", type="Float64",
                shape=(), unit="m", start=float("nan"), field="h_ext_m",
                description="External (barometric) height at the communication point for "
                            "vertical_mode = 2; NaN (the start value): none")


def imu_error_parameters() -> list:
    """The IMU error model (gf_imu_error, SI units; gfins_fmi.ImuErrors.fmu_parameters()
    gives them from datasheet units): compensated by the SINS FMU, applied by the vehicle
    FMU. ModelData field: ``FmuImuParams imu_params`` (common/imu_params.h)."""
    return [
        dict(name="gyro_bias", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="rad/s", start=0.0, field="imu_params.gyro_bias_rad_s", description="Gyro biases"),
        dict(name="gyro_scale", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), start=0.0, field="imu_params.gyro_scale", description="Gyro scale-factor errors (1 = 100%)"),
        dict(name="gyro_misalign", causality="parameter", variability="fixed", type="Float64",
             shape=(9,), unit="rad", start=0.0, field="imu_params.gyro_misalign_rad",
             description="Gyro cross-coupling N_g, row-major 3 x 3, zero diagonal"),
        dict(name="accel_bias", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="m/s2", start=0.0, field="imu_params.accel_bias_m_s2", description="Accelerometer biases"),
        dict(name="accel_scale", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), start=0.0, field="imu_params.accel_scale", description="Accelerometer scale-factor errors"),
        dict(name="accel_misalign", causality="parameter", variability="fixed", type="Float64",
             shape=(9,), unit="rad", start=0.0, field="imu_params.accel_misalign_rad",
             description="Accelerometer cross-coupling N_a, row-major 3 x 3, zero diagonal"),
        dict(name="accel_k2", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="s2/m", start=0.0, field="imu_params.accel_k2_s2_m",
             description="Accelerometer second-order coefficients K2"),
        dict(name="lever_arm", causality="parameter", variability="fixed", type="Float64",
             shape=(3,), unit="m", start=0.0, field="imu_params.lever_arm_m",
             description="Inner lever arms of the accelerometers along their axes (the "
                         "diagonal of their positions)"),
        dict(name="lever_arm_transverse", causality="parameter", variability="fixed", type="Float64",
             shape=(6,), unit="m", start=0.0, field="imu_params.lever_arm_transverse_m",
             description="Accelerometer positions across their axes: r_xy, r_xz, r_yx, r_yz, "
                         "r_zx, r_zy (r_ij: component j of accelerometer i's position)"),
        dict(name="accel_delay", causality="parameter", variability="fixed", type="Float64",
             shape=(), unit="s", start=0.0, field="imu_params.accel_delay_s",
             description="Accelerometer samples late behind the gyros by this"),
    ]


def refusal_table(settings) -> str:
    """C (model_extra.h): the FMU parameter, unit and bounds of each configuration field
    the core can refuse, by its member name (gf_ins_config_field), for the refusal message
    of common/ins_settings.h; ``settings``: the settings table's rows the FMU exposes."""
    rows = []
    for st in settings:
        is_int = 0 if st.kind in ("float", "vector") else 1
        bounds = " or ".join(f"{v} ({k})" for k, v in st.choices.items()) if st.choices \
            else st.describe_bounds()
        rows.append(f'    {{"{st.member}", "{st.short}", offsetof(ModelData, cfg.{st.member}), '
                    f'{is_int}, {st.size}, "{st.unit or ""}", "{bounds}"}},')
    return "\n".join([
        "/* the filter settings the FMU exposes (gfins_fmi/estimation/settings.py) */",
        "typedef struct InsSetting {",
        "    const char *member, *parameter;",
        "    size_t offset;",
        "    int is_int, count;",
        "    const char *unit, *bounds;",
        "} InsSetting;",
        "static const InsSetting kInsSettings[] = {", *rows, "};", ""])
