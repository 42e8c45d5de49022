"""``gfins integrate`` in chunks for every IMU format and every start (issue 20, "What to
build" 5: memory independent of the record's length). The run in chunks must write what
the whole record read at once writes, bit for bit: each test runs both paths (the whole
record forced by ``integrate._streamed``) with tiny chunks (many boundaries, none on a
divisor of anything here) and compares the files' bytes and the printed summary. The
truth is the whole-record path, which these changes leave as it was (the golden
outputs, bench/golden_outputs.py, hash it).
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.cli import main

#: samples per chunk in the runs in chunks: the drive's 1800 samples give 18 boundaries
CHUNK = 97
LEVER = "0.3,1.1,1.5"
RTK = __import__("pathlib").Path(__file__).parents[1] / "data" / "rtk_walk"


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """A 36 s drive at 50 Hz (tactical IMU, 1 Hz GNSS with velocity) that starts with
    8 s at rest, as our ImuRecord in CSV, Parquet and npz, a GnssRecord CSV and a
    TruthRecord CSV."""
    from gfins_fmi import io
    from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive
    from gfins_fmi.sim.vehicle import GnssReceiver, Segment, VehicleProfile
    folder = tmp_path_factory.mktemp("stream_drive")
    prof = VehicleProfile(segments=[Segment(8.0), Segment(8.0, dspeed_m_s=10.0), Segment(10.0, dheading_rad=1.5),
                                    Segment(10.0)], lat0_rad=0.6, lon0_rad=2.0, h0_m=30.0, heading0_rad=0.4)
    d = simulate_drive(prof, 36.0, 0.02, imu=TACTICAL, gnss=GnssReceiver(lever_arm_m=(0.3, 1.1, 1.5)), seed=5)
    d.imu.to_csv(folder / "imu.csv")
    cols = {"t_s": d.imu.t_s, **{f"gyro_{x}_rad": d.imu.gyro[:, j] for j, x in enumerate("xyz")},
            **{f"accel_{x}_m_s": d.imu.accel[:, j] for j, x in enumerate("xyz")}}
    np.savez(folder / "imu.npz", **cols)
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq
    pq.write_table(pa.table(cols), folder / "imu.parquet", row_group_size=1000)
    from gfins_fmi.io.kfgins import KFGINS_IMU_FORMAT, kfgins_imu_table
    np.savetxt(folder / "imu.txt", kfgins_imu_table(d.imu), fmt=KFGINS_IMU_FORMAT)
    np.ascontiguousarray(kfgins_imu_table(d.imu), dtype="<f8").tofile(folder / "imu.bin")
    d.gnss.to_csv(folder / "gnss.csv")
    tr = d.truth
    io.TruthRecord(tr.t_s, tr.lat_rad, tr.lon_rad, tr.h_m, tr.v_n_m_s, tr.euler_rad).to_csv(folder / "truth.csv")
    return folder, d


def _initial(d):
    tr = d.truth
    e = np.degrees(tr.euler_rad[0])
    return ["--initial", ",".join(repr(float(x)) for x in (np.degrees(tr.lat_rad[0]), np.degrees(tr.lon_rad[0]),
                                                          tr.h_m[0], e[0], e[1], e[2]))]


def _both(monkeypatch, capsys, tmp_path, args):
    """The run's files and printed lines, whole and in chunks of CHUNK."""
    import gfins_fmi.cli.integrate as integrate
    out = {}
    for name in ("whole", "chunks"):
        with monkeypatch.context() as m:
            if name == "whole":
                m.setattr(integrate, "_streamed", lambda a: False)
            m.setattr(integrate, "STREAM_CHUNK", CHUNK)
            sol = tmp_path / f"{name}.csv"
            rc = main([*args[:3], str(sol), *args[3:]])
            cap = capsys.readouterr()
            assert rc == 0, cap.err
            text = cap.out.replace(str(sol), "SOL").replace(str(sol.with_suffix(".innovations.csv")), "INN")
            out[name] = (sol.read_bytes(), sol.with_suffix(".innovations.csv").read_bytes(), text)
    return out


def _same(out):
    whole, chunks = out["whole"], out["chunks"]
    assert whole[0] == chunks[0], "the solution in chunks differs from the whole record's"
    assert whole[1] == chunks[1], "the innovation log in chunks differs from the whole record's"
    assert whole[2] == chunks[2], f"printed lines differ:\n{whole[2]}\n---\n{chunks[2]}"


@pytest.mark.parametrize("fmt", ["csv", "parquet", "npz", "txt", "bin"])
def test_every_format_with_the_default_start(fmt, drive, tmp_path, capsys, monkeypatch):
    """The default start (static alignment over the first 5 s) in chunks of 97 samples:
    the window read from the head (three chunks hold the 5 s), the rest streamed from the
    sample after it; our CSV, Parquet and npz, KF-GINS text and .bin. Before: read whole
    (Parquet and npz not read at all), and where the window's end t0 + 5 s fell a rounding
    before a sample's time (our CSV here: 0.02 + 5 < 251 x 0.02) the next increment got an
    interval of 1e-15 s and the filter refused it (exit 1, "IMU sample 0 exceeds |w|")."""
    folder, d = drive
    out = _both(monkeypatch, capsys, tmp_path, [
        "integrate", str(folder / f"imu.{fmt}"), str(folder / "gnss.csv"),
        "--imu-format", "kfgins" if fmt in ("txt", "bin") else "csv",
        "--gnss-format", "csv", "--grade", "tactical", f"--lever-arm={LEVER}", "--truth", str(folder / "truth.csv")])
    _same(out)
    assert "alignment:" in out["chunks"][2] and "filter: error to the truth" in out["chunks"][2]
    rows = out["chunks"][0].count(b"\n") - 1
    # the run starts at the end of the 5 s window, on the last sample at or before it (an
    # increment ends at its time): the samples after that one, the times as the file has them
    t = np.loadtxt(folder / "imu.txt", usecols=0) if fmt == "txt" else d.imu.t_s   # txt: 9 decimals
    end = t[t <= t[0] + 5.0][-1]
    assert rows == int(np.sum(t > end)), rows


@pytest.mark.parametrize("extra", [["--subsamples", "2"], ["--imu-errors"], ["--subsamples", "3", "--imu-errors"]])
@pytest.mark.parametrize("start", ["--initial", "truth"])
def test_given_starts_in_chunks(start, extra, drive, tmp_path, capsys, monkeypatch):
    """--initial (and the state of the truth file at the record's start), with
    --imu-errors and --subsamples (groups of samples across chunks of 97), the
    outage protocol's score, in chunks."""
    folder, d = drive
    errs = tmp_path / "errors.toml"
    errs.write_text("[imu_errors]\ngyro_bias_deg_h = [3.0, -2.0, 1.0]\naccel_bias_ug = [500.0, 200.0, -300.0]\n"
                    "gyro_scale_ppm = [100.0, -50.0, 20.0]\n")
    init = _initial(d) if start == "--initial" else ["--initial", "truth", "--truth", str(folder / "truth.csv")]
    extra = [x for e in extra for x in ([e, str(errs)] if e == "--imu-errors" else [e])]
    out = _both(monkeypatch, capsys, tmp_path, [
        "integrate", str(folder / "imu.parquet"), str(folder / "gnss.csv"), "--imu-format", "csv",
        "--gnss-format", "csv", "--grade", "tactical", f"--lever-arm={LEVER}", *init, *extra,
        "--outages", "4,10,8"])
    _same(out)
    assert "outage protocol (3 outages" in out["chunks"][2], out["chunks"][2]


def test_rtk_walk_rates_in_chunks(tmp_path, capsys, monkeypatch):
    """The rtk_walk record (rates, uneven sampling, a real MEMS IMU) cut to its first
    3000 samples: the default start (--static 9) and --subsamples 2 (the rates made
    increments by the trapezoid across the chunks' boundaries)."""
    imu = tmp_path / "imu.csv"
    imu.write_text("".join((RTK / "imu_1730_sf.csv").read_text().splitlines(keepends=True)[:3000]))
    for extra in ([], ["--subsamples", "2"]):
        out = _both(monkeypatch, capsys, tmp_path, [
            "integrate", str(imu), str(RTK / "gnss_1730_sf.pos"), "--imu-format", "rtk_walk", "--grade",
            "consumer", "--static", "9", "--zupt", "--lever-arm=0,0,0.05", *extra])
        _same(out)


def _table_error(path, monkeypatch, capsys, tmp_path, folder):
    """The whole-record error (exit 2) and the run in chunks' (exit 1, partial kept)."""
    import gfins_fmi.cli.integrate as integrate
    args = ["integrate", str(path), str(folder / "gnss.csv"), "", "--imu-format", "csv", "--gnss-format", "csv",
            "--grade", "tactical", "--initial", "34,2,30,0,0,0"]
    out = {}
    for name in ("whole", "chunks"):
        with monkeypatch.context() as m:
            if name == "whole":
                m.setattr(integrate, "_streamed", lambda a: False)
            m.setattr(integrate, "STREAM_CHUNK", CHUNK)
            args[3] = str(tmp_path / f"{name}_sol.csv")
            rc = main(args)
            out[name] = (rc, capsys.readouterr().err)
    return out


@pytest.mark.parametrize("defect", ["time", "gyro"])
def test_a_bad_sample_past_the_first_chunk(defect, drive, tmp_path, capsys, monkeypatch):
    """A time that goes back, or a gyro value that is not finite, in the 9th chunk: the
    run in chunks says what the whole-record reader says (the row of the whole record,
    the line of the file), exits 1 and keeps the solution before it as a partial file."""
    folder, d = drive
    lines = (folder / "imu.csv").read_text().splitlines(keepends=True)
    head = sum(1 for x in lines if x.startswith("#")) + 1
    row = 8 * CHUNK + 50
    fields = lines[head + row].split(",")
    if defect == "time":
        fields[0] = repr(float(d.imu.t_s[row - 2]))
    else:
        fields[2] = "nan"
    lines[head + row] = ",".join(fields) + ("" if fields[-1].endswith("\n") else "\n")
    bad = tmp_path / "bad_imu.csv"
    bad.write_text("".join(lines))
    out = _table_error(bad, monkeypatch, capsys, tmp_path, folder)
    assert out["whole"][0] == 2 and out["chunks"][0] == 1, out
    message = out["whole"][1].split("error: ", 1)[1].strip()
    assert f"{bad}:{head + row + 1}: " in message
    assert (f"t_s[{row}] = " if defect == "time" else f"gyro[{row}, 1] = nan") in message, message
    assert message in out["chunks"][1], out["chunks"][1]
    partial = tmp_path / "chunks_sol.partial.csv"
    assert partial.is_file() and "reading " in partial.read_text().splitlines()[0]
    assert not (tmp_path / "chunks_sol.csv").exists()


def test_parquet_and_npz_records_equal_the_csv(drive, tmp_path):
    """Our IMU record from Parquet and npz (the same columns as the CSV) reads as the
    CSV's, bit for bit; columns that are not a layout are refused by name."""
    from gfins_fmi.io.imu_stream import ImuChunks, read_imu_record
    from gfins_fmi.io import FileFormatError
    folder, d = drive
    for fmt in ("parquet", "npz"):
        rec = read_imu_record(folder / f"imu.{fmt}")
        for a, b in ((rec.t_s, d.imu.t_s), (rec.gyro, d.imu.gyro), (rec.accel, d.imu.accel)):
            assert np.array_equal(a, b)
        assert rec.kind == "increments"
        ch = ImuChunks(folder / f"imu.{fmt}", chunk=CHUNK)
        # the head: whole chunks up to 101 samples at least
        assert ch.t_end == d.imu.t_s[-1] and len(ch.first) == -(-101 // CHUNK) * CHUNK
        assert sum(len(r) for r in ch) == len(d.imu)
    np.savez(tmp_path / "x.npz", t=d.imu.t_s, gx=d.imu.gyro[:, 0])
    with pytest.raises(FileFormatError, match="the column names 't,gx' are not a ImuRecord layout"):
        read_imu_record(tmp_path / "x.npz")


def test_kfgins_text_with_commas_and_an_empty_file(drive, tmp_path, capsys, monkeypatch):
    """KF-GINS's own loader splits at commas too, and so does the whole-record reader: in
    chunks a comma-separated KF-GINS IMU text was refused ("text in a number column")
    once every run went through the chunked reader; now it gives the whole record's
    result. An empty IMU file (or comments only) is named, not an IndexError."""
    folder, d = drive
    comma = tmp_path / "imu_comma.txt"
    comma.write_text((folder / "imu.txt").read_text().replace(" ", ","))
    out = _both(monkeypatch, capsys, tmp_path, [
        "integrate", str(comma), str(folder / "gnss.csv"), "--imu-format", "kfgins", "--gnss-format", "csv",
        "--grade", "tactical", f"--lever-arm={LEVER}", *_initial(d)])
    _same(out)
    empty = tmp_path / "empty.txt"
    empty.write_text("# a header comment only\n\n")
    rc = main(["integrate", str(empty), str(folder / "gnss.csv"), str(tmp_path / "e.csv"), "--imu-format", "kfgins",
               "--gnss-format", "csv", *_initial(d)])
    err = capsys.readouterr().err
    assert rc == 2 and "no data line" in err, err
