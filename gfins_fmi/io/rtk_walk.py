"""The rtk_walk recording: a handheld consumer GNSS receiver and MEMS IMU carried while
walking (rtklibexplorer/GNSS_IMU, data/walk_0827; ``shared/data/rtk_walk`` and its
README).

IMU file (``imu_1730_sf.csv``): comma-separated, no header, 11 columns: time (s, the GPS
time scale counted from 1970-01-01 on the calendar, no leap seconds), specific force
x, y, z (g), angular rate x, y, z (rad/s), four unused columns; sensor axes; sampling
not uniform (6 ms mostly, 9 ms between some samples). GNSS file (``gnss_1730_sf.pos``):
RTKLIB, GPST calendar times, with velocities (:func:`~gfins_fmi.io.read_rtklib_pos`).
"""
from __future__ import annotations

import math
import pathlib

import numpy as np

from gfins_fmi.io._text import read_table, record_errors_at_lines
from gfins_fmi.io.conventions import GPS_EPOCH_FROM_1970_S, P_SWAP
from gfins_fmi.io.errors import FileFormatError
from gfins_fmi.io.records import GnssRecord, ImuRecord
from gfins_fmi.io.rtklib import read_rtklib_pos

__all__ = ["read_rtk_walk_imu", "load_rtk_walk", "rtk_walk_mounting", "mounting_from_rpy",
           "STANDARD_GRAVITY_M_S2"]

#: the unit g of the accelerometer (standard gravity, m/s^2)
STANDARD_GRAVITY_M_S2 = 9.80665


def mounting_from_rpy(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """Sensor-to-body rotation C_s^b (body right-front-up) from mounting angles in the
    convention of rtklibexplorer/GNSS_IMU (Groves' ``Euler_to_CTM``): the source maps
    sensor vectors to its forward-right-down body by
    ``C = (Rz(yaw) Ry(pitch) Rx(roll))^T``, then C_s^b = P_SWAP C (FRD -> RFU).

    Entries within 1e-15 of 0 or +-1 are set to it exactly: at multiples of 90 deg
    floating point cannot give the sines and cosines exactly (sin(pi) = 1.2e-16), and a
    mounting of 90-deg steps should permute axes without mixing them.

    Returns
    -------
    ndarray (3, 3)
        f_body_RFU = C_s^b @ f_sensor.
    """
    cr, sr = math.cos(roll_rad), math.sin(roll_rad)
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    c = P_SWAP @ (rz @ ry @ rx).T
    for exact in (-1.0, 0.0, 1.0):
        c[np.abs(c - exact) < 1e-15] = exact
    return c


def rtk_walk_mounting() -> np.ndarray:
    """C_s^b of the rtk_walk recording: the source's IMU orientation roll, pitch, yaw =
    180 deg, 0 deg, -90 deg (its walk_config.py) through :func:`mounting_from_rpy`.

    The source's matrix for these angles is [[0, -1, 0], [-1, 0, 0], [0, 0, -1]]
    (sensor -> forward-right-down), symmetric, so reading the angles as the sensor in
    the body or the body in the sensor gives the same rotation. In right-front-up it is
    diag(-1, -1, 1): right = -x_s, forward = -y_s, up = +z_s, a half turn
    about the sensor's z axis. The data agree (tests/io/test_rtk_walk.py): at rest the specific
    force points up (+9.9 m/s^2), and in the walk's turns the lateral specific force has
    the sign of the centripetal acceleration.
    """
    return mounting_from_rpy(math.pi, 0.0, -math.pi / 2)


def _check_mounting(mounting) -> np.ndarray:
    c = np.asarray(mounting, dtype=np.float64)
    if c.shape != (3, 3) or not np.all(np.isfinite(c)):
        raise ValueError(f"mounting must be a finite 3x3 rotation matrix C_s^b (sensor -> body "
                         f"RFU); got shape {c.shape}")
    err = np.abs(c @ c.T - np.eye(3)).max()
    if err > 1e-9 or np.linalg.det(c) < 0:
        raise ValueError(f"mounting must be a rotation (orthonormal, determinant +1); got "
                         f"|C C^T - I| = {err:.3g}, det = {np.linalg.det(c):.6g} (a determinant "
                         "of -1 swaps handedness: one axis has the wrong sign)")
    return c


def read_rtk_walk_imu(path, mounting, g_m_s2: float = STANDARD_GRAVITY_M_S2) -> ImuRecord:
    """Read the rtk_walk IMU CSV.

    Parameters
    ----------
    path : str or path-like
        ``imu_1730_sf.csv``.
    mounting : array_like (3, 3)
        C_s^b, sensor axes -> body right-front-up: f_b = C_s^b f_s, w_b = C_s^b w_s
        (for this recording: :func:`rtk_walk_mounting`).
    g_m_s2 : float
        The accelerometer's unit g in m/s^2 (default standard gravity 9.80665; the
        source's own filter multiplied by its local normal gravity instead, 0.1 % less).

    Returns
    -------
    ImuRecord
        ``kind="rates"``: gyro rad/s, accel m/s^2 (specific force), body RFU; times in
        GPS seconds since 1980-01-06 (file time - 315964800 s, the days from 1970-01-01
        to 1980-01-06): the scale of :func:`~gfins_fmi.io.read_rtklib_pos`.
    """
    path = pathlib.Path(path)
    c = _check_mounting(mounting)
    g = float(g_m_s2)
    if not (math.isfinite(g) and 9.7 < g < 9.9):
        raise ValueError(f"g_m_s2 must be the value of g in m/s^2 (about 9.8); got {g_m_s2!r}")
    table, line_of = read_table(path, [11], "rtk_walk IMU CSV", delimiter=",")
    with record_errors_at_lines(path, line_of):
        return ImuRecord(table[:, 0] - GPS_EPOCH_FROM_1970_S, (table[:, 4:7] @ c.T),
                         (table[:, 1:4] * g) @ c.T, "rates",
                         f"rtk_walk IMU file {path.name}: g -> m/s^2 (x {g}), sensor -> RFU by "
                         f"C_s^b = {(c + 0.0).tolist()}, GPST from 1970 -> GPS seconds")


def load_rtk_walk(directory, mounting=None, imu_file: str = "imu_1730_sf.csv",
                  gnss_file: str = "gnss_1730_sf.pos") -> tuple[ImuRecord, GnssRecord]:
    """Load the rtk_walk recording: IMU rates in body right-front-up and the RTKLIB
    solutions, both in GPS seconds since 1980-01-06 (both files are GPST: the IMU's
    first sample, 2025-08-28 17:30:40.961, falls 1.2 s after the first GNSS epoch,
    17:30:39.749, not 18 s off as a UTC/GPST mix would be).

    Parameters
    ----------
    directory : str or path-like
        The folder holding the two files (``shared/data/rtk_walk``).
    mounting : array_like (3, 3), optional
        C_s^b; default :func:`rtk_walk_mounting`, the source's configuration.
    imu_file, gnss_file : str
        File names inside ``directory``.

    Returns
    -------
    (ImuRecord, GnssRecord)
    """
    directory = pathlib.Path(directory)
    if not directory.is_dir():
        raise FileNotFoundError(f"{directory}: no such folder (the rtk_walk data folder, "
                                "shared/data/rtk_walk, was expected)")
    imu = read_rtk_walk_imu(directory / imu_file, rtk_walk_mounting() if mounting is None else mounting)
    gnss = read_rtklib_pos(directory / gnss_file)
    if imu.t_s[0] > gnss.t_s[-1] or gnss.t_s[0] > imu.t_s[-1]:
        raise FileFormatError(directory, None, f"the IMU ([{imu.t_s[0]:.17g}, {imu.t_s[-1]:.17g}] s) "
                              f"and GNSS ([{gnss.t_s[0]:.17g}, {gnss.t_s[-1]:.17g}] s) records do "
                              "not overlap: not the same recording, or not the same time scale")
    return imu, gnss
