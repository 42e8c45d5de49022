"""``gfins calibrate poses RECORD`` on a simulated hand-turned record: its report, IMU
errors file, residual tables and figure; the file read back by ``gfins integrate
--imu-errors`` (and equal to the Python API's result); raw counts; the refusals; the
system-level ``gfins calibrate IMU`` still asking for its site."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.calibration.poses import calibrate_poses
from gfins_fmi.cli import main
from gfins_fmi.estimation.noise_file import read_imu_errors
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
    from gfins_fmi.cli.integrate import compensated
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
