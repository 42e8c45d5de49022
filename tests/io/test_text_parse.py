"""Text tables read by the C parser (gf_text_parse through TableReader): every value bit
for bit what Python's float() reads from the same text (float is correctly rounded: an
independent truth), in the forms people write (repr, %.15e, %.17g, fixed decimals,
integers, extreme exponents), in both separator modes and across block boundaries; nan
and inf as before; text reading without polars."""
from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from gfins_fmi.io import tables
from gfins_fmi.io.errors import FileFormatError
from gfins_fmi.io.tables import TableReader


def _values(seed: int, n: int) -> list[float]:
    """Finite doubles: any bit pattern, and magnitudes spread over the decades."""
    rng = np.random.default_rng(seed)
    bits = rng.integers(0, 2**63, n, dtype=np.uint64) | (rng.integers(0, 2, n, dtype=np.uint64) << np.uint64(63))
    a = bits.view(np.float64)
    a = a[np.isfinite(a)]
    b = rng.uniform(-1, 1, n) * 10.0 ** rng.integers(-30, 30, n)
    return np.concatenate([a, b, rng.integers(-10**6, 10**6, n).astype(float)]).tolist()


FORMS = {"repr": repr, "e15": lambda x: "%.15e" % x, "g17": lambda x: "%.17g" % x,
         "f15": lambda x: "%.15f" % x if abs(x) < 1e22 else repr(x), "g25": lambda x: "%.25g" % x,
         "int": lambda x: "%d" % x if abs(x) < 1e30 else repr(x)}


@pytest.mark.parametrize("whitespace", [False, True])
def test_values_are_what_float_reads(whitespace, tmp_path, monkeypatch):
    monkeypatch.setattr(tables, "_TEXT_BLOCK_BYTES", 1 << 14)    # many blocks: lines cut at their ends
    v = _values(7, 3000)
    k = len(FORMS)
    rows = [[f(x) for f in FORMS.values()] for x in v]
    rows.append(["1e-400", "-1e400", "4.9406564584124654e-324", "1.7976931348623159e308",
                 "0." + "0" * 300 + "1e300", "9007199254740993"])
    sep = " \t " if whitespace else " , "
    p = tmp_path / "t.txt"
    p.write_text("# a comment\r\n" + "".join(sep.join(r) + ("\r\n" if i % 3 == 0 else "\n")
                                               for i, r in enumerate(rows)))
    got = np.concatenate([b for _, b in TableReader(p, whitespace=whitespace, chunk_rows=700)])
    want = np.array([[float(x) for x in r] for r in rows])
    assert got.shape == (len(rows), k), f"{got.shape} read where the file holds {(len(rows), k)}"
    # bit for bit (no tolerance: both claim correct rounding)
    diff = np.argwhere(got.view(np.uint64) != want.view(np.uint64))
    assert len(diff) == 0, (f"{len(diff)} values differ from float(); the first: "
                            f"{rows[diff[0][0]][diff[0][1]]!r} read as {got[tuple(diff[0])]!r}" if len(diff) else "")


def test_nan_inf_and_forms_as_before(tmp_path):
    """nan and inf in any case and sign read as numbers (a record refuses them later, naming the
    sample); the forms polars took ('5.', '.5', '+1', '1E+5') too."""
    p = tmp_path / "s.csv"
    p.write_text("nan,-NaN,inf,-Infinity,+INF,5.,.5,+1,1E+5,-0\n")
    (_, b), = list(TableReader(p))
    assert np.isnan(b[0, :2]).all() and np.signbit(b[0, 1]) and not np.signbit(b[0, 0])
    assert b[0, 2:].tolist() == [math.inf, -math.inf, math.inf, 5.0, 0.5, 1.0, 1e5, 0.0]
    assert np.signbit(b[0, -1])


@pytest.mark.parametrize("text, whitespace, match", [
    ("1,2\n3,1_0\n", False, r"s.txt:2: '1_0' is not a number in the forms a table takes"),
    ("1 2\n3 0x10\n", True, r"s.txt:2: '0x10' is not a number"),
    ("1 2\n3 4 5\n", True, r"s.txt:2: 3 columns where a table line has 2"),
    ("1,2\n3 4,5\n", False, r"s.txt:2: '3 4' is not a number"),
])
def test_refusals_name_the_line(text, whitespace, match, tmp_path):
    """Numbers Python reads but a table does not ('1_0'), whitespace files' fields named
    one by one, a space inside a CSV field (polars read '3 4' as 34)."""
    p = tmp_path / "s.txt"
    p.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        list(TableReader(p, whitespace=whitespace))


def test_a_line_longer_than_a_block(tmp_path, monkeypatch):
    monkeypatch.setattr(tables, "_TEXT_BLOCK_BYTES", 64)
    row = [repr(x) for x in _values(3, 40)[:60]]
    p = tmp_path / "long.csv"
    p.write_text(",".join(row) + "\n" + ",".join(row))          # no '\n' at the end
    got = np.concatenate([b for _, b in TableReader(p)])
    assert got.shape == (2, len(row)) and got[1].tolist() == [float(x) for x in row]


def test_text_is_read_without_polars(tmp_path):
    p = tmp_path / "w.txt"
    p.write_text("0.005 1 2 3 4 5 6\n0.010 1 2 3 4 5 6\n")
    code = ("import sys; from gfins_fmi.io.tables import TableReader; "
            f"b = [x for _, x in TableReader({str(p)!r}, whitespace=True)]; "
            "assert b[0].shape == (2, 7); print('polars' in sys.modules)")
    # run outside the checkout: there `import gfins_fmi` would find the sources, not the
    # installed package with its compiled core (the CI installs it, not in place)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "False", "reading text imported polars"


def test_a_chunk_larger_than_the_file_costs_its_rows(tmp_path, monkeypatch):
    """chunk_rows of 10^9 (a whole record at once, as the commands' tests ask): the rows
    are allocated as they come, not 10^9 rows (52 GiB) up front; chunks that grow across
    the first allocation keep every row."""
    monkeypatch.setattr(tables, "_FIRST_CHUNK_ROWS", 64)
    p = tmp_path / "g.csv"
    p.write_text("".join(f"{i},{i * 0.25!r}\n" for i in range(1000)))
    (start, b), = list(TableReader(p, chunk_rows=10 ** 9))
    assert start == 0 and b.shape == (1000, 2) and b[:, 0].tolist() == list(range(1000))
    got = [b for _, b in TableReader(p, chunk_rows=300)]
    assert [len(b) for b in got] == [300, 300, 300, 100]
    assert np.concatenate(got)[:, 1].tolist() == [i * 0.25 for i in range(1000)]
