"""Properties of the 9-accelerometer solver (hypothesis): Accel9Solver in pieces equals one
run over the record, bit for bit.
"""
from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra: pip install '.[test]'")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gfins_fmi as gf  # noqa: E402
from support.truth import numpy_outputs, paper_layout, smooth_motion  # noqa: E402
from support.properties import SOME  # noqa: E402


@SOME
@given(n=st.integers(2, 3000), l_m=st.floats(0.05, 0.5), data=st.data())
def test_accel9_in_pieces_equals_whole(n, l_m, data):
    dt = 0.01
    u, th = paper_layout(l_m)
    _, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    whole = gf.Accel9Solver(l_m, w[0]).solve(A, dt)
    cut = data.draw(st.integers(1, n - 1), label="cut")
    solver = gf.Accel9Solver(l_m, w[0])
    a, b = solver.solve(A[:cut], dt), solver.solve(A[cut:], dt)
    for name in ("f_m_s2", "omega_rad_s", "omega_dot_rad_s2", "omega_sq_rad2_s2"):
        np.testing.assert_array_equal(np.concatenate([getattr(a, name), getattr(b, name)]),
                                      getattr(whole, name), err_msg=f"cut at {cut}: {name}")
