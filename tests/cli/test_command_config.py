"""Configuration files for ``gfins align`` and ``gfins calibrate`` (issue 20, "What to
build" 1): ``--config FILE`` (TOML or YAML) runs like the same options typed, options on
the command line override the file, ``--print-config`` prints a commented template with
units, every run that writes a file writes its effective configuration beside it (or at
``--save-config``) and ``--config`` of that file repeats the run bit for bit; a bad key or
value is refused naming it and what to change.

Each test compares a run from a file with the same run from options (the truth: the
command line path, unchanged by this work), and the replay with the original, byte for
byte. Records are short (seconds of CPU): an 80 s rest at 100 Hz, a 70 s vehicle drive at
50 Hz, a 5-minute six-turn calibration path at 100 Hz.
"""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from gfins_fmi.cli import main
from gfins_fmi.io.records import BaroRecord, ImuRecord, OdometerRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import quat_to_euler
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle

DEG = np.pi / 180


@pytest.fixture(scope="module")
def rest_record(tmp_path_factory):
    """80 s at rest at 100 Hz, heading 40 deg, 34 deg N, navigation-grade noise (seeded)."""
    prof = VehicleProfile(lat0_rad=34 * DEG, lon0_rad=0.0, h0_m=80.0, heading0_rad=40 * DEG, segments=[Segment(80.0)])
    tr = simulate_vehicle(prof, 80.0, 0.01)
    rng = np.random.default_rng(3)
    wn, an = ImuNoise(gyro_arw_deg_sqrt_h=0.003, accel_vrw_ug_sqrt_hz=10.0).sample(len(tr.t_s) - 1, 0.01, rng)
    path = tmp_path_factory.mktemp("rest") / "imu.csv"
    ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad + wn * 0.01, accel=tr.dv_m_s + an * 0.01,
              kind="increments").to_csv(path)
    return path


def _lines(text: str) -> list[str]:
    return [x for x in text.splitlines() if x.startswith(("coarse", "fine", "pass", "note"))]


def test_align_static_from_a_file_like_its_options_and_repeated(rest_record, tmp_path, capsys):
    """Before: gfins align took options only. Now a TOML file with the positionals and
    options gives the same alignment as typing them; --save-config writes the effective
    configuration (every option with its unit, the grade, bias 1-sigma and window the run
    chose) and --config of it repeats the run; the command line overrides the file."""
    argv = ["align", "static", str(rest_record), "--position", "34,0,80", "--grade", "navigation", "--fine",
            "--fine-end", "75"]
    assert main(argv) == 0
    typed = _lines(capsys.readouterr().out)
    assert len(typed) == 2 and typed[1].startswith("fine (60.01 to 75 s)"), typed
    cfg = tmp_path / "align.toml"
    cfg.write_text(f'''mode = "static"
imu = "{rest_record}"
position = [34, 0, 80]
grade = "navigation"
fine = true
fine-end = 75
''')
    saved = tmp_path / "effective.json"
    assert main(["align", "--config", str(cfg), "--save-config", str(saved)]) == 0
    assert _lines(capsys.readouterr().out) == typed
    doc = json.loads(saved.read_text())
    assert doc["command"] == "align" and doc["options"]["mode"] == "static"
    assert doc["options"]["position"] == [34.0, 0.0, 80.0] and doc["units"]["position"] == "LAT,LON,H in deg, deg, m"
    assert doc["options"]["fine_end"] == 75.0 and doc["units"]["fine_end"] == "s"
    assert doc["options"]["heading_std"] == 5.0 and doc["units"]["heading_std"] == "deg"   # a default filled in
    assert doc["resolved"]["grade"] == "navigation" and doc["resolved"]["window_s"][1] == pytest.approx(60.01)
    # the navigation grade's bias instability (gfins_fmi.sim.scenarios.NAVIGATION): 0.027 deg/h
    assert doc["resolved"]["gyro_bias_1sigma_deg_h"] == pytest.approx(0.027)
    assert doc["inputs"][str(rest_record)]["bytes"] == rest_record.stat().st_size
    # the run repeated from what it wrote
    assert main(["align", "--config", str(saved)]) == 0
    assert _lines(capsys.readouterr().out) == typed
    # the command line overrides the file: a shorter fine alignment
    assert main(["align", "--config", str(cfg), "--fine-end", "70"]) == 0
    lines = _lines(capsys.readouterr().out)
    assert lines[0] == typed[0] and lines[1].startswith("fine (60.01 to 70 s)"), lines


def test_align_motion_writes_its_configuration_beside_the_output(tmp_path, capsys):
    """A run that writes a file writes OUT.config.json beside it, with the output set
    (appears with it); the replay into another output writes the same table byte for
    byte. YAML is read as TOML is."""
    segs = [Segment(20.0), Segment(30.0, dheading_rad=np.pi / 2), Segment(20.0, dspeed_m_s=1.0)]
    prof = VehicleProfile(lat0_rad=30 * DEG, lon0_rad=114 * DEG, h0_m=-50.0, heading0_rad=40 * DEG,
                          speed0_m_s=4.5, segments=segs)
    tr = simulate_vehicle(prof, 70.0, 0.02)
    rng = np.random.default_rng(7)
    n = len(tr.t_s) - 1
    ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad + rng.normal(0, 1e-6, (n, 3)),
              accel=tr.dv_m_s + rng.normal(0, 1e-5, (n, 3)), kind="increments").to_csv(tmp_path / "imu.csv")
    ks = np.arange(5, n + 1, 5)
    OdometerRecord(t_s=tr.t_s[ks], speed_m_s=np.hypot(tr.v_n_m_s[ks, 0], tr.v_n_m_s[ks, 1]),
                   std_m_s=np.full(len(ks), 0.05)).to_csv(tmp_path / "speed.csv")
    kd = np.arange(50, n + 1, 50)
    BaroRecord(t_s=tr.t_s[kd], h_m=tr.h_m[kd], std_m=np.full(len(kd), 0.1)).to_csv(tmp_path / "depth.csv")
    e = np.degrees(quat_to_euler(tr.q_bn[0])) + [2.0, 0.2, -0.2]
    initial = ",".join(repr(float(x)) for x in (30, 114, -50, *e))
    (tmp_path / "run.yaml").write_text(f"""mode: motion
imu: imu.csv
speed: speed.csv
depth: depth.csv
initial: "{initial}"
passes: 2
output: passes.csv
""")
    # 70 s is too short for the 0.5 deg heading limit: exit 1, "not converged", the outputs written all the same
    assert main(["align", "--config", str(tmp_path / "run.yaml")]) == 1
    first = capsys.readouterr().out
    written = tmp_path / "passes.config.json"
    doc = json.loads(written.read_text())
    assert doc["options"]["passes"] == 2 and doc["options"]["output"] == str(tmp_path / "passes.csv")
    assert main(["align", "--config", str(written), "--output", str(tmp_path / "again.csv")]) == 1
    assert (tmp_path / "again.csv").read_bytes() == (tmp_path / "passes.csv").read_bytes()
    assert [x for x in capsys.readouterr().out.splitlines() if x.startswith("pass")] == \
        [x for x in first.splitlines() if x.startswith("pass")]


def test_bad_keys_and_values_are_refused_by_name(rest_record, tmp_path, capsys):
    """A key that is no option, a value its option refuses, a wrong choice, a flag that is
    not true/false, and a combination the command refuses: exit 2 and a message naming
    the key and what to change; nothing written."""
    base = f'mode = "static"\nimu = "{rest_record}"\nposition = "34,0,80"\n'
    cases = [("positon = [34, 0, 80]\n", "unknown setting 'positon'; the options of gfins align (gfins align "
                                         "--print-config lists them)"),
             ('heading_std = "-1"\n', "heading_std: must be finite and > 0 deg; got -1.0"),
             ('grade = "superb"\n', "grade must be one of consumer, tactical, navigation; got 'superb'"),
             ('fine = "yes"\n', "fine must be true or false; got 'yes'"),
             ("fine_end = 70\n", "--fine-end is the end of the fine alignment: give --fine")]
    for extra, message in cases:
        cfg = tmp_path / "bad.toml"
        cfg.write_text(base + extra)
        assert main(["align", "--config", str(cfg), "--save-config", str(tmp_path / "s.json")]) == 2, extra
        err = capsys.readouterr().err
        assert message in err, (extra, err)
        assert not (tmp_path / "s.json").exists()
    cfg.write_text("mode = \"static\"\n")
    assert main(["align", "--config", str(cfg)]) == 2
    assert "the following arguments are required: mode (static, motion or transfer) and IMU" in capsys.readouterr().err
    with pytest.raises(SystemExit):       # no file: refused at parse time, as before
        main(["align", "static"])


def test_print_config_is_a_commented_template_with_units(capsys):
    """--print-config: every option commented out with its help, unit and default; the
    template read back as TOML once uncommented is a valid configuration."""
    import tomllib
    for command, keys in (("align", ("# mode = ", "# position =", "[LAT,LON,H in deg, deg, m]", "# heading_std = 5.0")),
                          ("calibrate", ("# lat =   (not set by default)", "[deg]", "# passes = 2",
                                         '# prior = ["NAME=VALUE", ...]'))):
        assert main([command, "--print-config"]) == 0
        text = capsys.readouterr().out
        for k in keys:
            assert k in text, (command, k)
        # the lines with a default, uncommented: TOML that parses
        body = [x[2:] for x in text.splitlines() if re.match(r"# [a-z_0-9]+ = ", x) and "not set" not in x
                and "NAME=VALUE" not in x]
        assert len(body) > 15, body
        tomllib.loads("\n".join(body))


@pytest.fixture(scope="module")
def cal_record(tmp_path_factory):
    """A six-turn path at 100 Hz (5.3 min) with the laboratory example's errors."""
    from gfins_fmi.calibration import compensation as cmp
    from gfins_fmi.calibration import system
    from gfins_fmi.sim import rotation as rot
    seq = ("-x", "-z", "+z", "+x", "+y", "-y")
    sched = rot.RotationSchedule(tuple([rot.rest(60.0)] + [rot.about_imu(a, 90.0, 20.0, 4.0, 0.5) for a in seq]))
    rec, _ = system.simulate_record(sched, cmp.from_compensation(cmp.laboratory_example()), np.radians(34.0), 80.0,
                                    0.01, noise=ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0),
                                    seed=3)
    path = tmp_path_factory.mktemp("cal") / "rec.csv"
    rec.to_csv(path)
    return path


def test_calibrate_from_a_file_and_repeated_from_its_effective_configuration(cal_record, tmp_path, capsys):
    """gfins calibrate --config run.toml equals the typed options (report and JSON byte for
    byte); R.config.json is written beside the report with the grade the run read from the
    record and its filter settings; --config R.config.json repeats the run."""
    a, b, c = (tmp_path / x for x in ("a", "b", "c"))
    for d in (a, b, c):
        d.mkdir()
    argv = ["calibrate", str(cal_record), "--lat", "34", "--height", "80", "--passes", "1",
            "--prior", "gyro_bias_deg_h=0.5", "--report", str(a / "r.md"), "--json", str(a / "p.json")]
    assert main(argv) == 0
    cfg = tmp_path / "cal.toml"
    cfg.write_text(f'''imu = "{cal_record}"
lat = 34
height = 80.0
passes = 1
prior = ["gyro_bias_deg_h=0.5"]
report = "b/r.md"
json = "b/p.json"
''')
    assert main(["calibrate", "--config", str(cfg)]) == 0
    for name in ("r.md", "p.json"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    doc = json.loads((b / "r.config.json").read_text())
    assert doc["options"]["prior"] == ["gyro_bias_deg_h=0.5"] and doc["units"]["lat"] == "deg"
    assert doc["resolved"]["grade"] == "navigation"            # read from the first static interval
    assert doc["resolved"]["syscal_config"]["prior"]["gyro_bias_deg_h"] == 0.5
    assert main(["calibrate", "--config", str(b / "r.config.json"), "--report", str(c / "r.md"),
                 "--json", str(c / "p.json")]) == 0
    assert (c / "p.json").read_bytes() == (a / "p.json").read_bytes()
    capsys.readouterr()
    # a required option missing from both: the parse-time message, once the file is read
    cfg.write_text(f'imu = "{cal_record}"\nlat = 34\n')
    assert main(["calibrate", "--config", str(cfg)]) == 2
    assert "the following arguments are required: --lat, --height" in capsys.readouterr().err


def test_calibrate_poses_from_a_file(tmp_path, capsys):
    """`gfins calibrate poses --config hand.toml` (the word poses typed, the rest from the
    file) runs the pose calibration as the typed options do (the output byte for byte);
    CAL.config.json beside its output records the word and the record (the replay itself
    is the system-level test's: the same mechanism). A 14-pose record at 50 Hz keeps it
    short."""
    from gfins_fmi.nav.imu_errors import ImuErrors
    from gfins_fmi.sim.hand_poses import CONSUMER_MEMS_ERRORS, hand_turned_record
    errs = ImuErrors.random(np.random.default_rng(5), **CONSUMER_MEMS_ERRORS)
    rec = hand_turned_record(errs, ImuNoise(gyro_arw_deg_sqrt_h=0.6, accel_vrw_ug_sqrt_hz=150.0), n_poses=14,
                             still_s=(4.0, 5.0), first_still_s=20.0, rate_hz=50.0, seed=5, lat_rad=np.radians(40.0),
                             h_m=100.0)
    rec.imu.to_csv(tmp_path / "hand.csv")
    (tmp_path / "hand.toml").write_text('record = "hand.csv"\nlat = 40\nheight = 100\noutput = "b.toml"\n')
    assert main(["calibrate", "poses", "--config", str(tmp_path / "hand.toml")]) == 0
    assert main(["calibrate", "poses", str(tmp_path / "hand.csv"), "--lat", "40", "--height", "100",
                 "--output", str(tmp_path / "a.toml")]) == 0
    assert (tmp_path / "a.toml").read_bytes() == (tmp_path / "b.toml").read_bytes()
    doc = json.loads((tmp_path / "b.config.json").read_text())
    assert doc["options"]["imu"] == "poses" and doc["options"]["record"] == str(tmp_path / "hand.csv")
    capsys.readouterr()


def test_an_option_typed_with_its_default_value_overrides_the_file(rest_record, tmp_path, capsys):
    """The command line overrides the file even where the typed value is the option's
    default (before: an option counted as given only when its value differed from the
    default, so the file's value won): --grade navigation typed over a file's tactical
    (integrate's default is tactical: the same rule for every command)."""
    cfg = tmp_path / "a.toml"
    cfg.write_text(f'mode = "static"\nimu = "{rest_record}"\nposition = "34,0,80"\ngrade = "tactical"\n'
                   'heading_std = 3.0\n')
    saved = tmp_path / "s.json"
    assert main(["align", "--config", str(cfg), "--heading-std", "5", "--save-config", str(saved)]) == 0
    capsys.readouterr()
    doc = json.loads(saved.read_text())
    assert doc["options"]["heading_std"] == 5.0 and doc["options"]["grade"] == "tactical", doc["options"]
