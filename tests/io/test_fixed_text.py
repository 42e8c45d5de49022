"""gf_text_fixed (csrc/base/gf_text.c): a table as text with fixed decimals, against
Python's own formatting (the C library's printf: exact decimal rounding of the binary
value) as the truth, through TableWriter(decimals=...)."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.io.table_writer import TableWriter


def _fixed(table, decimals, sep=b" "):
    table = np.ascontiguousarray(table, dtype=np.float64)
    cap = table.size * 40 + 1
    buf = ffi.new("char[]", cap)
    n = ffi.new("size_t *")
    status = lib.gf_text_fixed(table.shape[0], table.shape[1], ptr(table, table.size), decimals, sep, buf, cap, n)
    return int(status), ffi.buffer(buf, n[0])[:].decode()


@pytest.mark.parametrize("decimals", [0, 3, 9])
def test_equals_printf_to_the_last_digit(decimals):
    """Random magnitudes from 1e-12 to 1e20, both signs, the edge values, and values one
    ulp either side of a decimal tie (k + 1/2) 10^-d (where a once-rounded scaling of the
    fraction goes wrong: the formatter before this test took 373 of 2e6 such values at
    d = 3 and 9 of 2e6 at d = 9 across the tie): the same text as f"{x:.{d}f}" (exact
    decimal rounding of the binary value, exact ties to even, as printf), every digit."""
    rng = np.random.default_rng(20)
    x = rng.choice([-1.0, 1.0], 60000) * 10.0 ** rng.uniform(-12, 20, 60000)
    x[:12] = [0.0, -0.0, 0.5, -0.5, 1.5, 2.5, 1e-10, -1e-10, 9.999999999, 604799.995, 30.4447873701, 1e20]
    k = rng.integers(0, 10 ** 6, 30000)
    ties = (k + 0.5) / 10.0 ** decimals + rng.integers(0, 1000, 30000)
    near = np.nextafter(ties, np.where(rng.random(30000) < 0.5, np.inf, -np.inf))
    x = np.r_[x, ties, near * rng.choice([-1.0, 1.0], 30000)]
    status, text = _fixed(x.reshape(-1, 3), decimals)
    assert status == lib.GF_OK
    ours = text.replace("\n", " ").split()
    theirs = [f"{v:.{decimals}f}" for v in x]
    diff = [(v, a, b) for v, a, b in zip(x, ours, theirs) if a != b]
    assert not diff, diff[:5]


def test_special_values_and_refusals():
    status, text = _fixed(np.array([[np.nan, np.inf, -np.inf, -1e-12]]), 9, b",")
    assert status == lib.GF_OK and text == "NaN,inf,-inf,-0.000000000\n"
    assert _fixed(np.array([[1e25]]), 9)[0] == lib.GF_ERR_OUT_OF_RANGE
    assert _fixed(np.array([[1.0]]), 10)[0] == lib.GF_ERR_BAD_PARAMETER


def test_table_writer_fixed_decimals_falls_back_beyond_the_range(tmp_path):
    """TableWriter(decimals=9, separator=" ", header=False): KF-GINS's text; a chunk with a
    value beyond gf_text_fixed's range is formatted by polars (the same decimals)."""
    path = tmp_path / "t.txt"
    with TableWriter(path, ["a", "b"], decimals=9, separator=" ", header=False) as w:
        w.write([np.array([1.25, -2.0]), np.array([30.4447873701, 0.0])])
        w.write([np.array([1e30]), np.array([1.0])])
        w.write([np.arange(300000.0), np.zeros(300000)])   # a longer chunk than the first (the buffer)
        w.commit()
    lines = path.read_text().splitlines()
    assert lines[:2] == ["1.250000000 30.444787370", "-2.000000000 0.000000000"]
    assert float(lines[2].split()[0]) == 1e30 and lines[2].split()[1] == "1.000000000"
    assert len(lines) == 300003 and lines[-1] == "299999.000000000 0.000000000"
