"""Interface of the vehicle FMU (gf_vehicle): a level ground vehicle following a profile
of segments or driven by speed / heading-rate commands, with the outputs of the sensors
riding it — an IMU (rates and increments, optionally corrupted by the IMU error model),
an accelerometer array of a chosen layout and, when enabled, the aiding sensors: a GNSS
receiver, a barometer and an odometer (csrc/sim/gf_aiding.h). fmu/tools/fmugen.py makes the FMI 2.0
and 3.0 modelDescription.xml and the C table from it."""

import math
import pathlib
import runpy

_COMMON = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "common" / "nav_params.py"))
_p = _COMMON["parameter"]
_out = _COMMON["model_output"]
MAX_SEGMENTS = 32  # GF_VEHICLE_MAX_SEGMENTS
# default profile: seed 001's vehicle test with a 60 s alignment (VehicleProfile.seed001(60))
_DEFAULT = [(60.0, 0.0, 0.0, 0.0), (20.0, 15.0, 0.0, 0.0), (220.0, 0.0, 0.0, 0.0),
            (30.0, 0.0, 0.0, math.pi), (210.0, 0.0, 0.0, 0.0), (30.0, 0.0, 0.0, math.pi)]


def _column(k):
    return [row[k] for row in _DEFAULT] + [0.0] * (MAX_SEGMENTS - len(_DEFAULT))


MAX_OUTAGES = 8  # GF_AIDING_MAX_OUTAGES
MAX_TURNS = 64  # GF_ROT_MAX_SEGMENTS
# default rotation scheme: 16-position indexing, 180 deg turns at 10 deg/s (1 s ramps),
# 10 s stops (gfins_fmi.sim.rotation.indexing_scheme(16)); used when rotation = 1
_IDX8 = [("i", 1), ("m", 1), ("i", -1), ("m", -1), ("m", -1), ("i", -1), ("m", 1), ("i", 1)]
_IDX16 = _IDX8 + [("m" if a == "i" else "i", s) for a, s in _IDX8]


def _turn_column(kind):
    col = []
    for a, s in _IDX16:
        col.append({"base_axis": 0 if a == "m" else -1, "imu_axis": 2 if a == "i" else -1,
                    "base_angle": s * math.pi if a == "m" else 0.0,
                    "imu_angle": s * math.pi if a == "i" else 0.0,
                    "move": 19.0, "ramp": 1.0, "dwell": 10.0}[kind])
    pad = -1 if kind.endswith("axis") else 0.0
    return col + [pad] * (MAX_TURNS - len(col))


def _rotation_parameters():
    """The IMU on seed 001's two-axis mechanism (csrc/sim/gf_rot.h): a schedule of turns
    about the base's axes (middle axis: base x) and the IMU's axes (inner axis: IMU z);
    gfins_fmi.sim.rotation.RotationSchedule.fmu_parameters() gives them."""
    r = "rot_"
    return [
        _p("rotation", None, 0, "rotation", "1: the IMU rides the two-axis indexing mechanism "
           "and its outputs (gyro_rate ... dv) are those of the IMU frame m, turned by the "
           "schedule below; 0: fixed to the body", type_="Int32"),
        _p("rot_n", None, len(_IDX16), r + "n", f"Number of turns used, 0 .. {MAX_TURNS}",
           type_="Int32"),
        _p("rot_repeat", None, 1, r + "repeat", "1: the turns repeat (one cycle must bring "
           "the IMU back to its start attitude)", type_="Int32"),
        _p("rot_base_axis", None, _turn_column("base_axis"), r + "base_axis",
           "Turn k about the base's axis -1 (none), 0, 1, 2 = x (middle axis), y, z",
           type_="Int32", shape=(MAX_TURNS,)),
        _p("rot_imu_axis", None, _turn_column("imu_axis"), r + "imu_axis",
           "Turn k about the IMU's axis -1 (none), 0, 1, 2 = x, y, z (inner axis)",
           type_="Int32", shape=(MAX_TURNS,)),
        _p("rot_base_angle", "rad", _turn_column("base_angle"), r + "base_angle_rad",
           "Angle of turn k about the base axis (right-handed)", shape=(MAX_TURNS,)),
        _p("rot_imu_angle", "rad", _turn_column("imu_angle"), r + "imu_angle_rad",
           "Angle of turn k about the IMU axis (right-handed)", shape=(MAX_TURNS,)),
        _p("rot_move", "s", _turn_column("move"), r + "move_s",
           "Duration of turn k (0 only for a rest)", shape=(MAX_TURNS,)),
        _p("rot_ramp", "s", _turn_column("ramp"), r + "ramp_s",
           "Acceleration and deceleration time of turn k (smooth), 2 ramp <= move",
           shape=(MAX_TURNS,)),
        _p("rot_dwell", "s", _turn_column("dwell"), r + "dwell_s", "Rest after turn k",
           shape=(MAX_TURNS,)),
    ]


def _aiding_parameters():
    """GNSS receiver, barometer, odometer (csrc/sim/gf_aiding.h; gfins_fmi.sim.vehicle's
    GnssReceiver, Barometer, Odometer .fmu_parameters() give them). All off by default."""
    g, b, o = "aiding.gnss.", "aiding.baro.", "aiding.odo."
    return [
        _p("gnss", None, 0, g + "enabled", "1: simulate a GNSS receiver (outputs gnss_*)",
           type_="Int32"),
        _p("gnss_rate", "Hz", 1.0, g + "rate_hz", "GNSS epoch rate, 0 < rate <= 1000 Hz"),
        _p("gnss_offset", "s", 0.0, g + "offset_s",
           "Epoch k is valid at start time + gnss_offset + k / gnss_rate, offset >= 0"),
        _p("gnss_latency", "s", 0.0, g + "latency_s",
           "An epoch valid at t is delivered at t + latency, >= 0 (latency x rate <= 14)"),
        _p("gnss_lever_arm", "m", 0.0, g + "lever_arm_m",
           "Antenna phase centre from the IMU, body right-front-up, |l| <= 100 m", shape=(3,)),
        _p("gnss_pos_std", "m", [1.0, 1.0, 2.0], g + "pos_std_m",
           "White position error std, east, north, up", shape=(3,)),
        _p("gnss_vel_std", "m/s", [0.05, 0.05, 0.1], g + "vel_std_m_s",
           "White velocity error std, east, north, up", shape=(3,)),
        _p("gnss_pos_gm_std", "m", 0.0, g + "pos_gm_std_m",
           "First-order Gauss-Markov position error, stationary std east, north, up",
           shape=(3,)),
        _p("gnss_pos_gm_tau", "s", 100.0, g + "pos_gm_tau_s",
           "Correlation time of the Gauss-Markov position error, > 0"),
        _p("gnss_q", None, 5, g + "quality", "Solution quality reported with every epoch "
           "(RTKLIB Q: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP, 0 unknown)",
           type_="Int32"),
        _p("gnss_n_outages", None, 0, g + "n_outages",
           f"Number of outage intervals used, 0 .. {MAX_OUTAGES}", type_="Int32"),
        _p("gnss_outage_start", "s", 0.0, g + "outage_start_s",
           "Outage intervals [start, end), absolute times: epochs valid inside are not "
           "delivered", shape=(MAX_OUTAGES,)),
        _p("gnss_outage_end", "s", 0.0, g + "outage_end_s", "Ends of the outage intervals "
           "(> start)", shape=(MAX_OUTAGES,)),
        _p("gnss_outage_first", "s", 0.0, g + "outage_first_s",
           "Periodic outages: start of the first (absolute time)"),
        _p("gnss_outage_period", "s", 0.0, g + "outage_period_s",
           "Periodic outages: one every period (> 0 when gnss_outage_duration > 0)"),
        _p("gnss_outage_duration", "s", 0.0, g + "outage_duration_s",
           "Periodic outages: length of each, 0 (none) .. period"),
        _p("baro", None, 0, b + "enabled", "1: simulate a barometer (outputs baro_*)",
           type_="Int32"),
        _p("baro_rate", "Hz", 10.0, b + "rate_hz", "Barometer rate, 0 < rate <= 1000 Hz"),
        _p("baro_offset", "s", 0.0, b + "offset_s",
           "Sample k at start time + baro_offset + k / baro_rate, >= 0"),
        _p("baro_std", "m", 0.5, b + "std_m", "White noise std of the barometric height"),
        _p("baro_bias0", "m", 0.0, b + "bias0_m", "Constant part of the barometer bias"),
        _p("baro_bias_rw", None, 0.0, b + "bias_rw_m_sqrt_s",
           "Random walk of the barometer bias, m/sqrt(s)"),
        _p("baro_bias_gm_std", "m", 0.0, b + "bias_gm_std_m",
           "Gauss-Markov part of the barometer bias, stationary std"),
        _p("baro_bias_gm_tau", "s", 100.0, b + "bias_gm_tau_s",
           "Correlation time of the Gauss-Markov bias, > 0"),
        _p("odo", None, 0, o + "enabled", "1: simulate an odometer (outputs odo_*)",
           type_="Int32"),
        _p("odo_rate", "Hz", 10.0, o + "rate_hz", "Odometer rate, 0 < rate <= 1000 Hz"),
        _p("odo_offset", "s", 0.0, o + "offset_s",
           "Sample k at start time + odo_offset + k / odo_rate, >= 0"),
        _p("odo_lever_arm", "m", 0.0, o + "lever_arm_m",
           "Wheel contact point from the IMU, body right-front-up, |l| <= 100 m", shape=(3,)),
        _p("odo_scale_error", None, 0.0, o + "scale_error",
           "Odometer scale-factor error k (measured = (1 + k) true + noise), |k| < 0.5"),
        _p("odo_std", "m/s", 0.05, o + "std_m_s", "White noise std of the odometer speed"),
    ]


def _aiding_outputs():
    g, b, o = "aiding_out.gnss.", "aiding_out.baro.", "aiding_out.odo."
    held = " (held between epochs; NaN before the first)"
    return [
        _out("gnss_valid", None, (), "aiding_out.gnss_new",
             "Number of GNSS epochs delivered by the last step (normally 0 or 1; more when "
             "a step spans several epochs: the gnss_* outputs show the newest)", type_="Int32"),
        _out("gnss_time_s", "s", (), g + "t_s", "Time of validity of the GNSS epoch" + held),
        _out("gnss_lat_rad", "rad", (), g + "lat_rad", "GNSS antenna latitude, measured" + held),
        _out("gnss_lon_rad", "rad", (), g + "lon_rad", "GNSS antenna longitude, measured" + held),
        _out("gnss_h_m", "m", (), g + "h_m", "GNSS antenna height, measured" + held),
        _out("gnss_vel_enu_m_s", "m/s", (3,), g + "vel_enu_m_s",
             "GNSS antenna velocity east, north, up, measured" + held),
        _out("gnss_pos_std_m", "m", (3,), g + "pos_std_m",
             "Reported position std east, north, up" + held),
        _out("gnss_vel_std_m_s", "m/s", (3,), g + "vel_std_m_s",
             "Reported velocity std east, north, up" + held),
        _out("gnss_quality", None, (), "aiding_out.gnss_quality",
             "Reported solution quality (RTKLIB Q; 0 before the first epoch)", type_="Int32"),
        _out("baro_valid", None, (), "aiding_out.baro_new",
             "Number of barometer samples delivered by the last step", type_="Int32"),
        _out("baro_time_s", "s", (), b + "t_s", "Time of the barometer sample" + held),
        _out("baro_h_m", "m", (), b + "h_m", "Barometric height (with bias and noise)" + held),
        _out("baro_std_m", "m", (), b + "std_m", "Reported barometer std" + held),
        _out("odo_valid", None, (), "aiding_out.odo_new",
             "Number of odometer samples delivered by the last step", type_="Int32"),
        _out("odo_time_s", "s", (), o + "t_s", "Time of the odometer sample" + held),
        _out("odo_speed_m_s", "m/s", (), o + "speed_m_s",
             "Odometer forward speed (with scale error and noise)" + held),
        _out("odo_std_m_s", "m/s", (), o + "std_m_s", "Reported odometer std" + held),
    ]


MODEL = dict(
    model_name="gfins.Vehicle",
    model_identifier="gfins_vehicle",
    description=(
        "Level ground vehicle on WGS-84 following a segment profile (speed, heading-rate "
        "and heading changes by C2 smooth steps; seed 001's vehicle test by default) or "
        "speed / heading-rate commands, with its true pose and the exact outputs of an "
        "IMU and an accelerometer array riding it, and optionally a GNSS receiver, a "
        "barometer and an odometer. The outputs after doStep(t, h) describe t + h; "
        "increments cover (t, t + h]; an aiding epoch is delivered in the first step "
        "whose end reaches its delivery time (gnss_valid, baro_valid, odo_valid count "
        "them)."),
    default_experiment=dict(start_time=0.0, stop_time=600.0, step_size=0.01),
    variables=[
        _p("lat0", "rad", 0.5235987755982988, "profile.lat0_rad", "Start latitude, |lat0| < 89 deg"),
        _p("lon0", "rad", 1.9896753472735356, "profile.lon0_rad", "Start longitude"),
        _p("h0", "m", 100.0, "profile.h0_m", "Height (constant), -1000 .. 1e5 m"),
        _p("heading0", "rad", 0.0, "profile.heading0_rad", "Start heading, clockwise from north"),
        _p("speed0", "m/s", 0.0, "profile.speed0_m_s", "Start speed, >= 0"),
        _p("heading_rate0", "rad/s", 0.0, "profile.heading_rate0_rad_s",
           "Start heading rate (clockwise positive; a circle: -speed/radius turns left)"),
        _p("n_segments", None, len(_DEFAULT), "n_segments",
           f"Number of profile segments used, 0 .. {MAX_SEGMENTS}", type_="Int32"),
        _p("seg_duration", "s", _column(0), "seg_duration_s", "Segment durations, > 0",
           shape=(MAX_SEGMENTS,)),
        _p("seg_dspeed", "m/s", _column(1), "seg_dspeed_m_s",
           "Speed change over each segment (smooth step)", shape=(MAX_SEGMENTS,)),
        _p("seg_dheading_rate", "rad/s", _column(2), "seg_dheading_rate_rad_s",
           "Heading-rate change over each segment (smooth step)", shape=(MAX_SEGMENTS,)),
        _p("seg_dheading", "rad", _column(3), "seg_dheading_rad",
           "Heading change over each segment on top of the rate (smooth step; pi: a 180 deg "
           "turn to the right)", shape=(MAX_SEGMENTS,)),
        _p("drive", None, 0, "drive", "0: follow the profile; 1: follow the inputs speed_cmd "
           "and heading_rate_cmd", type_="Int32"),
        _p("command_time", "s", 1.0, "command_time_s",
           "drive = 1: a new command is reached over this time from the step at which it "
           "changes (C2 smooth step from the current speed and heading rate), > 0"),
        _p("imu_errors", None, 0, "imu_errors", "1: the IMU outputs carry the error model "
           "below (applied to rates; to increments as mean rates over the step)", type_="Int32"),
        *_COMMON["imu_error_parameters"](),
        *_rotation_parameters(),
        _p("noise", None, 0, "noise", "1: add the random errors below to the IMU and array "
           "outputs after the start sample (ImuNoise.fmu_parameters() gives them)", type_="Int32"),
        _p("noise_seed", None, 1, "noise_seed", "Seed of the noise generators: IMU, array "
           "and the GNSS, barometer and odometer (the seed of simulate_vehicle)", type_="Int32"),
        # units with square roots have no FMI unit (integer exponents only): in the text
        _p("gyro_arw", None, 0.0, "noise_params.gyro_arw_rad_sqrt_s",
           "Gyro angle random walk N, rad/sqrt(s): rate noise std per sample N / sqrt(h)"),
        _p("gyro_bias_instability", "rad/s", 0.0, "noise_params.gyro_gm_std_rad_s",
           "Gyro Gauss-Markov bias, stationary std"),
        _p("gyro_correlation_time", "s", 100.0, "noise_params.gyro_gm_tau_s",
           "Correlation time of the gyro Gauss-Markov bias, > 0"),
        _p("gyro_rrw", None, 0.0, "noise_params.gyro_rrw_rad_s_sqrt_s",
           "Gyro rate random walk K, rad/s/sqrt(s): the bias wanders as K sqrt(t)"),
        _p("accel_vrw", None, 0.0, "noise_params.accel_asd_m_s2_sqrt_hz",
           "Accelerometer white noise, one-sided ASD (m/s2/sqrt(Hz)): std per sample ASD sqrt(1/(2h))"),
        _p("accel_bias_instability", "m/s2", 0.0, "noise_params.accel_gm_std_m_s2",
           "Accelerometer Gauss-Markov bias, stationary std"),
        _p("accel_correlation_time", "s", 100.0, "noise_params.accel_gm_tau_s",
           "Correlation time of the accelerometer Gauss-Markov bias, > 0"),
        _p("accel_rrw", None, 0.0, "noise_params.accel_rw_m_s2_sqrt_s",
           "Random walk of the accelerometer bias, m/s2/sqrt(s)"),
        _p("gyro_band", "rad/s", 0.0, "noise_params.gyro_band_std_rad_s",
           "Band-limited gyro noise std (first-order low-pass of corner band_hz)"),
        _p("accel_band", "m/s2", 0.0, "noise_params.accel_band_std_m_s2",
           "Band-limited accelerometer noise std"),
        _p("band_hz", "Hz", 1.0, "noise_params.band_hz", "Corner of the band-limited noise, > 0"),
        _p("array_noise", "m/s2", 0.0, "array_noise_m_s2",
           "White noise std per sample of each array accelerometer"),
        _p("array_layout", None, 1, "array_layout", "Accelerometer array: 0 cube6 (6 outputs), "
           "1 qin9 (9), 2 twelve (12); A holds the layout's outputs first, zeros after",
           type_="Int32"),
        _p("l", "m", 0.1, "lever_arm_m", "Lever arm of the array layout, >= 1e-6 m"),
        _p("array_bias", "m/s2", 0.0, "array_bias_m_s2", "Bias of each array accelerometer",
           shape=(12,)),
        *_aiding_parameters(),
        dict(name="speed_cmd", causality="input", variability="continuous", type="Float64",
             shape=(), unit="m/s", start=0.0, field="speed_cmd_m_s",
             description="drive = 1: commanded speed, >= 0"),
        dict(name="heading_rate_cmd", causality="input", variability="continuous",
             type="Float64", shape=(), unit="rad/s", start=0.0, field="heading_rate_cmd_rad_s",
             description="drive = 1: commanded heading rate (clockwise positive)"),
        _out("q", None, (4,), "out.q_bn", "True attitude quaternion q_b^n"),
        _out("euler", "rad", (3,), "out.euler_rad", "True heading [0, 2 pi), pitch, roll"),
        _out("v", "m/s", (3,), "out.v_n_m_s", "True velocity, East-North-Up"),
        _out("lat", "rad", (), "out.lat_rad", "True latitude"),
        _out("lon", "rad", (), "out.lon_rad", "True longitude"),
        _out("h", "m", (), "out.h_m", "True height"),
        _out("gyro_rate", "rad/s", (3,), "gyro_rad_s", "IMU angular rate w_ib^b (with errors "
             "when imu_errors = 1; rotation = 1: w_im^m of the turning IMU frame)"),
        _out("specific_force", "m/s2", (3,), "accel_m_s2", "IMU specific force f^b (rotation "
             "= 1: f^m)"),
        _out("dtheta", "rad", (3,), "dtheta_rad", "IMU angle increment over the last step"),
        _out("dv", "m/s", (3,), "dv_m_s", "IMU velocity increment over the last step"),
        _out("angular_accel", "rad/s2", (3,), "out.gyro_dot_rad_s2", "True d w_ib^b / dt"),
        _out("A", "m/s2", (12,), "A_m_s2", "Accelerometer-array outputs (layout array_layout)"),
        _out("time_s", "s", (), "out.time_s", "Time that the outputs describe"),
        _out("gimbal", "rad", (2,), "gimbal_rad", "rotation = 1: middle and inner gimbal angles "
             "(encoders), C_m^b = R_x(middle) R_z(inner); 0 for a turntable schedule"),
        _out("q_mb", None, (4,), "q_mb", "rotation = 1: IMU attitude on the base C_m^b "
             "(scalar first); 1, 0, 0, 0 otherwise"),
        *_aiding_outputs(),
    ],
)
