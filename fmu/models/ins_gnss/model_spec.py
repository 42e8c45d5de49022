"""Interface of the integrated-navigator FMU: the error-state INS/GNSS filter of the C
core (csrc/est/gf_ins_gnss.h, EKF or UKF) aided by GNSS position/velocity, barometer and
odometer, with non-holonomic and zero-velocity updates — the one place its variables are
listed; fmu/tools/fmugen.py makes the FMI 2.0 and 3.0 modelDescription.xml and the C
table from it. Parameter defaults equal gfins_fmi.estimation.FilterConfig's (checked by
tests/test_fmu_ins_gnss.py); the noise and initial-uncertainty defaults describe a
consumer-grade MEMS IMU (set yours)."""

import math
import pathlib
import runpy

_COMMON = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "common" / "nav_params.py"))
_p = _COMMON["parameter"]
_in = _COMMON["model_input"]
_out = _COMMON["model_output"]
# the filter's settings table, read by path (the build runs without the package)
_SETTINGS = runpy.run_path(str(pathlib.Path(__file__).resolve().parents[3] / "gfins_fmi" /
                               "estimation" / "settings.py"))

DEG = math.pi / 180.0
# the default IMU of the FMU's noise parameters (settings.FMU_IMU_NOISE), also the default
# initial bias uncertainty
_GYRO_BIAS = _SETTINGS["FMU_IMU_NOISE"]["gyro_bias_std_rad_s"]
_ACCEL_BIAS = _SETTINGS["FMU_IMU_NOISE"]["accel_bias_std_m_s2"]

#: measurement kinds of the per-kind monitoring outputs, index = GF_INS_MEAS_* - 1
KINDS = "gnss_pos, gnss_vel, baro, odometer, nhc, zupt, zaru"


_NAN = float("nan")


def _filter_parameters():
    """One parameter per row of the settings table that the FMU can use, named as in C
    and Python, pointing at the member of ModelData.cfg."""
    out = []
    for st in _SETTINGS["fmu_settings"]():
        type_ = "Float64" if st.kind in ("float", "vector") else "Int32"
        text = st.meaning[0].upper() + st.meaning[1:]
        if st.kind == "enum":
            text += " (" + ", ".join(f"{v}: {k}" for k, v in st.choices.items()) + ")"
        elif st.kind != "flag":
            text += f"; {st.describe_bounds()}"
        out.append(_p(st.short, st.unit or None, st.fmu_start, "cfg." + st.member, text, type_,
                      shape=(st.size,) if st.kind == "vector" else ()))
    return out


def _initial_uncertainty():
    return [
        _p("sensors0", None, 0.0, "sensors0", "Initial sensor-error estimates (gyro bias 3 "
           "rad/s, accelerometer bias 3 m/s2, gyro scale 3, accelerometer scale 3, "
           "barometer bias m, odometer scale, odometer boresight correction pitch and "
           "heading rad)", shape=(16,)),
        _p("std0_vel", "m/s", 0.1, "std0_vel_m_s", "Initial 1-sigma of the velocity, "
           "east, north, up, > 0", shape=(3,)),
        _p("std0_pos", "m", 1.0, "std0_pos_m", "Initial 1-sigma of the position, east, "
           "north, up, > 0", shape=(3,)),
        _p("std0_att", "rad", [0.01, 0.01, 0.05], "std0_att_rad", "Initial 1-sigma of the "
           "attitude error (east, north tilt; up: heading), > 0", shape=(3,)),
        _p("std0_gyro_bias", "rad/s", _GYRO_BIAS, "std0_gyro_bias_rad_s",
           "Initial 1-sigma of the gyro biases, > 0", shape=(3,)),
        _p("std0_accel_bias", "m/s2", _ACCEL_BIAS, "std0_accel_bias_m_s2",
           "Initial 1-sigma of the accelerometer biases, > 0", shape=(3,)),
        _p("std0_gyro_scale", None, 1e-3, "std0_gyro_scale",
           "Initial 1-sigma of the gyro scale factors (scale_factors = 1), > 0", shape=(3,)),
        _p("std0_accel_scale", None, 1e-3, "std0_accel_scale",
           "Initial 1-sigma of the accelerometer scale factors (scale_factors = 1), > 0",
           shape=(3,)),
        _p("std0_baro_bias", "m", 1.0, "std0_baro_bias_m",
           "Initial 1-sigma of the barometer bias (baro_bias = 1), > 0"),
        _p("std0_odo_scale", None, 0.01, "std0_odo_scale",
           "Initial 1-sigma of the odometer scale factor (odometer_scale = 1), > 0"),
        _p("std0_odo_mount", "rad", 0.035, "std0_odo_mount_rad",
           "Initial 1-sigma of the odometer boresight pitch and heading (odometer_mount "
           "= 1), > 0", shape=(2,)),
    ]


_HELD = " (when *_valid > 0; not read otherwise)"


def _measurement_inputs():
    return [
        _in("gnss_valid", None, 0, "gnss_valid", "> 0: a GNSS epoch was delivered with "
            "this step (the gnss_* inputs hold it; a count > 1 uses the newest)", "Int32"),
        _in("gnss_time_s", "s", _NAN, "gnss_time_s", "GNSS time of validity, on the "
            "simulation time scale" + _HELD),
        _in("gnss_lat_rad", "rad", _NAN, "gnss_lat_rad", "GNSS antenna latitude" + _HELD),
        _in("gnss_lon_rad", "rad", _NAN, "gnss_lon_rad", "GNSS antenna longitude" + _HELD),
        _in("gnss_h_m", "m", _NAN, "gnss_h_m", "GNSS antenna height above the ellipsoid" + _HELD),
        _in("gnss_vel_enu_m_s", "m/s", _NAN, "gnss_vel_enu_m_s",
            "GNSS antenna velocity east, north, up" + _HELD, shape=(3,)),
        _in("gnss_pos_std_m", "m", _NAN, "gnss_pos_std_m",
            "GNSS position std east, north, up, > 0" + _HELD, shape=(3,)),
        _in("gnss_vel_std_m_s", "m/s", _NAN, "gnss_vel_std_m_s",
            "GNSS velocity std east, north, up, > 0" + _HELD, shape=(3,)),
        _in("gnss_vel_valid", None, 1, "gnss_vel_valid",
            "1: the GNSS epoch's velocity is used too; 0: position only", "Int32"),
        _in("baro_valid", None, 0, "baro_valid",
            "> 0: a barometer sample was delivered with this step", "Int32"),
        _in("baro_time_s", "s", _NAN, "baro_time_s", "Barometer time of validity" + _HELD),
        _in("baro_h_m", "m", _NAN, "baro_h_m", "Barometric height" + _HELD),
        _in("baro_std_m", "m", _NAN, "baro_std_m", "Barometer std, > 0" + _HELD),
        _in("odo_valid", None, 0, "odo_valid",
            "> 0: an odometer sample was delivered with this step", "Int32"),
        _in("odo_time_s", "s", _NAN, "odo_time_s", "Odometer time of validity" + _HELD),
        _in("odo_speed_m_s", "m/s", _NAN, "odo_speed_m_s",
            "Odometer forward speed of the wheel point" + _HELD),
        _in("odo_std_m_s", "m/s", _NAN, "odo_std_m_s", "Odometer std, > 0" + _HELD),
    ]


def _outputs():
    per_kind = f" per measurement kind ({KINDS})"
    return [
        _out("q", None, (4,), "q_bn", "Attitude quaternion q_b^n"),
        _out("euler", "rad", (3,), "euler_rad",
             "Heading (clockwise from north, [0, 2 pi)), pitch, roll"),
        _out("v", "m/s", (3,), "v_n_m_s", "Velocity, East-North-Up"),
        _out("lat", "rad", (), "lat_rad", "Geodetic latitude"),
        _out("lon", "rad", (), "lon_rad", "Longitude"),
        _out("h", "m", (), "h_m", "Height above the ellipsoid"),
        _out("time_s", "s", (), "nav_time_s", "Time that the navigation outputs describe"),
        _out("std", None, (9,), "std9", "1-sigma: velocity east, north, up (m/s), position "
             "east, north, up (m), attitude east, north, up (rad)"),
        _out("sensors", None, (16,), "sensors", "Sensor-error estimates: gyro bias (3, "
             "rad/s), accelerometer bias (3, m/s2), gyro scale (3), accelerometer scale (3), "
             "barometer bias (m), odometer scale, odometer boresight correction (pitch, "
             "heading, rad)"),
        _out("n_imu", None, (), "n_imu", "IMU samples processed", "Int32"),
        _out("n_updates", None, (), "n_updates", "Updates accepted", "Int32"),
        _out("n_rejected", None, (), "n_rejected",
             "Updates rejected (gate, singular, stale)", "Int32"),
        _out("nis", None, (7,), "nis", "Normalised innovation squared of the last update"
             + per_kind + "; NaN before the first and for stale measurements"),
        _out("update_status", None, (7,), "update_status", "Outcome of the last update"
             + per_kind + ": -1 none yet, 0 accepted, 1 rejected by the gate, 2 singular, "
             "3 stale (valid at or before the filter's time)", "Int32"),
        _out("update_time", "s", (7,), "update_time_s",
             "Time of the last update" + per_kind + "; NaN before the first"),
        _out("update_count", None, (7,), "update_count",
             "Updates so far (accepted or not)" + per_kind, "Int32"),
        _out("standstill", None, (), "standstill",
             "1: the standstill detector says the IMU is still (zupt = 1)", "Int32"),
        _out("aligning", None, (), "aligning",
             "1 during the alignment phase (align_time > 0): the navigation outputs are the "
             "initial state's while at rest; with align_heading = 1 then those of the "
             "mechanization with the heading unknown (heading relative to that at the end of "
             "the phase at rest) until a GNSS epoch faster than align_min_speed ends it — "
             "without one it stays 1", "Int32"),
    ]


MODEL = dict(
    model_name="gfins.IntegratedNavigator",
    model_identifier="gfins_ins_gnss",
    description=(
        "Integrated navigation: error-state Kalman filter (EKF or UKF) correcting a WGS-84 "
        "strapdown mechanization with GNSS position/velocity, barometer and odometer "
        "(gf_ins_gnss). doStep(t, h) takes the IMU sample set at t (an increment covers the "
        "interval since the previous sample; at the start time there is none) and the "
        "measurements delivered with it; each carries its time of validity t_m: inside the "
        "sample's interval the interval is split there, at or before its start it is stale, "
        "after t it is refused. The outputs after the step describe t."
    ),
    default_experiment=dict(start_time=0.0, stop_time=60.0, step_size=0.01),
    variables=[
        *_filter_parameters(),
        *_COMMON["initial_state"](),
        *_initial_uncertainty(),
        _COMMON["skip_steps"](),
        _p("align_time", "s", 0.0, "align_time_s", "> 0: the run starts with an alignment phase "
           "at rest of this duration: the IMU samples are averaged (measurements are not used), "
           "the attitude is found by levelling and gyrocompassing (TRIAD on gravity and the "
           "Earth rate, gf_ins_coarse_align; q0 and v0 are not used, the velocity is 0) and "
           "the filter starts from it at the end of the phase with std0_*; motion during the "
           "phase (std of |f| above 0.2 m/s2 or mean |w| above 0.05 rad/s) and |lat0| above "
           "85 deg are errors (align_heading = 0). 0: start from q0, v0"),
        _p("align_heading", None, 0, "align_heading", "How the alignment phase (align_time > "
           "0) finds the heading. 0: gyrocompassing at rest (the gyros must see the Earth "
           "rate: navigation or tactical grade). 1: from the direction of travel, for gyros "
           "that cannot gyrocompass: the phase at rest only levels (roll and pitch from the "
           "mean specific force; the mean rate at rest becomes the gyro-bias estimate), then "
           "the IMU is mechanized with heading 0 from the position lat0, lon0, h0 (aligning "
           "stays 1, measurements are not used) until the first GNSS epoch with velocity "
           "(gnss_vel_valid = 1) whose horizontal speed exceeds align_min_speed: the attitude "
           "is turned about the vertical so that the body's forward axis y points along that "
           "velocity, the velocity and position are set to the epoch's (position less the "
           "lever arm) and the filter starts there with std0_* (heading std: align_travel_std "
           "combined with the direction std of the GNSS velocity); that epoch is used up by "
           "the start (no update with it)", "Int32"),
        _p("align_min_speed", "m/s", 1.0, "align_min_speed_m_s", "align_heading = 1: the "
           "horizontal GNSS speed above which its direction gives the heading, > 0"),
        _p("align_travel_std", "rad", 10.0 * DEG, "align_travel_std_rad", "align_heading = 1: "
           "1-sigma angle between the body's forward axis y and the direction of travel "
           "(mounting misalignment, side slip), > 0"),
        *_COMMON["imu_inputs"](),
        *_measurement_inputs(),
        *_outputs(),
    ],
    c_extra=_COMMON["refusal_table"](_SETTINGS["fmu_settings"]()),
)
