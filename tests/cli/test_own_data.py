"""``gfins integrate`` on a user's own recording in KF-GINS's formats (issue 20's "Why"):
a simulated 300 s drive at 200 Hz (navigation-grade increments, 1 Hz GNSS at an antenna
0.3 m left, 0.2 m forward and 1.2 m above the IMU) written as KF-GINS's IMU and GNSS text
files and a ``.nav`` truth (and our TruthRecord CSV). Each test names what failed before.

Truths: the simulator's vehicle (gf_vehicle, itself checked against the independent
trajectory generator) and numpy formulas written here, never the code under test.
"""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from gfins_fmi.cli import main
from support.drives import kfgins_drive

LEVER = np.array([-0.3, 0.2, 1.2])      # body right, front, up, m
LEVER_TEXT = "-0.3,0.2,1.2"             # typed as people type it (no '=')


@pytest.fixture(scope="module")
def kf_drive(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kf_drive")
    d = kfgins_drive(folder, 300.0, 7, LEVER, truth=True)
    return folder, d


def _args(folder, out, *extra):
    return ["integrate", str(folder / "imu.txt"), str(folder / "gnss.txt"), str(out), "--imu-format", "kfgins",
            "--gnss-format", "kfgins", "--grade", "navigation", "--lever-arm", LEVER_TEXT, *extra]


def _initial(d, k=0):
    """--initial and --initial-velocity of the true state at truth row k."""
    tr = d.truth
    e = np.degrees(tr.euler_rad[k])
    return ["--initial", ",".join(repr(float(x)) for x in (np.degrees(tr.lat_rad[k]), np.degrees(tr.lon_rad[k]),
                                                          tr.h_m[k], e[0], e[1], e[2])),
            "--initial-velocity", ",".join(repr(float(x)) for x in tr.v_n_m_s[k])]


def _solution(path):
    with open(path) as fh:
        names = fh.readline().strip().split(",")
    return dict(zip(names, np.loadtxt(path, delimiter=",", skiprows=1).T))


def _rms(text, pattern):
    m = re.search(pattern, text)
    assert m, f"{pattern!r} not in the summary:\n{text}"
    return float(m.group(1))


# ---- evaluation -----------------------------------------------------------------------------

@pytest.mark.parametrize("truth", ["truth.nav", "truth.csv"])
def test_truth_plot_and_truth_scored_outages_for_every_truth_format(truth, kf_drive, tmp_path, capsys):
    """Before issue 21: --truth failed after the solution was written (exit 2), for a
    KF-GINS .nav and a TruthRecord CSV alike, and --plot and --outages with it. Now both
    formats score; the two give the same figures (the .nav's decimals: 1e-12 deg = 0.1 um)."""
    folder, d = kf_drive
    out = tmp_path / "sol.csv"
    rc = main(_args(folder, out, *_initial(d), "--truth", str(folder / truth), "--plot", str(tmp_path / "fig"),
                    "--outages", "30,100,100", "--smooth"))
    text = capsys.readouterr().out
    assert rc == 0, text
    hz = _rms(text, r"filter: error to the truth: horizontal RMS ([\d.]+) m")
    assert hz < 0.5, text          # GNSS at 2 cm with two 30 s outages of a navigation-grade IMU
    drift = _rms(text, r"filter: outage protocol \(2 outages, against the truth\): RMS of the maximum "
                       r"horizontal drift per outage ([\d.]+) m")
    assert 0 < drift < 5.0, text
    assert (tmp_path / "fig" / "integrate_filter.png").is_file()
    assert (tmp_path / "fig" / "integrate_smoother.png").is_file()


def _antenna_residuals(sol, gnss, lever):
    """The hand computation: at each GNSS epoch (they fall on IMU samples here), the
    solution row at that time, its antenna (attitude from the written heading, pitch and
    roll: C_b^n = Rz(-heading) Rx(pitch) Ry(roll), RFU body, ENU), minus the fix, ENU m."""
    from gfins_fmi.nav import earth
    t = sol["t_s"]
    k = np.searchsorted(t, gnss.t_s)
    ok = (k < len(t)) & (np.abs(t[np.minimum(k, len(t) - 1)] - gnss.t_s) < 1e-6)
    k, g = k[ok], np.flatnonzero(ok)
    hdg, pit, rol = (np.radians(sol[c][k]) for c in ("heading_deg", "pitch_deg", "roll_deg"))
    C = np.array(earth.quat_to_dcm(earth.euler_to_quat(hdg, pit, rol)))
    arm = C @ lever
    lat, lon, h = np.radians(sol["lat_deg"][k]), np.radians(sol["lon_deg"][k]), sol["h_m"][k]
    a = earth.WGS84.a
    e2 = earth.WGS84.e2
    glat = gnss.lat_rad[g]
    RN = a / np.sqrt(1 - e2 * np.sin(glat) ** 2)
    RM = RN * (1 - e2) / (1 - e2 * np.sin(glat) ** 2)
    e = (lon - gnss.lon_rad[g]) * (RN + gnss.h_m[g]) * np.cos(glat) + arm[:, 0]
    n = (lat - glat) * (RM + gnss.h_m[g]) + arm[:, 1]
    u = h - gnss.h_m[g] + arm[:, 2]
    return np.hypot(e, n), u


def test_summary_reports_residuals_at_the_antenna_where_gnss_exists(kf_drive, tmp_path, capsys):
    """Before: "horizontal difference to GNSS RMS 0.335 m" with the antenna 0.36 m from
    the IMU (the lever arm ignored), and GNSS interpolated straight across 60 s gaps. Now
    the residuals at the antenna and at the fixes used, equal to a hand computation
    (printed to 1 mm; the solution CSV's 1e-9 deg rounding is 0.1 mm)."""
    from gfins_fmi import io
    folder, d = kf_drive
    out = tmp_path / "sol.csv"
    assert main(_args(folder, out, *_initial(d))) == 0
    text = capsys.readouterr().out
    hz = _rms(text, r"filter: residuals to the GNSS fixes used \(\d+, at the antenna: lever arm "
                    r"-0.3,0.2,1.2 m\): horizontal RMS ([\d.]+) m")
    up = _rms(text, r"filter: residuals .* vertical RMS ([\d.]+) m")
    sol = _solution(out)
    gnss = io.read_kfgins_gnss(folder / "gnss.txt")
    h_hand, u_hand = _antenna_residuals(sol, gnss, LEVER)
    assert hz == pytest.approx(np.sqrt(np.mean(h_hand ** 2)), abs=1.5e-3), text
    assert up == pytest.approx(np.sqrt(np.mean(u_hand ** 2)), abs=1.5e-3), text
    # the fixes are at 2 cm: residuals of that order, not the 0.36 m of a forgotten lever arm
    assert hz < 0.08
    h_no_arm, _ = _antenna_residuals(sol, gnss, np.zeros(3))
    assert np.sqrt(np.mean(h_no_arm ** 2)) > 0.25


def test_outage_protocol_is_kfgins_one(kf_drive, tmp_path, capsys):
    """Before: the outage that ends after the record's end was dropped and both boundary
    fixes removed. Now KF-GINS's/pyins's protocol: outages at 100, 200 and 290 s after the
    first fix (the last ends after the record: scored too), the fixes with t0 < t < t0 + 30
    removed (29 per outage, the boundary fixes kept; the last one cut by the end), and
    without a truth the drift is scored against the removed fixes at the antenna."""
    folder, d = kf_drive
    out = tmp_path / "sol.csv"
    assert main(_args(folder, out, *_initial(d), "--outages", "30,100,100")) == 0
    text = capsys.readouterr().out
    t = d.gnss.t_s
    starts = t[0] + np.array([100.0, 200.0])
    starts = np.r_[starts, t[0] + 300.0] if t[0] + 300.0 < min(t[-1], d.imu.t_s[-1]) else starts
    removed = sum(int(np.sum((t > a) & (t < a + 30.0))) for a in starts)
    assert f"{len(starts)} simulated GNSS outages of 30 s (KF-GINS's protocol: the {removed} fixes strictly" \
        in text, text
    assert re.search(rf"filter: outage protocol \({len(starts)} outages, against the removed fixes at the antenna\)",
                     text), text


# ---- options as people type them -------------------------------------------------------------

def test_negative_vectors_typed_as_values(kf_drive, tmp_path, capsys):
    """Before: --lever-arm -0.3,0.2,1.2 failed ("expected one argument"); only
    --lever-arm=-0.3,... worked. Now both are the same value (the configuration written)."""
    folder, d = kf_drive
    for i, form in enumerate((["--lever-arm", LEVER_TEXT], [f"--lever-arm={LEVER_TEXT}"])):
        out = tmp_path / f"sol{i}.csv"
        args = _args(folder, out, *_initial(d))
        j = args.index("--lever-arm")
        args[j:j + 2] = form
        assert main(args) == 0
        doc = json.loads(out.with_suffix(".config.json").read_text())
        assert doc["filter"]["gnss_lever_arm_m"] == [-0.3, 0.2, 1.2]
    capsys.readouterr()


def test_noise_in_the_units_people_write(kf_drive, tmp_path, capsys):
    """Before: --noise took the VRW as a one-sided density in ug/sqrt(Hz) (0.03 m/s/sqrt(h)
    typed as 72.1, not 51), said only in a docstring. Now each value takes its unit;
    a bare number keeps its documented unit, and the help says which."""
    import argparse
    from gfins_fmi.cli.options import noise_values
    from gfins_fmi.cli.parser import build_parser
    # 0.03 m/s/sqrt(h) = 5e-4 m/s/sqrt(s) (Allan, two-sided); one-sided x sqrt(2); / 9.80665e-6
    vrw = 0.03 / 60.0 * np.sqrt(2.0) / 9.80665e-6
    assert noise_values("0.003,0.03m/s/sqrt(h),0.003,15mGal,1h") == pytest.approx(
        [0.003, vrw, 0.003, 15e-5 / 9.80665e-6, 3600.0], rel=1e-12)
    assert noise_values("0.003 deg/rt(h), 0.03 m/s/√h, 0.003deg/h, 15 ug, 3600 s") == pytest.approx(
        [0.003, vrw, 0.003, 15.0, 3600.0], rel=1e-12)
    with pytest.raises(argparse.ArgumentTypeError, match="VRW: unknown unit 'm/s'"):
        noise_values("0.003,0.03m/s,0.003,15,3600")
    helptext = build_parser()[1]["integrate"].format_help()
    assert "ONE-sided" in " ".join(helptext.split()) and "m/s/sqrt(h)" in helptext
    folder, d = kf_drive
    out = tmp_path / "sol.csv"
    assert main(_args(folder, out, *_initial(d), "--noise", "0.003,0.03m/s/sqrt(h),0.003,15mGal,1h")) == 0
    doc = json.loads(out.with_suffix(".config.json").read_text())
    assert doc["filter"]["imu"]["accel_vrw_ug_sqrt_hz"] == pytest.approx(vrw, rel=1e-12)
    capsys.readouterr()


# ---- exit codes --------------------------------------------------------------------------------

def test_a_failure_after_the_solution_is_written_exits_1_and_keeps_it(kf_drive, tmp_path, capsys, monkeypatch):
    """Before: any failure after the run (the scoring, a figure) was reported as a usage
    error (exit 2, "gfins integrate: error:") and the solution went with it. Now exit 1,
    "failed:", and the solution, its innovations and configuration are kept."""
    import gfins_fmi.cli.integrate as integrate
    import gfins_fmi.cli.integrate_stream as integrate_stream
    folder, d = kf_drive

    def broken(*a, **k):
        raise ValueError("a figure could not be drawn")
    monkeypatch.setattr(integrate, "_summary", broken)            # the whole-record run (--smooth)
    monkeypatch.setattr(integrate_stream.Scores, "lines", broken)  # the run in chunks
    for i, extra in enumerate(([], ["--smooth"])):
        out = tmp_path / f"sol{i}.csv"
        assert main(_args(folder, out, *_initial(d), *extra)) == 1
        err = capsys.readouterr().err
        assert err.startswith("gfins integrate: failed: the summary: a figure could not be drawn; the solution "
                              "was kept (written: "), err
        for name in (f"sol{i}.csv", f"sol{i}.innovations.csv", f"sol{i}.config.json"):
            assert (tmp_path / name).is_file()
    # a usage error stays 2
    with pytest.raises(SystemExit) as ei:
        main(_args(folder, out, "--position-std", "1,1,1"))
    assert ei.value.code == 2
    assert "--position-std describe the initial state of --initial" in capsys.readouterr().err


# ---- the initial state ------------------------------------------------------------------------

def test_initial_stds_from_the_command_line_match_the_python_api(kf_drive, tmp_path, capsys):
    """Before: --initial had fixed, undocumented stds (5 m, 0.5 m/s, 2/2/10 deg): from the
    exact state the heading wandered during the first stop. Now per-axis stds as options
    (KF-GINS's demo values here), printed, and the heading RMS equals the Python API's
    run with the same settings (acceptance: within 10 %; the same filter, so to 1e-6)."""
    from gfins_fmi import io
    from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
    from gfins_fmi.estimation.evaluation import navigation_errors
    from gfins_fmi.sim.scenarios import NAVIGATION
    folder, d = kf_drive
    stds = ["--position-std", "0.005,0.004,0.008", "--velocity-std", "0.003,0.004,0.004",
            "--attitude-std", "0.003,0.003,0.023"]
    out = tmp_path / "sol.csv"
    assert main(_args(folder, out, *_initial(d), *stds, "--truth", str(folder / "truth.nav"))) == 0
    text = capsys.readouterr().out
    assert "1-sigma position 0.005,0.004,0.008 m, velocity 0.003,0.004,0.004 m/s, attitude (tilt E, tilt N, " \
           "heading) 0.003,0.003,0.023 deg" in text
    cli_heading = _rms(text, r"filter: error to the truth: .* heading RMS ([\d.]+) deg")
    imu = io.read_kfgins_imu(folder / "imu.txt")
    gnss = io.read_kfgins_gnss(folder / "gnss.txt")
    t0 = float(imu.t_s[0] - np.median(np.diff(imu.t_s[:100])))
    nav0 = d.initial
    nav0 = type(nav0)(nav0.q_bn, nav0.v_n_m_s, nav0.lat_rad, nav0.lon_rad, nav0.h_m, t0)
    init = InitialState(nav0, position_std_m=(0.005, 0.004, 0.008), velocity_std_m_s=(0.003, 0.004, 0.004),
                        attitude_std_rad=tuple(np.radians([0.003, 0.003, 0.023])))
    cfg = FilterConfig(imu=NAVIGATION, input="increments", gnss_lever_arm_m=tuple(LEVER))
    sol = IntegratedNavigator(cfg, init).run(imu, gnss)
    api = np.degrees(navigation_errors(sol, io.read_kfgins_nav(folder / "truth.nav")).rms()["heading_rad"])
    assert cli_heading == pytest.approx(api, rel=0.10, abs=2e-4)
    assert cli_heading < 0.05, text     # a navigation-grade IMU from its true state


def test_a_record_that_starts_moving(kf_drive, tmp_path, capsys):
    """Before: a record that starts moving could not be processed from the command line
    (--initial meant at rest: every GNSS update gated, a 10 deg heading error). Now
    --initial-velocity (or --initial truth) starts it in motion: no update gated."""
    from gfins_fmi.io.kfgins import KFGINS_IMU_FORMAT, kfgins_imu_table
    folder, d = kf_drive
    k = int(np.searchsorted(d.truth.t_s, 60.0))        # mid-drive
    speed = float(np.linalg.norm(d.truth.v_n_m_s[k]))
    assert speed > 5.0
    imu = d.imu
    sel = imu.t_s > d.truth.t_s[k]
    import dataclasses
    np.savetxt(tmp_path / "imu.txt", kfgins_imu_table(dataclasses.replace(imu, t_s=imu.t_s[sel], gyro=imu.gyro[sel],
                                                                         accel=imu.accel[sel])),
               fmt=KFGINS_IMU_FORMAT)
    (tmp_path / "gnss.txt").write_bytes((folder / "gnss.txt").read_bytes())
    (tmp_path / "truth.nav").write_bytes((folder / "truth.nav").read_bytes())
    for how in (_initial(d, k), ["--initial", "truth"]):
        out = tmp_path / "sol.csv"
        assert main(_args(tmp_path, out, *how, "--truth", str(tmp_path / "truth.nav"))) == 0, how
        text = capsys.readouterr().out
        assert re.search(r"'gated': 0\b", text), text
        assert _rms(text, r"heading RMS ([\d.]+) deg") < 1.0, text   # the 10 deg default heading std converging


# ---- the KF-GINS drop-in ------------------------------------------------------------------------

def _kfgins_yaml(folder, d, out_folder):
    """A KF-GINS configuration file of the drive, as KF-GINS's own (dataset/kf-gins.yaml): the
    true initial state in its frames (NED velocity; roll, pitch, yaw; antenna lever arm
    forward, right, down) and the navigation grade's noise in its units."""
    from gfins_fmi.cli.kfgins_config import kfgins_config_text, kfgins_noise_block
    from gfins_fmi.sim.scenarios import NAVIGATION
    tr = d.truth
    return "# KF-GINS configuration file\n" + kfgins_config_text(
        folder / "imu.txt", folder / "gnss.txt", out_folder, float(d.imu.t_s[0]) - 0.005, tr.lat_rad[0],
        tr.lon_rad[0], tr.h_m[0], tr.v_n_m_s[0], tr.euler_rad[0], LEVER, kfgins_noise_block(NAVIGATION))


def test_kfgins_configuration_runs_unchanged_and_writes_kfgins_files(kf_drive, tmp_path, capsys):
    """Before: no way to run a KF-GINS configuration file, nor to write KF-GINS's output
    files. Now `gfins integrate --kfgins-config their.yaml` reads it as it is and writes
    KF_GINS_Navresult.nav (11 columns), KF_GINS_IMU_ERR.txt (13) and KF_GINS_STD.txt (22),
    numbers with KF-GINS's 9 decimals; the .nav scores within 1 % of the Python API's run
    with the same settings (the same filter: the difference is the 1e-9 deg rounding)."""
    from gfins_fmi import io
    from gfins_fmi.estimation import FilterConfig, IntegratedNavigator
    from gfins_fmi.cli.kfgins_config import initial_state, read_kfgins_config
    from gfins_fmi.estimation.config import SENSOR_NAMES
    from gfins_fmi.estimation.evaluation import navigation_errors
    folder, d = kf_drive
    out = tmp_path / "result"
    out.mkdir()
    cfg_path = tmp_path / "kf-gins.yaml"
    cfg_path.write_text(_kfgins_yaml(folder, d, out))
    assert main(["integrate", "--kfgins-config", str(cfg_path), "--truth", str(folder / "truth.nav")]) == 0
    text = capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["KF_GINS.config.json", "KF_GINS_IMU_ERR.txt",
                                                      "KF_GINS_Navresult.innovations.csv", "KF_GINS_Navresult.nav",
                                                      "KF_GINS_STD.txt"]
    for name, cols in (("KF_GINS_Navresult.nav", 11), ("KF_GINS_IMU_ERR.txt", 13), ("KF_GINS_STD.txt", 22)):
        first = (out / name).read_text().splitlines()[0].split(" ")
        assert len(first) == cols, (name, first)
        assert all(re.fullmatch(r"-?\d+\.\d{9}|NaN", x) for x in first), (name, first)
    nav = io.read_kfgins_nav(out / "KF_GINS_Navresult.nav")
    truth = io.read_kfgins_nav(folder / "truth.nav")
    cli = navigation_errors(nav, truth).rms()
    # the Python API with the same settings, from the same reading of the file
    kf = read_kfgins_config(cfg_path)
    imu = io.read_kfgins_imu(folder / "imu.txt")
    gnss = io.read_kfgins_gnss(folder / "gnss.txt")
    sel = imu.t_s > imu.t_s[0]
    rec = io.ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind="increments")
    cfg = FilterConfig(imu=kf.noise, input="increments", gnss_lever_arm_m=tuple(LEVER), scale_factors=True,
                       gyro_scale_std=300e-6, accel_scale_std=300e-6, gyro_scale_tau_s=kf.correlation_s,
                       accel_scale_tau_s=kf.correlation_s)
    sol = IntegratedNavigator(cfg, initial_state(kf, float(imu.t_s[0]), len(SENSOR_NAMES))).run(rec, gnss)
    api = navigation_errors(sol, truth).rms()
    assert cli["horizontal_m"] == pytest.approx(api["horizontal_m"], rel=0.01)
    assert cli["pos_enu_m"][2] == pytest.approx(api["pos_enu_m"][2], rel=0.01)
    assert cli["heading_rad"] == pytest.approx(api["heading_rad"], rel=0.01)
    assert cli["horizontal_m"] < 0.05, text
    # the antenna's lever arm came from antlever (FRD -> RFU)
    doc = json.loads((out / "KF_GINS.config.json").read_text())
    assert doc["filter"]["gnss_lever_arm_m"] == pytest.approx(list(LEVER))
    with pytest.raises(SystemExit):   # the files come from the configuration
        main(["integrate", "--kfgins-config", str(cfg_path), str(folder / "imu.txt")])


def test_progress_covers_reading_and_writing(kf_drive, tmp_path, capsys, monkeypatch):
    """Before: --progress covered the filter (0.1-0.3 s) but not reading and writing (over
    80 % of the time). Now a line per stage with its time."""
    import gfins_fmi.cli.integrate as integrate
    folder, d = kf_drive
    # the whole record (the path of the other formats), --smooth: a line per stage
    with monkeypatch.context() as m:
        m.setattr(integrate, "_streamed", lambda args: False)
        assert main(_args(folder, tmp_path / "sol.csv", *_initial(d), "--progress", "--smooth")) == 0
    err = capsys.readouterr().err
    for stage in (f"reading {folder / 'imu.txt'}", "reading the GNSS and the other records", "writing the solution"):
        assert re.search(rf"gfins integrate: {re.escape(stage)}: [\d.]+ s", err), err
    # in chunks: one bar over reading, filtering and writing, in record seconds; with
    # --smooth one over the backward pass (epochs) and one over the smoothed rows
    assert main(_args(folder, tmp_path / "sol.csv", *_initial(d), "--progress", "--smooth")) == 0
    err = capsys.readouterr().err
    for bar in ("read, filter, write (record seconds): 100%", "smoother, backward: 100%",
                "smoother, applied: 100%"):
        assert bar in err, err
    assert "warning" not in err, err


def test_chunks_give_the_whole_records_result(kf_drive, tmp_path, capsys, monkeypatch):
    """The run in chunks (issue 20: memory independent of the record's length) writes the
    same files and prints the same summary as the whole record read at once, bit for bit:
    chunks of 7001 samples (not a divisor of anything here) against one."""
    import gfins_fmi.cli.integrate as integrate
    folder, d = kf_drive
    extra = [*_initial(d), "--truth", str(folder / "truth.nav"), "--outages", "30,100,100"]
    outs = {}
    for name, chunk in (("whole", 10 ** 9), ("chunks", 7001)):
        monkeypatch.setattr(integrate, "STREAM_CHUNK", chunk)
        out = tmp_path / f"{name}.csv"
        assert main(_args(folder, out, *extra)) == 0
        text = capsys.readouterr().out
        outs[name] = (out.read_bytes(), out.with_suffix(".innovations.csv").read_bytes(),
                      [x for x in text.splitlines() if x.startswith("filter:")])
    assert outs["whole"][0] == outs["chunks"][0]
    assert outs["whole"][1] == outs["chunks"][1]
    assert outs["whole"][2] == outs["chunks"][2] and len(outs["whole"][2]) == 2
    # and without a truth: the residuals, with fixes between two chunks
    for name, chunk in (("whole", 10 ** 9), ("chunks", 7001)):
        monkeypatch.setattr(integrate, "STREAM_CHUNK", chunk)
        assert main(_args(folder, tmp_path / f"{name}2.csv", *_initial(d), "--outages", "30,100,100")) == 0
        outs[name] = [x for x in capsys.readouterr().out.splitlines() if x.startswith("filter:")]
    assert outs["whole"] == outs["chunks"] and len(outs["whole"]) == 2


def test_kfgins_starttime_past_the_first_chunk(kf_drive, tmp_path, capsys, monkeypatch):
    """KF-GINS's starttime minutes into the file: the run in chunks starts in the chunk
    that holds it and writes what the whole record read at once writes."""
    import gfins_fmi.cli.integrate as integrate
    folder, d = kf_drive
    k = int(np.searchsorted(d.truth.t_s, 100.0))
    text = _kfgins_yaml(folder, d, "OUT")
    tr = d.truth
    e = [float(x) for x in np.degrees(tr.euler_rad[k])]
    v = [float(x) for x in tr.v_n_m_s[k]]
    lines = []
    for line in text.splitlines():
        key = line.split(":")[0]
        if key == "starttime":
            line = f"starttime: {float(tr.t_s[k])!r}"
        elif key == "initpos":
            line = (f"initpos: [ {float(np.degrees(tr.lat_rad[k]))!r}, {float(np.degrees(tr.lon_rad[k]))!r}, "
                    f"{float(tr.h_m[k])!r} ]")
        elif key == "initvel":
            line = f"initvel: [ {v[1]!r}, {v[0]!r}, {-v[2]!r} ]"
        elif key == "initatt":
            line = f"initatt: [ {e[2]!r}, {e[1]!r}, {e[0]!r} ]"
        lines.append(line)
    navs = {}
    for name, chunk in (("whole", 10 ** 9), ("chunks", 7001)):
        out = tmp_path / name
        out.mkdir()
        cfg = tmp_path / f"{name}.yaml"
        cfg.write_text("\n".join(lines).replace('outputpath: "OUT"', f'outputpath: "{out}"') + "\n")
        monkeypatch.setattr(integrate, "STREAM_CHUNK", chunk)
        assert main(["integrate", "--kfgins-config", str(cfg)]) == 0
        capsys.readouterr()
        navs[name] = (out / "KF_GINS_Navresult.nav").read_bytes()
    assert navs["whole"] == navs["chunks"]
    first = float(navs["chunks"].split(b"\n")[0].split()[1])
    assert first == pytest.approx(float(tr.t_s[k]) + 0.005, abs=1e-6)


# ---- the configuration file -------------------------------------------------------------------

def test_a_configuration_file_runs_like_its_options_and_a_run_repeats(kf_drive, tmp_path, capsys):
    """Before: every setting on the command line, the filter's other settings only from
    Python. Now --config FILE.toml: options by name (through their own parsers: units,
    bounds), a [filter] table of the settings table, paths relative to the file; the
    command line overrides it; a run's OUT.config.json repeats it exactly; --print-config
    writes the template; a setting that is not one is refused by name."""
    folder, d = kf_drive
    init = _initial(d)
    cfg = tmp_path / "run.toml"
    (tmp_path / "data").symlink_to(folder)
    cfg.write_text(f"""imu = "data/imu.txt"
gnss = "data/gnss.txt"
output = "a.csv"
imu_format = "kfgins"
gnss-format = "kfgins"
grade = "navigation"
lever_arm = [-0.3, 0.2, 1.2]
initial = "{init[1]}"
initial_velocity = "{init[3]}"
position_std = [0.005, 0.004, 0.008]

[filter]
propagation_interval_s = 0.05
""")
    assert main(["integrate", "--config", str(cfg)]) == 0
    a = tmp_path / "a.csv"
    args = _args(folder, tmp_path / "b.csv", *init, "--position-std", "0.005,0.004,0.008",
                 "--propagation-interval", "0.05")
    assert main(args) == 0
    assert a.read_bytes() == (tmp_path / "b.csv").read_bytes()
    doc = json.loads(a.with_suffix(".config.json").read_text())
    assert doc["filter"]["propagation_interval_s"] == 0.05 and doc["filter"]["gnss_lever_arm_m"] == [-0.3, 0.2, 1.2]
    # the run repeated from its own OUT.config.json (into another output)
    replay = tmp_path / "replay.json"
    replay.write_text(a.with_suffix(".config.json").read_text())
    assert main(["integrate", "--config", str(replay), str(folder / "imu.txt"), str(folder / "gnss.txt"),
                 str(tmp_path / "c.csv")]) == 0
    assert (tmp_path / "c.csv").read_bytes() == a.read_bytes()
    # the command line overrides the file
    assert main(["integrate", "--config", str(cfg), "--lever-arm", "0,0,0", "--propagation-interval", "0.2"]) == 0
    doc = json.loads(a.with_suffix(".config.json").read_text())
    assert doc["filter"]["gnss_lever_arm_m"] == [0.0, 0.0, 0.0] and doc["filter"]["propagation_interval_s"] == 0.2
    capsys.readouterr()
    cfg.write_text(cfg.read_text() + "propagation_interval = 0.1\n")   # an option's name inside [filter]
    assert main(["integrate", "--config", str(cfg)]) == 2
    assert "[filter] propagation_interval: not a filter setting" in capsys.readouterr().err
    assert main(["integrate", "--print-config"]) == 0
    template = capsys.readouterr().out
    assert "# lever_arm = " in template and "[filter]" in template and "# gate_probability" in template


def test_the_noise_block_inside_the_configuration_file(kf_drive, tmp_path, capsys):
    """The noise block (issue 23's [imu]/[noise] tables, as gfins noise writes them) folded
    into the configuration file: read by its one reader, the same run as --noise-file."""
    from gfins_fmi.estimation.noise_file import noise_text
    from gfins_fmi.nav.imu_errors import ImuNoise
    folder, d = kf_drive
    init = _initial(d)
    noise = ImuNoise(gyro_arw_deg_sqrt_h=0.004, accel_vrw_ug_sqrt_hz=80.0, gyro_bias_instability_deg_h=0.03,
                     accel_bias_instability_ug=20.0, gyro_correlation_time_s=1800.0, accel_correlation_time_s=1800.0)
    (tmp_path / "noise.toml").write_text(noise_text(noise))
    cfg = tmp_path / "run.toml"
    cfg.write_text(f'''imu_format = "kfgins"
gnss_format = "kfgins"
lever_arm = "-0.3,0.2,1.2"
initial = "{init[1]}"
initial_velocity = "{init[3]}"

[inputs]        # TOML cannot hold a key imu beside the noise block's table [imu]
imu = "{folder / 'imu.txt'}"
gnss = "{folder / 'gnss.txt'}"
output = "a.csv"

''' + noise_text(noise))
    assert main(["integrate", "--config", str(cfg)]) == 0
    assert main(_args(folder, tmp_path / "b.csv", *init, "--noise-file", str(tmp_path / "noise.toml"))) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    doc = json.loads((tmp_path / "a.config.json").read_text())
    assert doc["filter"]["imu"]["gyro_arw_deg_sqrt_h"] == 0.004
    capsys.readouterr()


def test_binary_imu_in_chunks_gives_the_texts_result(kf_drive, tmp_path, capsys, monkeypatch):
    """KF-GINS's binary IMU form (seven float64 a sample) read a chunk at a time (before:
    memory-mapped, its pages resident as the record passed: 541 MiB peak for 10 h at
    200 Hz) writes the values the same record as text writes, bit for bit; a file that is not a
    whole number of samples is refused with its size."""
    import gfins_fmi.cli.integrate as integrate
    pq = pytest.importorskip("pyarrow.parquet")
    folder, d = kf_drive
    table = np.loadtxt(folder / "imu.txt")
    bin_path = tmp_path / "imu.bin"
    table.astype("<f8").tofile(bin_path)
    outs = {}
    for name, imu, chunk in (("text", folder / "imu.txt", 10 ** 9), ("bin", bin_path, 7001)):
        monkeypatch.setattr(integrate, "STREAM_CHUNK", chunk)
        out = tmp_path / f"{name}.parquet"
        argv = _args(folder, out, *_initial(d))
        argv[1] = str(imu)
        assert main(argv) == 0
        capsys.readouterr()
        outs[name] = pq.read_table(out)
    assert outs["text"].column_names == outs["bin"].column_names and outs["text"].num_rows == len(table)
    for c in outs["text"].column_names:     # bit for bit (the row groups follow the chunks)
        a, b = (outs[k][c].to_numpy() for k in ("text", "bin"))
        assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), c
    bad = tmp_path / "cut.bin"
    bad.write_bytes(bin_path.read_bytes()[:-8])
    argv = _args(folder, tmp_path / "cut.parquet", *_initial(d))
    argv[1] = str(bad)
    assert main(argv) != 0
    assert f"{bad}: {len(table) * 56 - 8} bytes is not a whole number of 56-byte samples" in capsys.readouterr().err


# ---- the smoother in chunks ---------------------------------------------------------------------

def _short_drive(kf_drive, tmp_path, seconds=30.0):
    """The drive's first ``seconds``: KF-GINS IMU and GNSS text, the .nav truth (small and
    fast; its fixes on whole seconds, as the samples every 5 ms)."""
    folder, d = kf_drive
    out = tmp_path / "short"
    out.mkdir()
    t_end = float(d.imu.t_s[0]) + seconds
    for name in ("imu.txt", "gnss.txt", "truth.nav"):
        lines = (folder / name).read_text().splitlines(keepends=True)
        (out / name).write_text("".join(x for x in lines if float(x.split()[0]) <= t_end))
    return out


def test_smoother_in_chunks_gives_the_whole_records_result(kf_drive, tmp_path, capsys, monkeypatch):
    """Before: --smooth held the whole record and the whole solution (619 MiB for 30
    minutes). Now it runs in chunks (epochs and rows on disk, the backward pass in blocks):
    the files and the summary are the whole-record run's, bit for bit — chunks of 2001
    samples (10 s), blocks of 5 epochs, with a truth and outages, then KF-GINS's
    configuration without a truth (residuals); no temporary file is left."""
    import gfins_fmi.cli.integrate as integrate
    import gfins_fmi.cli.integrate_smooth as integrate_smooth
    _, d = kf_drive
    short = _short_drive(kf_drive, tmp_path)
    extra = [*_initial(d), "--truth", str(short / "truth.nav"), "--outages", "10,20,15", "--smooth"]
    got = {}
    for name in ("whole", "chunks"):
        with monkeypatch.context() as m:
            if name == "whole":
                m.setattr(integrate, "_streamed", lambda args: False)
            m.setattr(integrate, "STREAM_CHUNK", 2001)
            m.setattr(integrate_smooth, "SMOOTH_BLOCK_EPOCHS", 5)
            out = tmp_path / f"{name}.csv"
            assert main(_args(short, out, *extra)) == 0
        text = capsys.readouterr().out
        got[name] = ([out.with_suffix(s).read_bytes() for s in (".csv", ".innovations.csv", ".smoothed.csv")],
                     [x for x in text.splitlines() if x.startswith(("filter:", "smoother:"))])
    assert got["chunks"][0][2] == got["whole"][0][2], "the smoothed solutions differ"
    assert got["chunks"][0][:2] == got["whole"][0][:2], "the forward solutions differ"
    assert got["chunks"][1] == got["whole"][1] and len(got["whole"][1]) == 4, got
    # KF-GINS's configuration, the residuals to GNSS
    for name in ("whole", "chunks"):
        res = tmp_path / f"kf_{name}"
        res.mkdir()
        cfg_path = tmp_path / f"kf_{name}.yaml"
        cfg_path.write_text(_kfgins_yaml(short, d, res))
        with monkeypatch.context() as m:
            if name == "whole":
                m.setattr(integrate, "_streamed", lambda args: False)
            m.setattr(integrate, "STREAM_CHUNK", 2001)
            m.setattr(integrate_smooth, "SMOOTH_BLOCK_EPOCHS", 5)
            assert main(["integrate", "--kfgins-config", str(cfg_path), "--smooth"]) == 0
        text = capsys.readouterr().out
        got[name] = ({p.name: p.read_bytes() for p in res.iterdir() if p.suffix != ".json"},
                     [x for x in text.splitlines() if x.startswith(("filter:", "smoother:"))])
    assert "KF_GINS_Navresult.smoothed.nav" in got["whole"][0]      # KF-GINS's .nav format
    for k in got["whole"][0]:
        a, b = got["chunks"][0].get(k, b"").splitlines(), got["whole"][0][k].splitlines()
        # the fix at the start time (before the first increment) logged as stale by both:
        # the first chunk takes the epochs before the start too
        assert a == b, (k, len(a), len(b), [(x, y) for x, y in zip(a, b) if x != y][:3])
    assert got["chunks"][1] == got["whole"][1] and len(got["whole"][1]) == 2, got[1]
    assert not [p for p in tmp_path.rglob("*") if ".tmp" in p.name], "temporary files left"


def test_smoother_in_chunks_keeps_the_solution_and_leaves_nothing_on_failure(kf_drive, tmp_path, capsys,
                                                                              monkeypatch):
    """A failure in the smoother (a full disk, a block refused in C) exits 1 with the
    forward solution kept and no smoothed file; a Ctrl-C in it exits 130 and leaves nothing; a sample the filter
    refuses leaves the partial tables; none leaves the smoother's temporary folder behind."""
    import gfins_fmi.estimation.smoother_stream as smoother_stream
    _, d = kf_drive
    short = _short_drive(kf_drive, tmp_path, 20.0)
    real = smoother_stream.StreamingSmoother.solutions
    from gfins_fmi._lib import GfinsError
    cases = (("disk", OSError("No space left on device"), 1),
             ("c", GfinsError("gf_ins_smooth_block (epochs 0 to 5 of 9): not positive definite"), 1),
             ("ctrl_c", KeyboardInterrupt(), 130))
    for name, exc, code in cases:
        def broken(self, *a, **k):
            it = real(self, *a, **k)
            yield next(it)
            raise exc
        out = tmp_path / f"sol_{name}.csv"
        with monkeypatch.context() as m:
            m.setattr(smoother_stream.StreamingSmoother, "solutions", broken)
            assert main(_args(short, out, *_initial(d), "--smooth")) == code, name
        err = capsys.readouterr().err
        left = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(f"sol_{name}"))
        if code == 1:
            assert f"failed: the smoother: {exc}; the solution was kept" in err, err
            assert left == [f"sol_{name}.config.json", f"sol_{name}.csv", f"sol_{name}.innovations.csv"], left
        else:
            assert "interrupted" in err and left == [], (err, left)
        assert not [p for p in tmp_path.rglob("*") if ".tmp" in p.name], "temporary files left"
    # a sample the filter refuses (50 rad in one 5 ms increment) in the forward pass: the
    # rows before it kept as partial tables, nothing smoothed, nothing temporary left
    lines = (short / "imu.txt").read_text().splitlines(keepends=True)
    cols = lines[3000].split()
    lines[3000] = " ".join([cols[0], "50.0", *cols[2:]]) + "\n"
    (short / "imu.txt").write_text("".join(lines))
    assert main(_args(short, tmp_path / "bad.csv", *_initial(d), "--smooth")) == 1
    assert "the 3000 samples before it are in" in capsys.readouterr().err
    left = sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("bad"))
    assert left == ["bad.config.partial.json", "bad.innovations.partial.csv", "bad.partial.csv"], left
    assert not [p for p in tmp_path.rglob("*") if ".tmp" in p.name], "temporary files left"


def test_smoothed_solution_in_the_outputs_format(kf_drive, tmp_path, capsys):
    """Before: the smoothed table was OUT.smoothed.csv whatever OUT's format (a Parquet run
    of 10 h wrote 3.8 GB of CSV beside it). Now it is OUT.smoothed.parquet for OUT.parquet,
    with the same numbers as the CSV run's smoothed table (the CSV's shortest round-trip
    digits read back: equal to the bit)."""
    import pyarrow.parquet as pq
    _, d = kf_drive
    short = _short_drive(kf_drive, tmp_path, seconds=20.0)
    tables = {}
    for suffix in (".csv", ".parquet"):
        out = tmp_path / f"sol{suffix}"
        assert main(_args(short, out, *_initial(d), "--smooth")) == 0
        assert f"(smoothed) -> {tmp_path / ('sol.smoothed' + suffix)}" in capsys.readouterr().out
        tables[suffix] = tmp_path / f"sol.smoothed{suffix}"
    pq_table = pq.read_table(tables[".parquet"])
    csv = np.genfromtxt(tables[".csv"], delimiter=",", names=True)
    assert pq_table.num_rows == len(csv) > 3000
    for name in ("t_s", "lat_deg", "lon_deg", "h_m", "heading_deg"):
        np.testing.assert_array_equal(pq_table.column(name).to_numpy(), csv[name], err_msg=name)
