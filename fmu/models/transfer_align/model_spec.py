"""Interface of the transfer-alignment FMU (issue 24): the slave IMU's filter of the C core
(csrc/est/gf_ins_gnss.h with the transfer-alignment states and the master kinds, "Transfer
alignment") fed by the slave's IMU samples and a master INS's navigation outputs (its
attitude, velocity, position and angular rate), so that a host model, its master INS and
the slave co-simulate. The one place its variables are listed; fmu/tools/fmugen.py makes
the FMI 2.0 and 3.0 modelDescription.xml and the C table from it. The filter's parameters
are the settings table's FMU rows, the transfer-alignment ones included
(gfins_fmi/estimation/settings.py); their defaults equal FilterConfig's."""

import math
import pathlib
import runpy

_COMMON = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "common" / "nav_params.py"))
_p = _COMMON["parameter"]
_in = _COMMON["model_input"]
_out = _COMMON["model_output"]
_SETTINGS = runpy.run_path(str(pathlib.Path(__file__).resolve().parents[3] / "gfins_fmi" /
                               "estimation" / "settings.py"))
_GYRO_BIAS = _SETTINGS["FMU_IMU_NOISE"]["gyro_bias_std_rad_s"]
_ACCEL_BIAS = _SETTINGS["FMU_IMU_NOISE"]["accel_bias_std_m_s2"]
_NAN = float("nan")


def _filter_parameters():
    """One parameter per FMU row of the settings table (the transfer rows included)."""
    out = []
    for st in _SETTINGS["fmu_settings"](transfer=True):
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
           "rad/s, accelerometer bias 3 m/s2, gyro scale 3, accelerometer scale 3, barometer "
           "bias m, odometer scale, odometer boresight pitch and heading rad)", shape=(16,)),
        _p("std0_vel", "m/s", 0.1, "std0_vel_m_s", "Initial 1-sigma of the velocity, east, north, up, > 0",
           shape=(3,)),
        _p("std0_pos", "m", 1.0, "std0_pos_m", "Initial 1-sigma of the position, east, north, up, > 0",
           shape=(3,)),
        _p("std0_att", "rad", 1e-3, "std0_att_rad", "Initial 1-sigma of the attitude error (east, north "
           "tilt; up: heading), > 0: with start_from_master = 1 and master_mount = 1 beyond the "
           "mounting's (the master's own attitude error)", shape=(3,)),
        _p("std0_gyro_bias", "rad/s", _GYRO_BIAS, "std0_gyro_bias_rad_s", "Initial 1-sigma of the gyro biases, > 0",
           shape=(3,)),
        _p("std0_accel_bias", "m/s2", _ACCEL_BIAS, "std0_accel_bias_m_s2",
           "Initial 1-sigma of the accelerometer biases, > 0", shape=(3,)),
        _p("std0_gyro_scale", None, 1e-3, "std0_gyro_scale", "Initial 1-sigma of the gyro scale factors "
           "(scale_factors = 1), > 0", shape=(3,)),
        _p("std0_accel_scale", None, 1e-3, "std0_accel_scale", "Initial 1-sigma of the accelerometer scale "
           "factors (scale_factors = 1), > 0", shape=(3,)),
        _p("std0_mount", "rad", 0.02, "std0_mount_rad", "Initial 1-sigma of the mounting heading, pitch, "
           "roll (master_mount = 1), > 0", shape=(3,)),
        _p("std0_lever", "m", 0.1, "std0_lever_m", "Initial 1-sigma of the lever arm x, y, z "
           "(master_lever = 1), > 0", shape=(3,)),
        _p("std0_time_offset", "s", 0.02, "std0_time_offset_s", "Initial 1-sigma of the time offset "
           "(master_time_offset = 1), > 0"),
    ]


_HELD = " (when master_valid > 0; not read otherwise)"


def _master_inputs():
    return [
        _in("master_valid", None, 0, "master_valid", "> 0: a master epoch was delivered with this "
            "step (the master_* inputs hold it)", "Int32"),
        _in("master_time_s", "s", _NAN, "master_time_s", "The master epoch's time, on the master's "
            "clock (the simulation time scale)" + _HELD),
        _in("master_euler", "rad", _NAN, "master_euler_rad", "The master's heading (clockwise from "
            "north), pitch, roll" + _HELD, shape=(3,)),
        _in("master_vel", "m/s", _NAN, "master_vel_m_s", "The master IMU's velocity, east, north, "
            "up" + _HELD, shape=(3,)),
        _in("master_lat", "rad", _NAN, "master_lat_rad", "The master IMU's latitude" + _HELD),
        _in("master_lon", "rad", _NAN, "master_lon_rad", "The master IMU's longitude" + _HELD),
        _in("master_h", "m", _NAN, "master_h_m", "The master IMU's height" + _HELD),
        _in("master_rate", "rad/s", _NAN, "master_rate_rad_s", "The master's angular rate w_im^m, "
            "master axes" + _HELD, shape=(3,)),
    ]


def _outputs():
    kinds = " per master kind (velocity, attitude, position)"
    return [
        _out("q", None, (4,), "q_bn", "The slave's attitude quaternion q_b^n"),
        _out("euler", "rad", (3,), "euler_rad", "The slave's heading [0, 2 pi), pitch, roll"),
        _out("v", "m/s", (3,), "v_n_m_s", "The slave's velocity, East-North-Up"),
        _out("lat", "rad", (), "lat_rad", "The slave's latitude"),
        _out("lon", "rad", (), "lon_rad", "The slave's longitude"),
        _out("h", "m", (), "h_m", "The slave's height"),
        _out("time_s", "s", (), "nav_time_s", "Time that the outputs describe (slave clock)"),
        _out("std", None, (9,), "std9", "1-sigma: velocity east, north, up (m/s), position east, "
             "north, up (m), attitude east, north, up (rad)"),
        _out("sensors", None, (16,), "sensors", "Sensor-error estimates (as gfins_ins_gnss's)"),
        _out("mount", "rad", (3,), "mount_rad", "The mounting: heading, pitch, roll of the slave's "
             "axes in the master's (master_mount_rad + the estimate)"),
        _out("mount_std", "rad", (3,), "mount_std_rad", "Its 1-sigma (NaN when not estimated)"),
        _out("lever", "m", (3,), "lever_m", "The lever arm: the slave IMU from the master's, master "
             "axes (master_lever_arm_m + the estimate)"),
        _out("lever_std", "m", (3,), "lever_std_m", "Its 1-sigma (NaN when not estimated)"),
        _out("time_offset", "s", (), "time_offset_s", "The time offset, slave stamp - master stamp "
             "(master_time_offset_s + the estimate)"),
        _out("time_offset_std", "s", (), "time_offset_std_s", "Its 1-sigma (NaN when not estimated)"),
        _out("flexure_angles", "rad", (3,), "flexure_rad", "The flexure angles' estimate (flexure = 1)"),
        _out("n_imu", None, (), "n_imu", "IMU samples processed", "Int32"),
        _out("n_updates", None, (), "n_updates", "Updates accepted", "Int32"),
        _out("n_rejected", None, (), "n_rejected", "Updates rejected (gate, singular, stale)", "Int32"),
        _out("nis", None, (3,), "nis", "NIS of the last update" + kinds + "; NaN before the first"),
        _out("update_status", None, (3,), "update_status", "Outcome of the last update" + kinds +
             ": -1 none yet, 0 accepted, 1 gate, 2 singular, 3 stale", "Int32"),
        _out("update_count", None, (3,), "update_count", "Updates so far" + kinds, "Int32"),
    ]


MODEL = dict(
    model_name="gfins.TransferAlignment",
    model_identifier="gfins_transfer_align",
    description=(
        "Transfer alignment: the slave IMU's error-state filter (EKF or UKF, gf_ins_gnss) aligned "
        "and calibrated in motion against a master INS - its attitude, biases, mounting on the "
        "host, the lever arm to the master and the time offset between the two streams - from the "
        "master's velocity (with match_attitude its attitude, with match_position its position) "
        "and angular rate. doStep(t, h) takes the slave's IMU sample set at t (an increment covers "
        "the interval since the previous sample; at the start time there is none) and the master "
        "epoch delivered with it (time on the master's clock, inside the sample's interval; "
        "earlier ones are stale). The outputs after the step describe t."),
    default_experiment=dict(start_time=0.0, stop_time=100.0, step_size=0.01),
    variables=[
        *_filter_parameters(),
        *_COMMON["initial_state"](),
        *_initial_uncertainty(),
        _COMMON["skip_steps"](),
        _p("start_from_master", None, 1, "start_from_master", "1: q0 is the master's attitude "
           "turned by master_mount_rad, so the slave's attitude error starts as the mounting's: "
           "with master_mount = 1 their errors start correlated (gf_ins_master_start_covariance) "
           "and std0_att is the uncertainty beyond the mounting's; 0: independent", "Int32"),
        _p("match_attitude", None, 1, "match_attitude", "1: the master's attitude is matched too "
           "(velocity + attitude); 0: its velocity only", "Int32"),
        _p("match_position", None, 0, "match_position", "1: the master's position is matched too",
           "Int32"),
        _p("master_interval", "s", 0.0, "master_interval_s", "A master epoch less than this after "
           "the last one used is left out (0: every epoch delivered is used): a master INS FMU "
           "that outputs every step gives 10 Hz epochs with 0.1, >= 0"),
        _p("master_vel_std", "m/s", 0.02, "master_vel_std_m_s", "The master's velocity error as "
           "measurement noise, east, north, up, > 0", shape=(3,)),
        _p("master_att_std", "rad", [1e-4, 1e-4, 3e-4], "master_att_std_rad", "The master's attitude "
           "error as measurement noise, east, north, up (small angles), > 0", shape=(3,)),
        _p("master_pos_std", "m", 1.0, "master_pos_std_m", "The master's position error as "
           "measurement noise, east, north, up, > 0", shape=(3,)),
        *_COMMON["imu_inputs"](),
        *_master_inputs(),
        *_outputs(),
    ],
    c_extra=_COMMON["refusal_table"](_SETTINGS["fmu_settings"](transfer=True)),
)
