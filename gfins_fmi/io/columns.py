"""The column vocabulary of the solution tables the commands write (CSV, Parquet, npz):
every name said once here, with its unit in the name, and used by every writer and
reader of those tables.

The navigation solution (geodetic position: the commands navigate on WGS-84) is
:data:`NAV_SOLUTION`; the strapdown and gyro-free commands add the attitude quaternion
(:data:`NAV_COLUMNS`), the gyro-free one its solved rates (:data:`RATE_COLUMNS`); the
integrated navigator adds the 1-sigma of velocity, position and attitude
(:data:`STD_COLUMNS`) and its sensor-error estimates (named by the filter:
``gfins_fmi.estimation.SENSOR_NAMES``; :func:`integrated_columns`).
"""
from __future__ import annotations

__all__ = ["TIME", "POSITION_DEG", "VELOCITY_ENU", "EULER_DEG", "QUATERNION", "NAV_SOLUTION",
           "NAV_COLUMNS", "RATE_COLUMNS", "ACCEL9_COLUMNS", "STD_COLUMNS", "integrated_columns",
           "INNOVATION_COLUMNS", "ALIGNMENT_PASS_COLUMNS", "TRANSFER_COLUMNS"]

#: time of the row, s
TIME = ("t_s",)
#: latitude, longitude (deg) and height (m)
POSITION_DEG = ("lat_deg", "lon_deg", "h_m")
#: velocity east, north, up (m/s)
VELOCITY_ENU = ("v_e_m_s", "v_n_m_s", "v_u_m_s")
#: heading (clockwise from north), pitch, roll (deg)
EULER_DEG = ("heading_deg", "pitch_deg", "roll_deg")
#: the attitude quaternion q_b^n, scalar first
QUATERNION = ("q0", "q1", "q2", "q3")
#: the navigation solution: time, position, velocity, attitude
NAV_SOLUTION = TIME + POSITION_DEG + VELOCITY_ENU + EULER_DEG
#: ``gfins navigate`` and the first columns of ``gfins gfnav``
NAV_COLUMNS = NAV_SOLUTION + QUATERNION
#: what ``gfins gfnav`` adds: the solved rate (rad/s), specific force (m/s^2), flags
RATE_COLUMNS = ("omega_x_rad_s", "omega_y_rad_s", "omega_z_rad_s", "f_x_m_s2", "f_y_m_s2",
                "f_z_m_s2", "flags")
#: ``gfins solve9``: the 9-accelerometer solution
ACCEL9_COLUMNS = ("t_s", "f_x_m_s2", "f_y_m_s2", "f_z_m_s2", "omega_x_rad_s", "omega_y_rad_s",
                  "omega_z_rad_s", "omega_dot_x_rad_s2", "omega_dot_y_rad_s2", "omega_dot_z_rad_s2",
                  "omega_sq_x_rad2_s2", "omega_sq_y_rad2_s2", "omega_sq_z_rad2_s2", "flags")
#: 1-sigma of velocity (m/s), position east, north, up (m) and attitude (deg)
STD_COLUMNS = ("std_v_e_m_s", "std_v_n_m_s", "std_v_u_m_s", "std_e_m", "std_n_m", "std_u_m",
               "std_att_e_deg", "std_att_n_deg", "std_att_u_deg")
#: ``gfins integrate``'s innovation log: kind and status by name (text columns)
INNOVATION_COLUMNS = ("t_s", "kind", "status", "m", "nis", "r0", "r1", "r2", "s0", "s1", "s2")
#: ``gfins align motion --output``: the state after each forward or backward pass
ALIGNMENT_PASS_COLUMNS = ("t_s", "direction") + EULER_DEG + STD_COLUMNS[6:] + ("n_updates",
                                                                                "n_rejected")


#: ``gfins align transfer --output``: the estimates over time with their 1-sigma (NaN for
#: what is not estimated): mounting (deg), lever arm (m, master axes), time offset (s),
#: gyro (deg/h) and accelerometer (mg) biases, the slave's attitude (deg) and its 1-sigma
TRANSFER_COLUMNS = (("t_s", "mount_heading_deg", "mount_pitch_deg", "mount_roll_deg", "std_mount_heading_deg",
                     "std_mount_pitch_deg", "std_mount_roll_deg", "lever_x_m", "lever_y_m", "lever_z_m",
                     "std_lever_x_m", "std_lever_y_m", "std_lever_z_m", "time_offset_s", "std_time_offset_s",
                     "bg_x_deg_h", "bg_y_deg_h", "bg_z_deg_h", "std_bg_x_deg_h", "std_bg_y_deg_h", "std_bg_z_deg_h",
                     "ba_x_mg", "ba_y_mg", "ba_z_mg", "std_ba_x_mg", "std_ba_y_mg", "std_ba_z_mg")
                    + EULER_DEG + STD_COLUMNS[6:])


def integrated_columns(sensor_names) -> tuple:
    """``gfins integrate``'s solution: the navigation solution, its 1-sigma and the
    filter's sensor-error estimates (``sensor_names``, in the filter's order)."""
    return NAV_SOLUTION + STD_COLUMNS + tuple(sensor_names)
