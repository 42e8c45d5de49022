"""Nothing lost, ever (issue 21): the commands' outputs against their inputs, partial
results, records a run cannot use, finite but absurd inputs, and the messages the held-out
run found blaming the wrong thing. Each test is one item of the issue's "Why" and failed
on the code before it (the "Before:" line says how).

Truth: the input files' bytes, the files in the folder, the text the commands print;
the static records are closed-form (a level IMU at rest: gravity up, the Earth rate at
the site's latitude).
"""
from __future__ import annotations

import os
import pathlib
import re

import numpy as np
import pytest

from gfins_fmi.cli import main
from support.truth import OMEGA, numpy_outputs, paper_layout, smooth_motion

N0 = ["--lat0", "30", "--lon0", "114", "--h0", "50"]
DT = 0.01


def _strapdown(n=600, bad=None):
    """t, gyro and accelerometer increments of a wobbling vehicle at rest (rad, m/s)."""
    t = np.arange(1, n + 1) * DT
    w = np.c_[0.02 * np.sin(0.7 * t), 0.01 * np.cos(1.1 * t), 0.05 * np.sin(0.2 * t)]
    f = np.c_[0.3 * np.sin(0.5 * t), 0.2 + 0.1 * np.cos(0.3 * t), 9.80 + 0.05 * np.sin(t)]
    rec = np.c_[t, w * DT, f * DT]
    if bad is not None:
        rec[bad, 3] = np.nan
    return rec


def _accel9(n=400, bad=None, time_scale=1.0):
    """t, A1..A9 of seed 000's layout (l = 0.1 m) on a smooth motion (m/s^2)."""
    u, th = paper_layout(0.1)
    t, f, w, wd = smooth_motion(n, DT)
    rec = np.c_[t * time_scale, numpy_outputs(u, th, f, w, wd)]
    if bad is not None:
        rec[bad, 4] = np.nan
    return rec


def _csv(path, table) -> pathlib.Path:
    np.savetxt(path, table, delimiter=",", fmt="%.17g")
    return path


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """20 s of a simulated drive (tactical IMU, GNSS at 1 Hz) as record CSVs, and the
    --initial option of its start."""
    import gfins_fmi as gf
    from gfins_fmi.io import TruthRecord
    from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
    from gfins_fmi.sim.vehicle import GnssReceiver
    d = simulate_drive(town_drive(20.0, lat0_rad=0.6, lon0_rad=2.0, h0_m=30.0), 20.0, DT,
                       imu=TACTICAL, gnss=GnssReceiver(), seed=3)
    folder = tmp_path_factory.mktemp("drive")
    d.imu.to_csv(folder / "imu.csv")
    d.gnss.to_csv(folder / "gnss.csv")
    tr = d.truth
    TruthRecord(t_s=tr.t_s, lat_rad=tr.lat_rad, lon_rad=tr.lon_rad, h_m=tr.h_m, v_enu_m_s=tr.v_n_m_s,
                euler_rad=tr.euler_rad).to_csv(folder / "truth.csv")
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    init = "--initial=" + ",".join(repr(float(x)) for x in
                                   (np.degrees(tr.lat_rad[0]), np.degrees(tr.lon_rad[0]), tr.h_m[0], *e))
    return folder, d, init


def _integrate(folder, out, init, *extra, imu="imu.csv", gnss="gnss.csv"):
    return ["integrate", str(folder / imu), str(folder / gnss), str(out), "--imu-format", "csv",
            "--gnss-format", "csv", init, *extra]


# ---- an input overwritten -----------------------------------------------------------------

_COMMANDS = {
    "solve9": lambda src, out: ["solve9", src, out, "--lever-arm", "0.1", "--dt", "0.01"],
    "navigate": lambda src, out: ["navigate", src, out, *N0],
    "gfnav": lambda src, out: ["gfnav", src, out, "--layout", "qin9", "--lever-arm", "0.1", *N0],
    "integrate": lambda src, out: ["integrate", src, src + ".gnss", out, "--initial=30,114,0,0,0,0"],
    "align motion --output": lambda src, out: ["align", "motion", src, src + ".speed",
                                               "--initial=30,114,0,0,0,0", "--output", out],
    "calibrate --json": lambda src, out: ["calibrate", src, "--lat", "34", "--height", "80",
                                          "--json", out],
}


@pytest.mark.parametrize("how", ["same name", "symbolic link", "hard link"])
@pytest.mark.parametrize("command", sorted(_COMMANDS))
def test_no_command_writes_over_its_input(command, how, tmp_path, capsys):
    """Before: with the output path equal to an input, every writing command replaced the
    recording (with a bad sample inside: by a 499-row partial solution, exit 1). Now the
    output is compared with every input as a file (by inode: a link is caught too) and
    refused before anything is read; the recording is untouched."""
    src = tmp_path / "rec.csv"
    src.write_bytes(b"0.01,1,2,3,4,5,6,7,8,9\n")
    for side in (".gnss", ".speed"):
        (tmp_path / ("rec.csv" + side)).write_text("t_s\n")
    out = tmp_path / "out.csv"
    if how == "same name":
        out = src
    elif how == "symbolic link":
        out.symlink_to(src)
    else:
        os.link(src, out)
    assert main([str(a) for a in _COMMANDS[command](str(src), str(out))]) == 2
    err = capsys.readouterr().err
    assert f"the output {out} is the input {src}" in err and "give another output name" in err, err
    assert src.read_bytes() == b"0.01,1,2,3,4,5,6,7,8,9\n"


# ---- partial outputs under the final name --------------------------------------------------

@pytest.mark.parametrize("command", ["navigate", "gfnav", "solve9"])
def test_a_refused_sample_leaves_a_partial_file_and_the_output_as_it_was(command, tmp_path, capsys):
    """Before: after a refused sample the rows before it were written under the output's
    own name, unmarked (the README promises an output appears under its name only when
    complete), and the message said "(see .partial)" where no such file existed. Now they
    go to sol.partial.csv, whose first line says where and why the run stopped; the
    message names that file; sol.csv is left as it was; the next good run removes it."""
    rec, good = ((_strapdown(bad=250), _strapdown()) if command == "navigate" else
                 (_accel9(bad=250), _accel9()))
    src, out = _csv(tmp_path / "rec.csv", rec), tmp_path / "sol.csv"
    out.write_text("the previous solution\n")
    args = {"navigate": ["navigate", str(src), str(out), *N0],
            "gfnav": ["gfnav", str(src), str(out), "--layout", "qin9", "--lever-arm", "0.1", *N0],
            "solve9": ["solve9", str(src), str(out), "--lever-arm", "0.1"]}[command]
    assert main(args) == 1
    err = capsys.readouterr().err
    verb = "solved" if command == "solve9" else "navigated"
    partial = tmp_path / "sol.partial.csv"
    assert f"the 250 samples {verb} before it are in {partial} ({out} left as it was)" in err, err
    assert "see .partial" not in err and ".partial is empty" not in err
    assert out.read_text() == "the previous solution\n"
    first, header, *rows = partial.read_text().splitlines()
    assert re.fullmatch(rf"# partial: stopped at input row 250 of {re.escape(str(src))}: .* is not "
                        rf"finite; the 250 rows here are the samples {verb} before it", first), first
    assert header.startswith("t_s,") and len(rows) == 250
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "sol.csv", "sol.partial.csv"]
    _csv(src, good)
    assert main(args) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "sol.csv"]


def test_integrate_keeps_partial_tables_after_a_refused_sample(drive, tmp_path, capsys):
    """The integrated solution and its innovation log, cut at a refused IMU sample: both
    go to their partial names, stamped alike; the previous set stays whole."""
    from gfins_fmi import io
    folder, d, init = drive
    a = d.imu.accel.copy()
    a[700, 2] = 1e9                                     # |f| far beyond 1000 m/s^2
    io.ImuRecord(t_s=d.imu.t_s, gyro=d.imu.gyro, accel=a, kind=d.imu.kind).to_csv(tmp_path / "imu.csv")
    (tmp_path / "gnss.csv").write_bytes((folder / "gnss.csv").read_bytes())
    for name in ("out.csv", "out.innovations.csv"):
        (tmp_path / name).write_text("previous\n")
    assert main(_integrate(tmp_path, tmp_path / "out.csv", init)) == 1
    err = capsys.readouterr().err
    assert (f"the 700 samples before it are in {tmp_path / 'out.partial.csv'}, "
            f"{tmp_path / 'out.innovations.partial.csv'}") in err, err
    for name in ("out.csv", "out.innovations.csv"):
        assert (tmp_path / name).read_text() == "previous\n"
    assert (tmp_path / "out.config.partial.json").is_file()     # what the failed run used
    for name in ("out.partial.csv", "out.innovations.partial.csv"):
        assert (tmp_path / name).read_text().startswith(
            f"# partial: the filter stopped at IMU sample 700 of {tmp_path / 'imu.csv'}: IMU sample 700 exceeds")
    assert len(np.loadtxt(tmp_path / "out.partial.csv", delimiter=",", skiprows=2)) == 700


def test_a_set_holds_only_this_runs_files(drive, tmp_path, capsys):
    """A run without --smooth after one with it: before, the earlier OUT.smoothed.csv
    stayed beside a solution it did not belong to. Now the set's files this run does not
    produce go with its commit."""
    folder, _, init = drive
    out = tmp_path / "out.csv"
    assert main(_integrate(folder, out, init, "--smooth")) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.config.json", "out.csv",
                                                           "out.innovations.csv", "out.smoothed.csv"]
    assert main(_integrate(folder, out, init)) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.config.json", "out.csv",
                                                           "out.innovations.csv"]
    # the effective configuration: what the run used, to read back or rerun it
    import json
    doc = json.loads((tmp_path / "out.config.json").read_text())
    assert doc["options"]["smooth"] is False and doc["filter"]["imu"]["gyro_arw_deg_sqrt_h"] == 0.05
    assert doc["inputs"]["imu"]["bytes"] == (folder / "imu.csv").stat().st_size


# ---- silently unaided ----------------------------------------------------------------------

@pytest.mark.parametrize("shift, hint", [(1000.0, "they are +1000 s apart: put both records on one "
                                                  "time scale"),
                                         (604800.0, "they are 1 GPS week apart")])
def test_integrate_refuses_a_record_it_cannot_use(shift, hint, drive, tmp_path, capsys):
    """Before: GNSS times entirely outside the IMU record — integrate ran unaided, wrote
    its outputs, then failed in the scoring step. Now refused before the run, naming the
    spans and the likely cause; nothing is written."""
    import dataclasses
    from gfins_fmi import io
    folder, d, init = drive
    g = io.GnssRecord.from_csv(folder / "gnss.csv")
    dataclasses.replace(g, t_s=g.t_s + shift).to_csv(tmp_path / "gnss.csv")
    (tmp_path / "imu.csv").symlink_to(folder / "imu.csv")
    assert main(_integrate(tmp_path, tmp_path / "out.csv", init)) == 2
    err = capsys.readouterr().err
    assert "no GNSS epoch falls inside the IMU record (0 to 20 s): its 21 epochs cover" in err, err
    assert hint in err and "nothing was run" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gnss.csv", "imu.csv"]


def test_integrate_scores_against_a_truth_record(drive, tmp_path, capsys):
    """Before: --truth with a TruthRecord CSV always failed in the scoring ("euler_rad must
    have shape (3,)": the record's angles were handed whole to the one-attitude
    function), after the outputs were written."""
    folder, _, init = drive
    assert main(_integrate(folder, tmp_path / "out.csv", init, "--truth", str(folder / "truth.csv"))) == 0
    assert "filter: error to the truth: horizontal RMS" in capsys.readouterr().out


# ---- absurd but finite values ---------------------------------------------------------------

def test_solve9_warns_of_times_in_milliseconds(tmp_path, capsys):
    """Before: solve9 with the time column in ms (dt read as 10 s) integrated omega_dot
    over 1000 times the interval: the sign of omega_x wrong in most rows, no flag. Now the
    record's own rates give the interval (d(omega^2) = 2 omega omega_dot dt) and the
    command warns (the run goes on: a warning, the numbers are the user's)."""
    src = _csv(tmp_path / "a9.csv", _accel9(1001, time_scale=1000.0))
    assert main(["solve9", str(src), str(tmp_path / "s.csv"), "--lever-arm", "0.1"]) == 0
    err = capsys.readouterr().err
    assert re.search(r"gfins solve9: warning: the 9-accelerometer record: the sample interval is 10 "
                     r"s, but the record's own rates imply about 0\.01\d* s .* the interval given is "
                     r"\d+ times longer; likely cause: times in ms where s are expected", err), err
    src = _csv(tmp_path / "a9.csv", _accel9(1001))
    assert main(["solve9", str(src), str(tmp_path / "s.csv"), "--lever-arm", "0.1"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_navigate_warns_of_accelerations_in_g(tmp_path, capsys):
    """Increments of a record whose accelerations are in g: the median |f| is 1 m/s^2,
    a tenth of gravity (a vehicle that is not falling reads g): warned."""
    rec = _strapdown()
    rec[:, 4:7] /= 9.80665
    src = _csv(tmp_path / "rec.csv", rec)
    assert main(["navigate", str(src), str(tmp_path / "sol.csv"), *N0]) == 0
    err = capsys.readouterr().err
    assert "gfins navigate: warning: " in err and "accelerations in g where m/s^2 are expected" in err, err


def _static_record(path, lat_deg, seconds=60.0):
    """A level IMU at rest facing north at ``lat_deg``: increments of gravity (up) and the
    Earth rate (0, cos L, sin L) Omega, closed form, as an ImuRecord CSV."""
    from gfins_fmi import io
    from gfins_fmi.nav.earth import gravity
    lat = np.radians(lat_deg)
    n = int(seconds / DT)
    t = np.arange(1, n + 1) * DT
    w = OMEGA * np.array([0.0, np.cos(lat), np.sin(lat)])
    f = np.array([0.0, 0.0, float(gravity(lat, 80.0))])
    io.ImuRecord(t_s=t, gyro=np.tile(w * DT, (n, 1)), accel=np.tile(f * DT, (n, 1)),
                 kind="increments").to_csv(path)
    return path


@pytest.mark.parametrize("command", ["calibrate", "align static"])
def test_a_latitude_the_earth_rate_contradicts_is_refused(command, tmp_path, capsys):
    """Before: a calibration record made at 34 deg N given --lat 60 was accepted silently
    (the filter fit the wrong Earth rate into the gyro errors). Now the latitude the gyros
    measure at rest (the Earth rate along and across the vertical) is compared with it.
    (align static without --window on an increment record also failed before, for another
    reason: its default window opens 1e-9 s before the first sample, which was taken as
    that increment's interval, |f| = 1e6 m/s^2, "motion during the static alignment
    window".)"""
    rec = _static_record(tmp_path / "rec.csv", 34.0)
    args = (["calibrate", str(rec), "--height", "80", "--lat"] if command == "calibrate" else
            ["align", "static", str(rec), "--position"])
    assert main(args + (["60"] if command == "calibrate" else ["60,0,80"])) == 2
    err = capsys.readouterr().err
    assert re.search(r"the latitude given, 60\.0000 deg, is 26 deg from the one the gyros measure at "
                     r"rest, 34\.0000 deg", err), err
    if command == "align static":                     # the right latitude passes
        assert main(args + ["34,0,80"]) == 0


def test_cosim_checks_its_step_at_parse_time(capsys):
    """Before: --step 0.0100001 failed deep inside the run (the step count rounded up: the
    last step passed the FMUs' stop time). Now refused at parse time."""
    with pytest.raises(SystemExit) as ei:
        main(["cosim", "--step", "0.0100001", "--seconds", "2"])
    assert ei.value.code == 2
    assert ("--seconds 2 s is not a whole number of --step 0.0100001 s (199.998 steps): give a step "
            "that divides it, or --seconds 1.9900199 or 2.00002 (199 or 200 steps)") in capsys.readouterr().err


# ---- messages that blamed the wrong thing -----------------------------------------------------

_PARSE = {
    "gfnav --accel-noise 1e300": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1",
                                   "--strategy", "fused", "--accel-noise", "1e300", *N0],
                                  "argument --accel-noise: must be finite and in (0, 1000] m/s^2; got 1e+300"),
    "navigate --h0 1e300": (["navigate", "a.csv", "o.csv", "--lat0", "30", "--lon0", "114", "--h0", "1e300"],
                            "argument --h0: must be finite and in (-3.18907e+06, 2.12605e+06) m; got 1e+300"),
    "integrate --outages 10,5,0": (["integrate", "i.csv", "g.pos", "o.csv", "--outages", "10,5,0"],
                                   "--outages 10,5,0: DURATION must be > 0 s, PERIOD >= DURATION"),
}


@pytest.mark.parametrize("case", sorted(_PARSE))
def test_options_name_the_limit_at_parse_time(case, capsys):
    """Before: gfnav --strategy fused --accel-noise 1e300: "strategy 'fused' needs ...
    Strategies that navigate it: 'fused'"; navigate --h0 1e300: "gf_sins_init: a parameter
    is out of its legal range (status 3)"."""
    args, message = _PARSE[case]
    with pytest.raises(SystemExit) as ei:
        main(args)
    assert ei.value.code == 2
    assert message in capsys.readouterr().err


def test_outages_outside_the_record_are_named_before_the_run(drive, tmp_path, capsys):
    """Before: integrate --outages 1e300,1e300,0: "zero-size array to reduction operation
    maximum which has no identity", after the outputs were written. (Under KF-GINS's
    protocol, issue 20, an outage of 1e300 s that starts inside the record is one outage to
    the end; none starting inside is what is refused.)"""
    folder, _, init = drive
    assert main(_integrate(folder, tmp_path / "out.csv", init, "--outages", "1e300,1e300,1e300")) == 2
    err = capsys.readouterr().err
    assert ("--outages 1e+300,1e+300,1e+300: no outage starting 1e+300 s after the first GNSS epoch "
            "removes a fix inside the aided span (0 to 20 s, 20 s long)") in err, err
    assert "zero-size" not in err and list(tmp_path.iterdir()) == []


def test_navigate_t0_after_the_record_is_named(tmp_path, capsys):
    """Before: navigate --t0 1e300: "sample 0: sample times must be strictly increasing"."""
    src = _csv(tmp_path / "rec.csv", _strapdown())
    assert main(["navigate", str(src), str(tmp_path / "o.csv"), *N0, "--t0", "1e300"]) == 2
    assert ("--t0 1e+300 s is not before the record's first time 0.01 s: the first increment covers "
            "the interval from --t0 to it") in capsys.readouterr().err


def test_a_missing_output_folder_is_named_before_the_run(tmp_path, capsys):
    """Before: "[Errno 2] No such file or directory: '.../out.csv.1a2b3c4d.partial'",
    after the run."""
    src = _csv(tmp_path / "rec.csv", _strapdown())
    out = tmp_path / "nowhere" / "out.csv"
    assert main(["navigate", str(src), str(out), *N0]) == 2
    err = capsys.readouterr().err
    assert f"{out}: its folder {out.parent} does not exist: create it" in err, err
    assert "Errno" not in err and "partial" not in err


def test_a_folder_given_as_input_is_named(tmp_path, capsys):
    """Before: a directory given as the IMU file: "no such file"."""
    (tmp_path / "imu").mkdir()
    assert main(["integrate", str(tmp_path / "imu"), str(tmp_path / "g.csv"), str(tmp_path / "o.csv"),
                 "--imu-format", "csv", "--initial=30,114,0,0,0,0"]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'imu'}: is a folder, not a file (an ImuRecord CSV was expected)" in err, err


def test_an_absurd_measurement_std_is_named(drive, tmp_path, capsys):
    """Before: an odometer (speed) std of 1e300 was reported as "IMU sample 0 holds NaN or
    Inf" (its variance overflowed in C)."""
    from gfins_fmi import io
    folder, d, init = drive
    n = 20
    io.OdometerRecord(t_s=np.arange(1, n + 1, dtype=float), speed_m_s=np.full(n, 5.0),
                      std_m_s=np.full(n, 1e300)).to_csv(tmp_path / "odo.csv")
    assert main(_integrate(folder, tmp_path / "out.csv", init, "--odometer", str(tmp_path / "odo.csv"))) == 2
    err = capsys.readouterr().err
    assert ("odometer at t = 1.0 s has a standard deviation of [1e+300] (in the record's units: m, "
            "m/s): above 1e+100 its variance overflows") in err, err
    assert "IMU sample" not in err
