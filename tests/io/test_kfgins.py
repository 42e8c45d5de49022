"""The KF-GINS readers (gfins_fmi.io.kfgins): IMU text (comma separators, extra columns)
and binary files, GNSS files of 7 and 13 columns, the .nav truth, frames and units
converted at the door (front-right-down -> right-front-up, NED -> ENU), bad files named.
"""
from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import gfins_fmi as gf
from gfins_fmi.io import FileFormatError, read_kfgins_gnss, read_kfgins_imu, read_kfgins_nav
from gfins_fmi.io.conventions import rpy_frd_ned_to_euler_rfu_enu

EPS = np.finfo(float).eps
DEG = math.pi / 180


def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def dcm_kfgins(roll, pitch, yaw):
    """C_b^n of a forward-right-down body in north-east-down (KF-GINS's euler2matrix)."""
    return rz(yaw) @ ry(pitch) @ rx(roll)


def dcm_ours(heading, pitch, roll):
    """C_b^n of a right-front-up body in east-north-up (CONVENTIONS_AIDING, gf_sins.h)."""
    return rz(-heading) @ rx(pitch) @ ry(roll)


# axes of FRD as seen from RFU, and of NED from ENU, typed in: R = F's y, F = F's x, U = -D
FRD_TO_RFU = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]], float)


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(text, encoding="utf-8")
    return path


def test_kfgins_attitude_maps_to_ours_with_the_same_angles(rng):
    """C_b^n built both ways from random angles: KF-GINS's FRD/NED matrix, changed to
    RFU/ENU axes, equals ours from the converted angles (1e-15, round-off); and the C
    core extracts those same angles from it (1e-12: its atan2/asin of a matrix given to
    1e-16 — asin near +-90 deg pitch is avoided by the pitch range)."""
    n = 200
    roll = rng.uniform(-np.pi, np.pi, n)
    pitch = rng.uniform(-1.5, 1.5, n)
    yaw = rng.uniform(-np.pi, 2 * np.pi, n)        # both of KF-GINS's conventions for yaw
    eul = rpy_frd_ned_to_euler_rfu_enu(roll, pitch, yaw)
    assert np.all((eul[:, 0] >= 0) & (eul[:, 0] < 2 * np.pi))
    q = []
    for k in range(n):
        c_rfu_enu = FRD_TO_RFU @ dcm_kfgins(roll[k], pitch[k], yaw[k]) @ FRD_TO_RFU.T
        assert np.abs(c_rfu_enu - dcm_ours(*eul[k])).max() < 1e-15
        x, y, z, w = Rotation.from_matrix(c_rfu_enu).as_quat()
        q.append([w, x, y, z])
    core = gf.quat_to_euler(np.array(q))
    d = core - eul
    d[:, 0] = (d[:, 0] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(d).max() < 1e-12


KF_IMU = """456300.005   0.0001   0.0002  -0.0003   0.011   0.022   -0.049
456300.010   0.0004  -0.0005   0.0006   0.012  -0.023    0.048
"""


# the same samples in our axes, typed in: (y, x, -z) of each FRD triple
RFU_GYRO = [[0.0002, 0.0001, 0.0003], [-0.0005, 0.0004, -0.0006]]
RFU_ACCEL = [[0.022, 0.011, 0.049], [-0.023, 0.012, -0.048]]


def test_kfgins_imu_text_comma_extra_columns_and_binary(tmp_path):
    for name, text, kw in [("a.txt", KF_IMU, {}),
                           ("b.txt", KF_IMU.replace("   ", ", ").replace("  ", ","), {}),  # commas
                           ("c.txt", KF_IMU.replace("\n", "  1.5\n"), {"n_columns": 8})]:
        r = read_kfgins_imu(write(tmp_path / name, text), **kw)
        assert r.kind == "increments" and "FRD -> RFU" in r.source
        np.testing.assert_array_equal(r.t_s, [456300.005, 456300.010])
        np.testing.assert_array_equal(r.gyro, RFU_GYRO)              # a permutation: exact
        np.testing.assert_array_equal(r.accel, RFU_ACCEL)
    raw = np.loadtxt(tmp_path / "a.txt")
    raw.astype("<f8").tofile(tmp_path / "d.bin")
    b = read_kfgins_imu(tmp_path / "d.bin", gps_week=2200)
    np.testing.assert_array_equal(b.t_s, 2200 * 604800 + raw[:, 0])
    np.testing.assert_array_equal(b.gyro, RFU_GYRO)
    (tmp_path / "e.bin").write_bytes(b"\0" * 60)
    with pytest.raises(FileFormatError, match="60 bytes is not a whole number of 56-byte samples"):
        read_kfgins_imu(tmp_path / "e.bin")


@pytest.mark.parametrize("text, match", [
    ("", r"a.txt: no data lines: the file is empty"),
    ("time gx gy gz ax ay az\n" + KF_IMU, r"a.txt:1: KF-GINS IMU files have no header line, but the "
     r"first line holds text \('time'\): delete that line"),
    (KF_IMU + "456300.015 0.1 0.2 0.3 0.4 0.5\n", r"a.txt:3: 6 columns where a KF-GINS IMU line has 7"),
    (KF_IMU.replace("0.012", "0.0x2"), r"a.txt:2: '0.0x2' is not a number"),
    (KF_IMU + "456300.010 0 0 0 0 0 0\n", r"a.txt:3: t_s must be strictly increasing: t_s\[2\] "
     r"= 456300.01 s repeats"),
    (KF_IMU.replace("0.0004", "nan"), r"a.txt:2: gyro\[1, 1\] = nan is not finite"),
])
def test_kfgins_imu_bad_files(tmp_path, text, match):
    with pytest.raises(FileFormatError, match=match):
        read_kfgins_imu(write(tmp_path / "a.txt", text))


def test_kfgins_gnss_7_and_13_columns(tmp_path):
    r = read_kfgins_gnss(write(tmp_path / "g.txt",
                               "456250.000    30.4447858054   114.4718661162     21.095    0.010    0.009    0.019\n"
                               "456251.000    30.4447857891   114.4718661133     21.091    0.011    0.008    0.018\n"))
    np.testing.assert_allclose(r.lat_rad, [math.radians(30.4447858054), math.radians(30.4447857891)],
                               rtol=2 * EPS)                          # deg -> rad: 1 ulp
    np.testing.assert_allclose(r.lon_rad[0], math.radians(114.4718661162), rtol=2 * EPS)
    np.testing.assert_array_equal(r.h_m, [21.095, 21.091])
    np.testing.assert_array_equal(r.pos_std_m, [[0.009, 0.010, 0.019], [0.008, 0.011, 0.018]])  # E, N, U
    assert not r.has_velocity and r.quality_counts() == {"unknown": 2}
    v = read_kfgins_gnss(write(tmp_path / "v.txt", "116454.0 30.5 114.3 21.0 0.1 0.2 0.3 "
                                                  "1.5 -2.5 0.5 0.01 0.02 0.03\n"))
    np.testing.assert_array_equal(v.vel_enu_m_s, [[-2.5, 1.5, -0.5]])   # (E, N, -D)
    np.testing.assert_array_equal(v.vel_std_m_s, [[0.02, 0.01, 0.03]])
    w = read_kfgins_gnss(write(tmp_path / "w.txt", "116454.0 0.5 2.0 21.0 0.1 0.2 0.3\n"), angles="rad")
    assert (w.lat_rad[0], w.lon_rad[0]) == (0.5, 2.0)
    with pytest.raises(FileFormatError, match=r"w.txt:1: 5 columns where a KF-GINS GNSS line has 7 or 13"):
        read_kfgins_gnss(write(tmp_path / "w.txt", "116454.0 0.5 2.0 21.0 0.1\n"))
    with pytest.raises(FileFormatError, match=r"pos_std_m\[0, 0\] = 0.0 m"):
        read_kfgins_gnss(write(tmp_path / "z.txt", "116454.0 30 114 21.0 0.2 0.0 0.3\n"))   # east


def test_kfgins_nav_truth(tmp_path):
    """Velocity (E, N, -D); attitude: the DCM of the read angles equals the KF-GINS
    DCM of the file's angles in RFU/ENU axes (1e-15, round-off)."""
    r = read_kfgins_nav(write(tmp_path / "t.nav",
                              "2019 456300.000 30.4447873701 114.4718632047 20.899 1.0 2.0 3.0 10.0 -5.0 -30.0\n"
                              "2019 456300.005 30.4447873702 114.4718632048 20.898 1.1 2.1 3.1 10.5 -5.5 185.7\n"))
    np.testing.assert_array_equal(r.v_enu_m_s, [[2.0, 1.0, -3.0], [2.1, 1.1, -3.1]])
    np.testing.assert_allclose(r.euler_rad[0], [330 * DEG, -5 * DEG, 10 * DEG], rtol=4 * EPS)
    for k, (roll, pitch, yaw) in enumerate([(10.0, -5.0, -30.0), (10.5, -5.5, 185.7)]):
        kf = FRD_TO_RFU @ dcm_kfgins(roll * DEG, pitch * DEG, yaw * DEG) @ FRD_TO_RFU.T
        assert np.abs(kf - dcm_ours(*r.euler_rad[k])).max() < 1e-15
    assert "GPS week 2019" in r.source
    with pytest.raises(FileFormatError, match=r"t2.nav:2: the GPS week changes from 2019 to 2020"):
        read_kfgins_nav(write(tmp_path / "t2.nav",
                              "2019 604799.0 30 114 20 0 0 0 0 0 0\n2020 0.5 30 114 20 0 0 0 0 0 0\n"))


def test_kfgins_arguments_and_files_at_their_limits(tmp_path):
    """gps_week: 0 (the GPS epoch's week) is a week, -1, True and 2.5 are not; n_columns:
    7 and more, not 6, True or 7.0; an empty .bin is refused like a truncated one; a text
    file whose suffix sorts before '.bin' ('.asc') is text."""
    path = write(tmp_path / "a.txt", KF_IMU)
    np.testing.assert_array_equal(read_kfgins_imu(path, gps_week=0).t_s, [456300.005, 456300.010])
    for bad in (-1, True, 2.5):
        with pytest.raises(ValueError, match="gps_week must be a non-negative integer"):
            read_kfgins_imu(path, gps_week=bad)
    for bad in (6, True, 7.0):
        with pytest.raises(ValueError, match="n_columns must be an integer >= 7"):
            read_kfgins_imu(path, n_columns=bad)
    (tmp_path / "z.bin").write_bytes(b"")
    with pytest.raises(FileFormatError, match="0 bytes is not a whole number of 56-byte samples"):
        read_kfgins_imu(tmp_path / "z.bin")
    asc = read_kfgins_imu(write(tmp_path / "a.asc", KF_IMU))
    np.testing.assert_array_equal(asc.gyro, RFU_GYRO)


def test_kfgins_nav_position_columns_and_week_changes(tmp_path):
    """Latitude, longitude and height from their own columns (values all different); a
    week that changes back (2020, then 2019) is refused too, at the first line that
    differs from the first week."""
    r = read_kfgins_nav(write(tmp_path / "t.nav", "2019 456300.0 30.5 114.25 20.75 1.25 -2.5 0.375 "
                                                  "10.0 -5.0 -30.0\n"))
    np.testing.assert_allclose([r.lat_rad[0], r.lon_rad[0]], np.radians([30.5, 114.25]), rtol=2 * EPS)
    assert r.h_m[0] == 20.75 and r.t_s[0] == 456300.0      # the seconds of week, column 2
    with pytest.raises(FileFormatError, match=r"b.nav:2: the GPS week changes from 2020 to 2019"):
        read_kfgins_nav(write(tmp_path / "b.nav", "2020 0.5 30 114 20 0 0 0 0 0 0\n"
                                                  "2019 604799.0 30 114 20 0 0 0 0 0 0\n"))
    with pytest.raises(FileFormatError, match=r"c.nav:2: the GPS week changes from 2019 to 2020"):
        read_kfgins_nav(write(tmp_path / "c.nav", "2019 604799.0 30 114 20 0 0 0 0 0 0\n"
                                                  "2020 0.5 30 114 20 0 0 0 0 0 0\n"
                                                  "2021 0.6 30 114 20 0 0 0 0 0 0\n"))
