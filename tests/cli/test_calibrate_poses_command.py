"""``gfins calibrate poses RECORD`` on a simulated hand-turned record: its report, IMU
errors file, residual tables and figure; the file read back by ``gfins integrate
--imu-errors`` (and equal to the Python API's result); raw counts; the refusals; the
system-level ``gfins calibrate IMU`` still asking for its site."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.calibration.poses import calibrate_poses
from gfins_fmi.cli import main
from gfins_fmi.cli.files import compensated
from gfins_fmi.estimation.noise_file import imu_errors_text, read_imu_errors
from gfins_fmi.io import ImuRecord
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.sim.hand_poses import CONSUMER_MEMS_ERRORS, hand_turned_record


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    d = tmp_path_factory.mktemp("poses")
    errs = ImuErrors.random(np.random.default_rng(5), **CONSUMER_MEMS_ERRORS)
    rec = hand_turned_record(errs, ImuNoise(gyro_arw_deg_sqrt_h=0.6, accel_vrw_ug_sqrt_hz=150.0), n_poses=24,
                             seed=5, lat_rad=np.radians(40.0), h_m=100.0)
    rec.imu.to_csv(d / "hand.csv")
    return d, rec


def test_command_outputs(record, capsys):
    d, rec = record
    code = main(["calibrate", "poses", str(d / "hand.csv"), "--lat", "40", "--height", "100", "--output",
                 str(d / "cal.toml"), "--table", str(d / "res"), "--plot", str(d), "--report", str(d / "r.md")])
    assert code == 0
    out = capsys.readouterr().out
    assert "24 still poses" in out and "| gyro_bias_z |" in out
    got = read_imu_errors(d / "cal.toml")
    api = calibrate_poses(rec.imu, lat_rad=np.radians(40.0), h_m=100.0).errors
    # the file holds the API's result (repr floats: bit for bit)
    for k in ("gyro_bias_deg_h", "gyro_scale_ppm", "gyro_misalignment_arcsec", "accel_bias_ug",
              "accel_scale_ppm", "accel_misalignment_arcsec"):
        np.testing.assert_array_equal(getattr(got, k), getattr(api, k))
    assert (d / "res.poses.csv").read_text().splitlines()[0].startswith("t0_s,t1_s,accel_x_m_s2")
    assert len((d / "res.turns.csv").read_text().splitlines()) == 24    # header + 23 turns
    assert (d / "pose_calibration.png").stat().st_size > 10000
    assert "accelerometer-defined body frame" in (d / "r.md").read_text()


def test_raw_counts(record, tmp_path, capsys):
    """A CSV of counts (t, 3 gyro, 3 accel LSB) with --counts gives the calibration of the
    same record in SI (the nominal sensitivities divide out: scale factors differ by the
    rounding of the counts only; biases within 1e-3 relative)."""
    d, rec = record
    g_lsb, a_lsb = 131.0, 16384.0                      # a common MEMS range setting
    counts = np.column_stack([rec.imu.t_s, np.degrees(rec.imu.gyro) * g_lsb, rec.imu.accel / 9.80665 * a_lsb])
    np.savetxt(tmp_path / "counts.csv", counts, delimiter=",")
    assert main(["calibrate", "poses", str(tmp_path / "counts.csv"), "--counts", f"{g_lsb},{a_lsb}",
                 "--gravity", "9.80", "--output", str(tmp_path / "c.toml")]) == 0
    c = read_imu_errors(tmp_path / "c.toml")
    ref = calibrate_poses(rec.imu, gravity_m_s2=9.80).errors
    np.testing.assert_allclose(c.gyro_bias_deg_h, ref.gyro_bias_deg_h, rtol=1e-6)
    np.testing.assert_allclose(c.accel_bias_ug, ref.accel_bias_ug, rtol=1e-6)


def test_integrate_compensates_with_the_file(record, tmp_path):
    """`integrate --imu-errors` hands the filter the record compensated by the file's
    errors: compensated(imu) = ImuErrors.compensate of the rates (0 difference)."""
    d, rec = record
    errs = read_imu_errors(d / "cal.toml") if (d / "cal.toml").exists() else ImuErrors(gyro_bias_deg_h=[1.0, 2, 3])
    out = compensated(rec.imu, errs)
    w, f = errs.compensate(rec.imu.gyro, rec.imu.accel)
    np.testing.assert_array_equal(out.gyro, w)
    np.testing.assert_array_equal(out.accel, f)


def test_refusals(record, capsys):
    d, _ = record
    with pytest.raises(SystemExit):
        main(["calibrate", "poses", str(d / "hand.csv")])
    assert "needs the gravity" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["calibrate", str(d / "hand.csv")])
    assert "required: --lat, --height" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["calibrate", "other", str(d / "hand.csv"), "--lat", "40", "--height", "0"])
    assert "gfins calibrate poses RECORD" in capsys.readouterr().err
    assert main(["calibrate", "poses", str(d / "hand.csv"), "--gravity", "9.8", "--min-still", "12"]) == 2
    assert "still poses found" in capsys.readouterr().err


def test_navigate_and_align_take_the_errors(tmp_path):
    """`navigate --imu-errors` on a record with known errors applied navigates as on the
    clean record (chunks of 1000: the increments' first interval carried across chunks;
    1e-12 of the outputs: round-off of apply then compensate); `align static
    --imu-errors` reads the same file."""
    n, dt = 3000, 0.01
    t = np.arange(1, n + 1) * dt
    w = np.c_[0.02 * np.sin(0.7 * t), 0.01 * np.cos(1.1 * t), 0.05 * np.sin(0.2 * t)] * dt
    f = np.c_[0.3 * np.sin(0.5 * t), 0.2 + 0.1 * np.cos(0.3 * t), 9.8 + 0.05 * np.sin(t)] * dt
    e = ImuErrors(gyro_bias_deg_h=[100, -50, 20], gyro_scale_ppm=[300, 0, -100],
                  accel_scale_ppm=[1000, 2000, -500], accel_bias_ug=[500, 100, -300])
    we, fe = e.apply_increments(w, f, dt)
    np.savetxt(tmp_path / "clean.csv", np.c_[t, w, f], delimiter=",")
    np.savetxt(tmp_path / "err.csv", np.c_[t, we, fe], delimiter=",")
    (tmp_path / "e.toml").write_text(imu_errors_text(e))
    nav0 = ["--lat0", "30", "--lon0", "114", "--h0", "50", "--chunk", "1000"]
    assert main(["navigate", str(tmp_path / "clean.csv"), str(tmp_path / "a.csv")] + nav0) == 0
    assert main(["navigate", str(tmp_path / "err.csv"), str(tmp_path / "b.csv"), "--imu-errors",
                 str(tmp_path / "e.toml")] + nav0) == 0
    a = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    b = np.loadtxt(tmp_path / "b.csv", delimiter=",", skiprows=1)
    assert np.all(np.abs(b - a) <= 1e-12 * np.abs(a).max(axis=0) + 1e-12), np.abs(b - a).max(axis=0)
    ImuRecord(t, we, fe, "increments").to_csv(tmp_path / "rec.csv")
    assert main(["align", "static", str(tmp_path / "rec.csv"), "--position", "30,114,50", "--window", "0,20",
                 "--imu-errors", str(tmp_path / "e.toml")]) == 0
