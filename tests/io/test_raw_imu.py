"""The raw 7-column IMU reader (gfins_fmi.io.read_raw_imu): layouts, units, columns,
refusals. Truth: the arrays written here, converted by the unit definitions (1 deg =
pi/180 rad, 1 g = 9.80665 m/s^2)."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.io import FileFormatError, read_raw_imu

RNG = np.random.default_rng(71)
N = 50
T = np.arange(1, N + 1) * 0.01
W = RNG.normal(0, 1e-3, (N, 3))
A = RNG.normal(0, 1e-2, (N, 3)) + [0, 0, 0.098]


def test_binary_layouts(tmp_path):
    """float64 (.bin) exact; float32 (.f32 or layout="float32") to its rounding (6e-8)."""
    tab = np.c_[W, A, T]
    tab.astype("<f8").tofile(tmp_path / "r.bin")
    r = read_raw_imu(tmp_path / "r.bin")
    assert r.kind == "increments"
    np.testing.assert_array_equal(r.gyro, W)
    np.testing.assert_array_equal(r.accel, A)
    np.testing.assert_array_equal(r.t_s, T)
    tab.astype("<f4").tofile(tmp_path / "r.f32")
    r = read_raw_imu(tmp_path / "r.f32")
    np.testing.assert_allclose(r.gyro, W, rtol=6e-8)


def test_text_units_and_columns(tmp_path):
    """Text with comments (# and %), commas, rates in deg/h and g, time in ms, another
    column order."""
    lines = ["% PSINS-style record", "# t wx wy wz ax ay az"]
    for k in range(N):
        vals = [T[k] * 1e3, *(W[k] / (np.pi / 180 / 3600)), *(A[k] / 9.80665)]
        lines.append(", ".join(repr(float(v)) for v in vals) + "  # sample")
    (tmp_path / "r.txt").write_text("\n".join(lines) + "\n")
    r = read_raw_imu(tmp_path / "r.txt", kind="rates", gyro_unit="deg/h", accel_unit="g",
                     time_scale_s=1e-3, columns=("t", "wx", "wy", "wz", "ax", "ay", "az"))
    assert r.kind == "rates"
    np.testing.assert_allclose(r.gyro, W, rtol=1e-14)
    np.testing.assert_allclose(r.accel, A, rtol=1e-14)
    np.testing.assert_allclose(r.t_s, T, rtol=1e-14)


def test_refusals(tmp_path):
    """A size that is not whole samples (with the other width named when it fits), an
    implausible interval (the wrong width with an even count), a line of 6 columns, a NaN,
    deg/h with increments, a bad column list."""
    np.zeros(7 * 3, "<f4").tofile(tmp_path / "odd.bin")          # 84 bytes: 3 float32 samples
    with pytest.raises(FileFormatError, match="float32"):
        read_raw_imu(tmp_path / "odd.bin")
    np.c_[W, A, T].astype("<f4").tofile(tmp_path / "even.bin")   # 50 float32 samples read as 25 float64
    with pytest.raises(FileFormatError, match="median sample interval"):
        read_raw_imu(tmp_path / "even.bin")
    (tmp_path / "six.txt").write_text("1 2 3 4 5 6 0.01\n1 2 3 4 5 0.02\n")
    with pytest.raises(FileFormatError, match="six.txt"):
        read_raw_imu(tmp_path / "six.txt")
    (tmp_path / "nan.txt").write_text("0 0 0 0 0 0.098 0.01\n0 nan 0 0 0 0.098 0.02\n")
    with pytest.raises(FileFormatError, match="nan.txt:2: gyro"):
        read_raw_imu(tmp_path / "nan.txt")
    with pytest.raises(ValueError, match="rates"):
        read_raw_imu(tmp_path / "nan.txt", gyro_unit="deg/h")
    with pytest.raises(ValueError, match="seven names"):
        read_raw_imu(tmp_path / "nan.txt", columns=("wx", "wy", "wz", "ax", "ay", "az", "time"))
