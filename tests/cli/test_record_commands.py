"""The record commands (``gfins solve9``, ``navigate``, ``gfnav``) streaming through the tables of
gfins_fmi.io (issue 15, item 5). Each defect the tester found is a test here:

* an interrupted write left a truncated output in place;
* a failure at the first sample replaced an existing output with a header-only file;
* the gfnav partial output dropped the rate columns;
* "samples 0..-1 were solved";
* an empty file reported "found 1 column" and leaked a numpy warning;
* a text header without ``--header`` gave no hint (and solve9 had no ``--header``);
* no progress during load and write.

The 10^7-row timings and memory are in bench/bench_record_io.py (docs/benchmarks.md).
Truth: the library called on the whole record in memory, and the values written.
"""
from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.cli import main
from gfins_fmi.io.tables import table_format
from support.truth import W0, numpy_outputs, paper_layout, smooth_motion


#: a sampling interval exact in binary: times k * DT and their sums carry no rounding,
#: so a record cut into chunks gives the same floats as one call
DT = 2.0 ** -7


def _needs(fmt):
    if fmt == "parquet":
        pytest.importorskip("pyarrow", reason="Parquet needs the optional pyarrow")


def _write(path, table, names=None, header=False):
    """A table file written without the code under test (numpy, or pyarrow for Parquet)."""
    path = pathlib.Path(path)
    names = names or [f"c{j}" for j in range(table.shape[1])]
    fmt = table_format(path)
    if fmt == "csv":
        np.savetxt(path, table, delimiter=",", fmt="%.17g",
                   header=",".join(names) if header else "", comments="")
    elif fmt == "npz":
        np.savez(path, **{n: table[:, j] for j, n in enumerate(names)})
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq
        pq.write_table(pa.table({n: table[:, j] for j, n in enumerate(names)}), path)
    return path


def _read(path) -> np.ndarray:
    """An output read back without the code under test."""
    fmt = table_format(path)
    if fmt == "csv":                  # '#' lines, the header line, then numbers
        lines = [x for x in pathlib.Path(path).read_text().splitlines() if not x.startswith("#")]
        return np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    if fmt == "npz":
        with np.load(path) as z:
            return np.column_stack([z[k] for k in z.files])
    import pyarrow.parquet as pq
    t = pq.read_table(path)
    return np.column_stack([c.to_numpy() for c in t.columns])


@pytest.fixture(scope="module")
def nav_record():
    """A strapdown record (t, increments) of a circle drive at 2^-7 s, and the options of
    its initial state."""
    tr = tj.sample(tj.Circle(), 8.0, DT)
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    init = ["--lat0", repr(float(np.degrees(tr.lat_rad[0]))), "--lon0",
            repr(float(np.degrees(tr.lon_rad[0]))), "--h0", repr(float(tr.h_m[0])),
            "--heading0", repr(float(e[0])), "--pitch0", repr(float(e[1])), "--roll0",
            repr(float(e[2])), "--v0=" + ",".join(repr(float(x)) for x in tr.v_n_m_s[0])]
    return tr, np.c_[tr.t_s[1:], tr.dtheta_rad, tr.dv_m_s], init


@pytest.fixture(scope="module")
def array_record(nav_record):
    tr, _, init = nav_record
    g = gf.layout("qin9", 0.1)
    return tr, np.c_[tr.t_s, tr.array_outputs(g)], init


@pytest.fixture(scope="module")
def accel9_record():
    u, th = paper_layout(0.1)
    t, f, w, wd = smooth_motion(800, DT)
    return np.c_[100.0 + t, numpy_outputs(u, th, f, w, wd)]


def _x0(init, t0_s):
    """The initial state the commands build from the options ``init`` (degrees)."""
    o = {init[k]: float(init[k + 1]) for k in range(0, len(init) - 1, 2)}
    v0 = [float(x) for x in init[-1].split("=")[1].split(",")]
    deg = np.pi / 180
    return gf.NavState.from_euler([o["--heading0"] * deg, o["--pitch0"] * deg, o["--roll0"] * deg],
                                  v0, o["--lat0"] * deg, o["--lon0"] * deg, o["--h0"], t0_s)


def _nav_reference(tr, init, rows=None):
    sol = gf.Strapdown(_x0(init, tr.t_s[0])).run(tr.dtheta_rad, tr.dv_m_s, t_s=tr.t_s[1:])
    return sol if rows is None else sol._rows(slice(0, rows))


def _nav_table(sol) -> np.ndarray:
    deg = 180 / np.pi
    return np.c_[sol.t_s, sol.lat_rad * deg, sol.lon_rad * deg, sol.h_m, sol.v_n_m_s,
                 sol.euler_rad * deg, sol.q_bn]


def _gfnav_args(src, dst, init, *extra):
    return ["gfnav", str(src), str(dst), "--layout", "qin9", "--lever-arm", "0.1",
            "--strategy", "sqrt", *init, *extra]


def _gfnav_reference(tr, init, A):
    g = gf.layout("qin9", 0.1)
    return gf.GyroFreeNavigator(g, _x0(init, tr.t_s[0]), "sqrt").run(A, DT)


@pytest.mark.parametrize("fmt_in, fmt_out", [("csv", "csv"), ("npz", "npz"), ("parquet", "parquet"),
                                             ("csv", "npz"), ("npz", "csv")])
def test_navigate_streams_in_chunks_as_one_call(fmt_in, fmt_out, nav_record, tmp_path):
    """Chunks of 100 samples (10 of them, the last short) give the solution of one
    Strapdown.run over the whole record, bit for bit, in every format."""
    _needs(fmt_in), _needs(fmt_out)
    tr, rec, init = nav_record
    src = _write(tmp_path / f"rec.{fmt_in}", rec)
    dst = tmp_path / f"sol.{fmt_out}"
    assert main(["navigate", str(src), str(dst), *init, "--chunk", "100"]) == 0
    assert np.array_equal(_read(dst), _nav_table(_nav_reference(tr, init)))


def test_gfnav_and_solve9_stream_in_chunks_as_one_call(array_record, accel9_record, tmp_path):
    tr, rec, init = array_record
    src = _write(tmp_path / "arr.csv", rec)
    assert main(_gfnav_args(src, tmp_path / "sol.npz", init, "--chunk", "128")) == 0
    sol, rates = _gfnav_reference(tr, init, rec[:, 1:])
    ref = np.c_[_nav_table(sol), rates.omega_rad_s, rates.f_m_s2, rates.flags]
    out = _read(tmp_path / "sol.npz")
    assert out.shape == (len(rec), 21) and np.array_equal(out, ref)
    src = _write(tmp_path / "a9.csv", accel9_record)
    assert main(["solve9", str(src), str(tmp_path / "s9.csv"), "--lever-arm", "0.1",
                 "--omega-init=" + ",".join(map(str, W0)), "--chunk", "300"]) == 0
    s = gf.solve_accel9(accel9_record[:, 1:], DT, 0.1, W0)
    ref = np.c_[accel9_record[:, 0], s.f_m_s2, s.omega_rad_s, s.omega_dot_rad_s2,
                s.omega_sq_rad2_s2, s.flags]
    assert np.array_equal(_read(tmp_path / "s9.csv"), ref)


def test_errors_past_the_first_chunk_name_the_records_row(nav_record, tmp_path, capsys):
    """A NaN at row 700 in chunks of 256: the message names row 700 (not 700 - 512) and
    the partial output holds the 700 rows before it; times checked across chunk
    boundaries."""
    tr, rec, init = nav_record
    bad = rec.copy()
    bad[700, 5] = np.nan
    src, dst = _write(tmp_path / "rec.csv", bad), tmp_path / "sol.csv"
    assert main(["navigate", str(src), str(dst), *init, "--chunk", "256"]) == 1
    err = capsys.readouterr().err
    assert "accel[700, 1] = nan is not finite" in err, err
    assert "the 700 samples navigated before it are in " + str(tmp_path / "sol.partial.csv") in err
    assert np.array_equal(_read(tmp_path / "sol.partial.csv"), _nav_table(_nav_reference(tr, init, 700)))
    assert not dst.exists()
    bad = rec.copy()
    bad[512, 0] = bad[511, 0]                         # the first row of the third chunk
    _write(src, bad)
    assert main(["navigate", str(src), str(dst), *init, "--chunk", "256"]) == 2
    assert "row 512: time" in capsys.readouterr().err
    bad = rec.copy()
    bad[256:, 0] += 1.0                               # a gap between two chunks
    _write(src, bad)
    assert main(["navigate", str(src), str(dst), *init, "--chunk", "256"]) == 0
    assert "note: 1 gap in the time column: row 256" in capsys.readouterr().err


def test_interrupted_write_leaves_no_truncated_output(nav_record, tmp_path):
    """Before: Ctrl-C while the solution was written left a truncated file under the
    output's name. Now the output is written beside it and renamed when complete: the
    destination holds either the old file or a whole solution, and no temporary file
    stays. (The signal is sent as soon as any new file appears in the folder.)"""
    init = nav_record[2]
    n = 200_000                                      # 26 minutes at rest: seconds to write
    big = np.c_[np.arange(1, n + 1) * DT, np.full((n, 3), 1e-9), np.zeros((n, 2)),
                np.full(n, 9.8 * DT)]
    src = _write(tmp_path / "rec.csv", big)
    out = tmp_path / "out"
    out.mkdir()
    dst = out / "sol.csv"
    dst.write_text("old solution\n")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from gfins_fmi.cli import main; "
                             "sys.exit(main(sys.argv[1:]))", "navigate", str(src), str(dst), *init,
                             "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                            cwd=tmp_path)   # not the checkout: its gfins_fmi/ has no build
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline:
        if len(list(out.iterdir())) > 1 or dst.read_bytes() != b"old solution\n":
            proc.send_signal(signal.SIGINT)
            break
        time.sleep(0.002)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode in (0, 130, -signal.SIGINT), err.decode()   # done, or interrupted
    assert [p.name for p in out.iterdir()] == ["sol.csv"], list(out.iterdir())
    text = dst.read_text()
    if text != "old solution\n":                       # the run finished before the signal
        assert _read(dst).shape == (len(big), 14)


@pytest.mark.parametrize("command", ["navigate", "gfnav", "solve9"])
def test_failure_at_the_first_sample_keeps_an_existing_output(command, nav_record, array_record,
                                                              accel9_record, tmp_path, capsys):
    """Before: exit 1 and the existing output replaced by a header-only file (and, for
    solve9, 'samples 0..-1 were solved')."""
    if command == "navigate":
        rec, init = nav_record[1].copy(), nav_record[2]
        rec[0, 2] = np.nan
        args = ["navigate", None, None, *init]
    elif command == "gfnav":
        rec, init = array_record[1].copy(), array_record[2]
        rec[0, 3] = np.nan
        args = _gfnav_args(None, None, init)
    else:
        rec = accel9_record.copy()
        rec[0, 3] = np.nan
        args = ["solve9", None, None, "--lever-arm", "0.1"]
    args[1], args[2] = str(_write(tmp_path / "rec.csv", rec)), str(tmp_path / "sol.csv")
    (tmp_path / "sol.csv").write_text("the previous solution\n")
    assert main(args) == 1
    err = capsys.readouterr().err
    verb = "solved" if command == "solve9" else "navigated"
    assert f"no sample was {verb}: {tmp_path / 'sol.csv'} left as it was" in err, err
    assert "0..-1" not in err
    assert (tmp_path / "sol.csv").read_text() == "the previous solution\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.csv", "sol.csv"]


def test_solver_messages_at_the_first_sample():
    """Before: 'samples 0..-1 were solved (see .partial)'."""
    A = np.zeros((5, 9))
    A[0, 2] = np.nan
    with pytest.raises(gf.NonFiniteInputError) as exc:
        gf.Accel9Solver(0.1).solve(A, 0.01)
    assert "no sample was solved before it" in str(exc.value) and "0..-1" not in str(exc.value)
    A[0, 2], A[3, 2] = 0.0, np.nan
    with pytest.raises(gf.NonFiniteInputError) as exc:
        gf.Accel9Solver(0.1).solve(A, 0.01, start_index=1000)
    assert str(exc.value).startswith("A_m_s2[1003, 2] = nan")
    assert "samples 1000..1002 were solved" in str(exc.value) and exc.value.index == 1003
    assert len(exc.value.partial) == 3


def test_gfnav_partial_output_keeps_the_rate_columns(array_record, tmp_path, capsys):
    """Before: after a refused sample the gfnav output had 14 columns instead of 21."""
    tr, rec, init = array_record
    bad = rec.copy()
    bad[300, 4] = np.nan
    src, dst = _write(tmp_path / "arr.csv", bad), tmp_path / "sol.csv"
    assert main(_gfnav_args(src, dst, init)) == 1
    assert "A_m_s2[300, 3] = nan is not finite" in capsys.readouterr().err
    dst = tmp_path / "sol.partial.csv"
    out = _read(dst)
    sol, rates = _gfnav_reference(tr, init, rec[:300, 1:])
    assert out.shape == (300, 21)
    assert np.array_equal(out, np.c_[_nav_table(sol), rates.omega_rad_s, rates.f_m_s2, rates.flags])
    header = dst.read_text().splitlines()[1].split(",")      # after the "# partial: ..." line
    assert header[-7:] == ["omega_x_rad_s", "omega_y_rad_s", "omega_z_rad_s", "f_x_m_s2",
                           "f_y_m_s2", "f_z_m_s2", "flags"]


@pytest.mark.parametrize("command", ["navigate", "gfnav", "solve9"])
def test_empty_input_is_named_without_a_warning(command, nav_record, tmp_path, capsys):
    """Before: 'expected 7 or 8 columns ...; found 1' and numpy's UserWarning 'input
    contained no data'."""
    src, dst = tmp_path / "rec.csv", tmp_path / "sol.csv"
    src.write_text("")
    args = {"navigate": ["navigate", str(src), str(dst), *nav_record[2]],
            "gfnav": _gfnav_args(src, dst, nav_record[2]),
            "solve9": ["solve9", str(src), str(dst), "--lever-arm", "0.1", "--dt", "0.01"]}[command]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(args) == 2
    err = capsys.readouterr().err
    assert f"{src}: no data lines: the file is empty" in err, err
    assert "found 1" not in err and "Warning" not in err
    assert not dst.exists()


@pytest.mark.parametrize("command", ["navigate", "gfnav", "solve9"])
def test_a_header_line_gets_a_hint_and_header_reads_it(command, nav_record, array_record,
                                                       accel9_record, tmp_path, capsys):
    """Before: "could not convert string 't' to float64" with no hint; solve9 had no
    --header."""
    rec, names = {"navigate": (nav_record[1], ["t_s", "gx", "gy", "gz", "ax", "ay", "az"]),
                  "gfnav": (array_record[1], ["t_s"] + [f"A{i}" for i in range(1, 10)]),
                  "solve9": (accel9_record, ["t_s"] + [f"A{i}" for i in range(1, 10)])}[command]
    src, dst = _write(tmp_path / "rec.csv", rec, names, header=True), tmp_path / "sol.csv"
    args = {"navigate": ["navigate", str(src), str(dst), *nav_record[2]],
            "gfnav": _gfnav_args(src, dst, array_record[2]),
            "solve9": ["solve9", str(src), str(dst), "--lever-arm", "0.1"]}[command]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert (f"{src}:1: the first data line holds text ('t_s') where numbers were expected: if "
            "it is a line of column names, give --header") in err, err
    assert not dst.exists()
    assert main(args + ["--header"]) == 0
    assert _read(dst).shape[0] == len(rec)


def test_progress_covers_reading_and_writing(nav_record, accel9_record, tmp_path, capsys):
    """Before: a bar only while the C core ran (navigate), none in solve9 and gfnav. Now
    one bar over the input's bytes, advanced when a chunk is read, solved and written."""
    _, rec, init = nav_record
    src, dst = _write(tmp_path / "rec.csv", rec), tmp_path / "sol.csv"
    assert main(["navigate", str(src), str(dst), *init, "--progress"]) == 0
    err = capsys.readouterr().err
    assert "read, navigate, write: 100%" in err and "B/s" in err, err    # bytes of input
    assert main(["solve9", str(_write(tmp_path / "a9.csv", accel9_record)), str(dst),
                 "--lever-arm", "0.1", "--progress"]) == 0
    assert "read, solve, write: 100%" in capsys.readouterr().err
