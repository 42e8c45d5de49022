"""``gfins calibrate``: the full model by default with the grade read from the record,
the outputs in both conventions, the raw formats, the seed model's warning, option
combinations refused. A short 13-position path at 100 Hz (7 min) keeps them quick; the
accuracy of the calibration itself is tests/calibration's."""
from __future__ import annotations

import json

import numpy as np
import pytest

from gfins_fmi.calibration import compensation as cmp
from gfins_fmi.calibration import syscal_filter, system
from gfins_fmi.cli import main
from gfins_fmi.io import read_raw_imu
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim import rotation as rot

LAT_DEG, H = 34.0, 80.0


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """The laboratory example's errors on a short turntable path, seed-grade noise, as CSV
    and as the raw 7-column layouts (PSINS's [wx wy wz ax ay az t] increments)."""
    seq = ("-x", "-z", "+z", "+x", "+x", "-x", "+y", "-y", "-y", "-x", "+y", "+y")
    sched = rot.RotationSchedule(tuple([rot.rest(120.0)] + [rot.about_imu(a, 90.0, 25.0, 6.0, 0.5) for a in seq]))
    errs = cmp.from_compensation(cmp.laboratory_example())
    rec, _ = system.simulate_record(sched, errs, np.radians(LAT_DEG), H, 0.01,
                                    noise=ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0), seed=3)
    d = tmp_path_factory.mktemp("cal")
    rec.to_csv(d / "rec.csv")
    table = np.c_[rec.gyro, rec.accel, rec.t_s]
    table.astype("<f8").tofile(d / "rec.bin")
    table.astype("<f4").tofile(d / "rec32.bin")
    np.savetxt(d / "rec.txt", np.c_[np.degrees(rec.gyro), rec.accel, rec.t_s], header="wx wy wz (deg) ax ay az t")
    return d, rec, errs


def test_default_run_writes_both_conventions(lab, capsys):
    """Defaults: grade read from the first static interval (navigation, with the record's
    white noise), the full model with the delay (40 states); the report prints the table,
    the checks and the compensation form; --json holds both conventions and the FMU
    parameters, --compensation the PSINS layout, equal to the JSON's."""
    d, rec, errs = lab
    rc = main(["calibrate", str(d / "rec.csv"), "--lat", str(LAT_DEG), "--height", str(H),
               "--json", str(d / "p.json"), "--compensation", str(d / "c.bin"), "--report", str(d / "r.md")])
    out = capsys.readouterr().out
    assert rc == 0
    assert "40 states (full model, delay); grade navigation" in out and "ARW 0.00" in out
    assert "lever_rx_y" in out and "accel_delay" in out and "Ka2 (ug/g^2)" in out and "mean NIS" in out
    doc = json.loads((d / "p.json").read_text())
    assert doc["model"] == "full" and doc["n_states"] == 40 and len(doc["names"]) == 31
    assert set(doc["fmu_parameters"]) >= {"lever_arm_transverse", "accel_delay"}
    cf = cmp.read_compensation(d / "c.bin")
    np.testing.assert_array_equal(cf.to_array(), cmp.CompensationForm.from_dict(doc["compensation_form"]).to_array())
    # the result is the laboratory example within a few sigma (7 min, seed noise)
    truth = syscal_filter.imu_errors_to_params(errs, "full", True)
    z = (np.array(doc["estimate_si"]) - truth) / np.array(doc["std_si"])
    assert np.all(np.abs(z) < 4.0), np.round(z, 2)
    assert (d / "r.md").read_text().startswith("# calibration of")


def test_raw_formats_read_the_same_record(lab, capsys):
    """--format bin64 / bin32 / text7 with their units give the record of the CSV: float64
    exactly, float32 to its 6e-8 relative rounding, text in degrees converted."""
    d, rec, _ = lab
    b = read_raw_imu(d / "rec.bin")
    np.testing.assert_array_equal(b.gyro, rec.gyro)
    np.testing.assert_array_equal(b.t_s, rec.t_s)
    f = read_raw_imu(d / "rec32.bin", "float32")
    np.testing.assert_allclose(f.accel, rec.accel, rtol=1.2e-7)
    t = read_raw_imu(d / "rec.txt", gyro_unit="deg")
    np.testing.assert_allclose(t.gyro, rec.gyro, rtol=1e-15, atol=1e-20)
    rc = main(["calibrate", str(d / "rec.txt"), "--format", "text7", "--gyro-unit", "deg", "--lat",
               str(LAT_DEG), "--height", str(H), "--passes", "1", "--grade", "navigation"])
    assert rc == 0 and "grade navigation" in capsys.readouterr().out


def test_seed_model_warns_and_bad_options(lab, capsys):
    """--model seed (36 states) on a record with transverse lever arms and a delay: the
    warning names the missing terms; --max-rounds without --widen-priors and --gyro-unit
    deg/h with increments are refused at parse time; a wrong float width is named."""
    d, _, _ = lab
    rc = main(["calibrate", str(d / "rec.csv"), "--lat", str(LAT_DEG), "--height", str(H), "--model", "seed",
               "--grade", "navigation"])
    out = capsys.readouterr().out
    assert rc == 0 and "36 states" in out and "WARNING: the record holds terms the seed model lacks" in out
    assert "lever_ry_x" in out and "accel_delay" in out
    with pytest.raises(SystemExit):
        main(["calibrate", str(d / "rec.csv"), "--lat", "34", "--height", "80", "--max-rounds", "2"])
    with pytest.raises(SystemExit):
        main(["calibrate", str(d / "rec.bin"), "--format", "bin64", "--gyro-unit", "deg/h", "--lat", "34",
              "--height", "80"])
    rc = main(["calibrate", str(d / "rec32.bin"), "--format", "bin64", "--lat", "34", "--height", "80"])
    err = capsys.readouterr().err
    assert rc == 2 and "float32" in err, err


def test_simulate_lab_errors_and_prior_mean(tmp_path, capsys):
    """--simulate turntable19 --sim-errors lab writes a record with transverse lever arms and
    a delay and their truth (both conventions); --prior-mean reads a compensation form
    (here the truth's) as the prior's centre (--passes 1: the run's shift against it is
    small)."""
    rec = tmp_path / "sim.csv"
    rc = main(["calibrate", str(rec), "--lat", "34", "--height", "80", "--simulate", "turntable19",
               "--sim-errors", "lab", "--sim-seed", "5", "--passes", "1", "--json", str(tmp_path / "p.json")])
    assert rc == 0
    truth = json.loads((tmp_path / "sim.csv.truth.json").read_text())
    assert truth["model"] == "full" and len(truth["si"]) == 31
    cmp.write_compensation(cmp.CompensationForm.from_dict(truth["compensation_form"]), tmp_path / "t.json")
    capsys.readouterr()
    rc = main(["calibrate", str(rec), "--lat", "34", "--height", "80", "--passes", "1", "--prior-mean",
               str(tmp_path / "t.json"), "--json", str(tmp_path / "q.json")])
    assert rc == 0
    doc = json.loads((tmp_path / "q.json").read_text())
    assert np.max(np.abs(doc["shift_prior_sigma"])) < 0.1
