"""Tables read and written in chunks (gfins_fmi.io.tables, table_writer; issue 15, item 5):
CSV, npz and Parquet round trips bit for bit, the write-behind, npz written in place or
through side files, CSV conventions and errors naming the line, the writer replacing the
destination only on commit. The record commands that stream through them:
tests/cli/test_record_commands.py.

Truth: the values written.
"""
from __future__ import annotations

import pathlib
import zipfile

import numpy as np
import pytest

from gfins_fmi.io import FileFormatError
from gfins_fmi.io import table_writer, tables
from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.tables import TableReader, table_format

FORMATS = ["csv", "npz", "parquet"]


def _needs(fmt):
    if fmt == "parquet":
        pytest.importorskip("pyarrow", reason="Parquet needs the optional pyarrow")


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
        side = list(tmp_path.glob("t.*.tmp.npz.d"))
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
