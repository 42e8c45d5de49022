"""``gfins align static`` as issue 20 found it: the default window on a record of
increments (fixed by issue 21: checked here from the command line), --fine with an end
time, a given heading when gyrocompassing cannot give one, and a warning with the
--disturbed hint when the base sways during a static gyrocompass.

The records: a vehicle at rest (gf_vehicle truth, a closed form) with seeded IMU noise;
the sway is a yaw of 0.5 deg at 0.1 Hz added to the z-axis increments (a rotation about
the body's up axis leaves the specific force of gravity unchanged: exact to the Earth
rate's horizontal part turning by 0.5 deg, 1e-7 rad/s).
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.cli import main
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import quat_to_euler
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle

DEG = np.pi / 180
DT = 0.01
HEADING = 40.0


@pytest.fixture(scope="module")
def at_rest():
    prof = VehicleProfile(lat0_rad=34 * DEG, lon0_rad=0.0, h0_m=80.0, heading0_rad=HEADING * DEG,
                          segments=[Segment(200.0)])
    return simulate_vehicle(prof, 200.0, DT)


def _write(truth, path, noise, sway_deg=0.0, seed=3):
    rng = np.random.default_rng(seed)
    n = len(truth.t_s) - 1
    wn, an = noise.sample(n, DT, rng)
    gyro = truth.dtheta_rad + wn * DT
    if sway_deg:
        yaw = sway_deg * DEG * np.sin(2 * np.pi * 0.1 * truth.t_s)
        gyro[:, 2] += np.diff(yaw)
    ImuRecord(t_s=truth.t_s[1:], gyro=gyro, accel=truth.dv_m_s + an * DT, kind="increments").to_csv(path)
    return path


NAV = ImuNoise(gyro_arw_deg_sqrt_h=0.003, accel_vrw_ug_sqrt_hz=10.0)


def test_default_window_on_increments_then_fine_to_an_end_time(at_rest, tmp_path, capsys):
    """The README's `--fine` example without --window on increments: before issue 21 the
    first interval was 1e-9 s ("std of |f| 1.26e+06 m/s^2"). --fine-end (issue 20) ends
    the fine alignment there; before it had no end time."""
    rec = _write(at_rest, tmp_path / "imu.csv", NAV)
    rc = main(["align", "static", str(rec), "--position", "34,0,80", "--grade", "navigation", "--fine",
               "--fine-end", "150"])
    out = capsys.readouterr().out
    assert rc == 0 and "coarse (gyrocompass)" in out and "fine (60.01 to 150 s): heading" in out, out
    heading = float(out.split("fine (60.01 to 150 s): heading ")[1].split(" deg")[0])
    assert abs(heading - HEADING) < 0.5, out     # navigation grade, 0.027 deg/h: ~0.1 deg
    with pytest.raises(SystemExit):
        main(["align", "static", str(rec), "--position", "34,0,80", "--fine-end", "150"])


def test_a_given_heading_when_gyrocompassing_cannot(at_rest, tmp_path, capsys):
    """A consumer-grade IMU cannot gyrocompass: before, --fine then failed ("the coarse
    alignment has no heading") with no way to give one. Now --heading (with --heading-std)."""
    rec = _write(at_rest, tmp_path / "imu.csv", NAV)
    rc = main(["align", "static", str(rec), "--position", "34,0,80", "--grade", "consumer", "--fine"])
    err = capsys.readouterr().err
    assert rc == 2 and "give one with --heading DEG" in err, err
    rc = main(["align", "static", str(rec), "--position", "34,0,80", "--grade", "consumer", "--fine",
               "--heading", "42", "--heading-std", "3"])
    out = capsys.readouterr().out
    assert rc == 0 and "coarse (given): heading 42.0000 deg" in out and "heading 1-sigma 3.0000 deg" in out, out
    assert "fine (60.01 to 200 s)" in out, out


def test_a_swaying_base_is_warned_of(at_rest, tmp_path, capsys):
    """Static gyrocompassing on a swaying base: before, silent (its sigma understated
    7-deg-level errors on a real laser-gyro record). Now a warning naming --disturbed;
    none on the base at rest."""
    still = _write(at_rest, tmp_path / "still.csv", NAV)
    assert main(["align", "static", str(still), "--position", "34,0,80", "--grade", "navigation"]) == 0
    assert "warning" not in capsys.readouterr().err
    sway = _write(at_rest, tmp_path / "sway.csv", NAV, sway_deg=0.5)
    assert main(["align", "static", str(sway), "--position", "34,0,80", "--grade", "navigation"]) == 0
    err = capsys.readouterr().err
    assert "gfins align: warning: the base turned up to" in err and "use --disturbed" in err, err
