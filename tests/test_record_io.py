"""Record I/O (issue 15, item 5): tables read and written in chunks (CSV, npz, Parquet),
and the record commands (``gfins solve9``, ``navigate``, ``gfnav``) streaming through
them. Each defect the tester found is a test here:

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
import zipfile

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.cli import main
from gfins_fmi.io import FileFormatError
from gfins_fmi.io import table_writer, tables
from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.tables import TableReader, table_format
from conftest import W0, numpy_outputs, paper_layout, smooth_motion

FORMATS = ["csv", "npz", "parquet"]
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


# ---- tables ------------------------------------------------------------------------

@pytest.fixture
def values(rng):
    """Doubles that stress a text format: 1e-300..1e300, subnormals, -0, NaN, inf."""
    x = rng.normal(size=(1000, 4)) * 10.0 ** rng.integers(-300, 300, (1000, 4))
    x[0] = [5e-324, -0.0, np.nan, np.inf]
    x[1] = [-np.inf, 0.1, 1e21, 2.0 ** 53 + 2]
    return x


@pytest.mark.parametrize("fmt", FORMATS)
def test_tables_round_trip_bit_for_bit_in_chunks(fmt, values, tmp_path):
    _needs(fmt)
    path = tmp_path / f"t.{fmt}"
    flags = np.arange(1000, dtype=np.uint8)
    with TableWriter(path, ["a_s", "b_m", "c", "d", "flags"], [np.float64] * 4 + [np.uint8],
                     comments=["written by a test"]) as w:
        for lo in range(0, 1000, 300):                       # uneven chunks
            w.write([values[lo:lo + 300, j] for j in range(4)] + [flags[lo:lo + 300]])
        w.commit()
    back = _read(path)                                       # read by numpy / pyarrow
    assert np.array_equal(back[:, :4], values, equal_nan=True)
    assert np.array_equal(back[:, 4], flags)
    r = TableReader(path, header=True, chunk_rows=128)       # and by the reader
    assert r.names == ("a_s", "b_m", "c", "d", "flags") and r.n_columns == 5
    chunks = list(r)
    assert [s for s, _ in chunks] == list(range(0, 1000, 128))
    assert all(b.flags.c_contiguous and b.dtype == np.float64 for _, b in chunks)
    got = np.concatenate([b for _, b in chunks])
    assert np.array_equal(got[:, :4], values, equal_nan=True)
    assert np.array_equal(got[:, 4], flags)
    assert r.position == r.size                               # progress reaches its total
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary file left


@pytest.mark.parametrize("fmt", FORMATS)
def test_write_behind_sends_each_range_then_drops_it_and_keeps_tables_exact(fmt, values,
                                                                             tmp_path, monkeypatch):
    """The writer sends what it wrote to the disk and drops it from the page cache one
    step later (every 64 MB; here after every chunk): every byte written is sent once,
    every range but the last step's is waited for before it is dropped, and the table
    still reads back bit for bit."""
    _needs(fmt)
    real = table_writer._sync_file_range()
    if real is None:
        pytest.skip("no sync_file_range here (not Linux): the writer leaves the cache alone")
    calls = []

    def spy(fd, offset, length, flags):
        calls.append((offset, length, flags))
        return real(fd, offset, length, flags)
    monkeypatch.setattr(table_writer, "_sync_file_range", lambda: spy)
    monkeypatch.setattr(table_writer, "_WRITE_BEHIND_BYTES", 1)
    path = tmp_path / f"t.{fmt}"
    with TableWriter(path, ["a_s", "b_m", "c", "d"], rows=1000) as w:
        for lo in range(0, 1000, 300):
            w.write([values[lo:lo + 300, j] for j in range(4)])
        w.commit()
    assert np.array_equal(_read(path), values, equal_nan=True)
    sent = [(o, n) for o, n, f in calls if f == 2]               # SYNC_FILE_RANGE_WRITE
    waited = [(o, n) for o, n, f in calls if f == 1 | 2 | 4]     # WAIT_BEFORE|WRITE|WAIT_AFTER
    assert len(sent) + len(waited) == len(calls) and waited, calls
    assert waited == sent[:len(waited)] and len(sent) > len(waited), calls
    covered = np.zeros(path.stat().st_size, bool)                 # no byte sent twice
    for o, n in sent:
        assert not covered[o:o + n].any(), (o, n)
        covered[o:o + n] = True
    size, m = covered.size, int(covered.sum())
    if fmt == "npz":                # the four columns' data, not the zip's headers
        assert m == 4 * 1000 * 8
    elif fmt == "csv":              # everything after the header line
        head = path.read_bytes().index(b"\n") + 1
        assert not covered[:head].any() and covered[head:].all()
    else:                           # from the start, all but the footer (written at commit)
        assert covered[:m].all() and 4 * 1000 * 8 < m < size


@pytest.mark.parametrize("planned", [None, 1000, 700, 1300])
def test_npz_written_in_place_or_through_side_files(planned, values, tmp_path):
    """With the row count known (a binary input) the npz columns are written in place
    and the zip headers at the end; a count that turns out different (a partial output,
    or more rows) falls back to side files. Either way zipfile finds every CRC right
    and numpy reads the columns back bit for bit."""
    path = tmp_path / "t.npz"
    flags = np.arange(1000, dtype=np.uint8)
    with TableWriter(path, ["a_s", "b", "c", "d", "flags"], [np.float64] * 4 + [np.uint8],
                     rows=planned) as w:
        for lo in range(0, 1000, 300):
            w.write([values[lo:lo + 300, j] for j in range(4)] + [flags[lo:lo + 300]])
        # side files from the start without a count, from the 701st row with 700; none
        # yet with 1000 or 1300 (the short one is moved to side files at commit)
        side = list(tmp_path.glob("*.partial.d"))
        assert (side != []) == (planned is None or planned < 1000), side
        w.commit()
    with zipfile.ZipFile(path) as z:
        assert z.testzip() is None and z.namelist() == ["a_s.npy", "b.npy", "c.npy", "d.npy",
                                                        "flags.npy"]
    with np.load(path) as z:
        assert np.array_equal(np.column_stack([z["a_s"], z["b"], z["c"], z["d"]]), values,
                              equal_nan=True)
        assert z["flags"].dtype == np.uint8 and np.array_equal(z["flags"], flags)
    assert [p.name for p in tmp_path.iterdir()] == ["t.npz"]


def test_csv_text_conventions(tmp_path):
    """Comments and blank lines anywhere, spaces, CRLF, numpy's '# names' header line."""
    p = tmp_path / "a.csv"
    p.write_text("# made by hand\n\n1, 2 ,3\r\n  # a remark\n\n4,5,6\n# a,b,c\n\t7,8,9\n")
    (_, b), = TableReader(p)
    assert b.tolist() == [[1, 2, 3], [4, 5, 6], [7, 8, 9]]
    p.write_text("# t_s,x_m\n1,2\n3,4\n")                       # np.savetxt(header=...)
    r = TableReader(p, header=True)
    assert r.names == ("t_s", "x_m") and next(iter(r))[1].tolist() == [[1, 2], [3, 4]]
    p.write_text("t_s,x_m\n1,2\n")
    assert TableReader(p, header=True).names == ("t_s", "x_m")
    p.write_text("1,2\n")
    with pytest.raises(FileFormatError, match=r"a.csv:1: a header line of column names was "
                                              r"expected, but the first line holds numbers"):
        TableReader(p, header=True)


TEXT_ERRORS = {
    "empty": ("", r"a.csv: no data lines: the file is empty"),
    "comments only": ("# x\n\n", r"a.csv: no data lines: the file is empty"),
    "header": ("t,a,b\n1,2,3\n", r"a.csv:1: the first data line holds text \('t'\) where numbers "
               r"were expected: if it is a line of column names, read it with header=True"),
    "short line": ("1,2,3\n4,5\n", r"a.csv:2: 2 columns where a table line has 3"),
    "long line": ("1,2,3\n4,5,6,7\n", r"a.csv:2: 4 columns where a table line has 3"),
    "text": ("1,2,3\n4,x,6\n", r"a.csv:2: 'x' is not a number"),
    "empty field": ("1,2,3\n4,,6\n", r"a.csv:2: an empty field"),
    "trailing comment": ("1,2,3\n4,5,6 # no\n", r"a.csv:2: '6 # no' is not a number"),
    "header and no data": ("# only\n", r"a.csv: no data lines"),
}


@pytest.mark.parametrize("case", sorted(TEXT_ERRORS))
def test_csv_errors_name_the_line(case, tmp_path):
    text, match = TEXT_ERRORS[case]
    p = tmp_path / "a.csv"
    p.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        list(TableReader(p))


def test_csv_error_far_into_a_file_names_its_line(tmp_path, monkeypatch):
    """Blocks of 4 KiB: the bad line is in the 30th block; its number counts the
    comment and blank lines before it."""
    monkeypatch.setattr(tables, "_TEXT_BLOCK_BYTES", 4096)
    lines = ["# head", ""] + [f"{k},{k * 0.5!r},{-k}" for k in range(20000)]
    lines[2 + 7777] = "7777,oops,1"
    p = tmp_path / "a.csv"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError, match=r"a.csv:7780: 'oops' is not a number"):
        list(TableReader(p, chunk_rows=1000))
    lines[2 + 7777] = "7777,1,2"
    p.write_text("\n".join(lines) + "\n")
    got = np.concatenate([b for _, b in TableReader(p, chunk_rows=1000)])
    assert got.shape == (20000, 3) and got[7777].tolist() == [7777, 1, 2]
    assert np.array_equal(got[:, 0], np.r_[np.arange(7777), 7777, np.arange(7778, 20000)])


def test_npz_layouts(tmp_path):
    a = np.arange(24.0).reshape(8, 3)
    for order in ("C", "F"):                        # one 2-D array, either memory order
        np.savez(tmp_path / "m.npz", np.array(a, order=order))
        got = np.concatenate([b for _, b in TableReader(tmp_path / "m.npz", chunk_rows=3)])
        assert np.array_equal(got, a)
    np.savez_compressed(tmp_path / "c.npz", t=np.arange(5), x=np.arange(5) * 0.5)  # ints, deflated
    r = TableReader(tmp_path / "c.npz")
    assert r.names == ("t", "x") and next(iter(r))[1].tolist() == [[k, k / 2] for k in range(5)]
    np.savez(tmp_path / "b.npz", t=np.arange(5.0), x=np.arange(4.0))
    with pytest.raises(FileFormatError, match=r"1-D arrays have lengths \[4, 5\]"):
        TableReader(tmp_path / "b.npz")
    np.savez(tmp_path / "s.npz", t=np.array(["a", "b"]))
    with pytest.raises(FileFormatError, match=r"column 't.npy' holds <U1, not numbers"):
        TableReader(tmp_path / "s.npz")
    (tmp_path / "z.npz").write_bytes(b"not a zip")
    with pytest.raises(FileFormatError, match="not an npz"):
        TableReader(tmp_path / "z.npz")


def test_parquet_refusals(tmp_path):
    pa = pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq
    pq.write_table(pa.table({"t": [1.0, 2.0], "name": ["a", "b"]}), tmp_path / "s.parquet")
    with pytest.raises(FileFormatError, match="column 'name' holds string, not numbers"):
        TableReader(tmp_path / "s.parquet")
    pq.write_table(pa.table({"t": [1.0, 2.0, 3.0], "x": [1.0, None, 3.0]}), tmp_path / "n.parquet")
    with pytest.raises(FileFormatError, match=r"column 'x', row 1: no value \(null\)"):
        list(TableReader(tmp_path / "n.parquet"))


def test_writer_replaces_the_destination_only_on_commit(tmp_path):
    path = tmp_path / "out.csv"
    path.write_text("precious\n")
    with pytest.raises(RuntimeError):
        with TableWriter(path, ["x"]) as w:
            w.write([np.arange(3.0)])
            raise RuntimeError("failure while writing")
    assert path.read_text() == "precious\n" and [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    with TableWriter(path, ["x"]) as w:
        w.write([np.arange(3.0)])
        assert path.read_text() == "precious\n"              # still the old file
        w.commit()
    assert path.read_text() == "x\n0.0\n1.0\n2.0\n"
    with pytest.raises(ValueError, match="column names must be"):
        TableWriter(tmp_path / "b.csv", ["x,y"])
    with pytest.raises(FileNotFoundError):
        TableWriter(tmp_path / "missing" / "c.csv", ["x"])


# ---- the record commands -------------------------------------------------------------

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
    the output holds the 700 rows before it; times checked across chunk boundaries."""
    tr, rec, init = nav_record
    bad = rec.copy()
    bad[700, 5] = np.nan
    src, dst = _write(tmp_path / "rec.csv", bad), tmp_path / "sol.csv"
    assert main(["navigate", str(src), str(dst), *init, "--chunk", "256"]) == 1
    err = capsys.readouterr().err
    assert "accel[700, 1] = nan is not finite" in err, err
    assert "writing the 700 samples navigated before it" in err
    assert np.array_equal(_read(dst), _nav_table(_nav_reference(tr, init, 700)))
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
    out = _read(dst)
    sol, rates = _gfnav_reference(tr, init, rec[:300, 1:])
    assert out.shape == (300, 21)
    assert np.array_equal(out, np.c_[_nav_table(sol), rates.omega_rad_s, rates.f_m_s2, rates.flags])
    header = dst.read_text().splitlines()[0].split(",")
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
