"""Properties of the SINS FMU (hypothesis): a short record through the FMU equals
Strapdown.run.
"""
from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra: pip install '.[test]'")
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gfins_fmi as gf  # noqa: E402


@settings(max_examples=3, deadline=None, derandomize=True)   # FMUs are slow to instantiate
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 60))
def test_sins_fmu_equals_batch(seed, n):
    from gfins_fmi.fmi.models import run_sins_fmu
    rng = np.random.default_rng(seed)
    dth = rng.normal(0, 1e-3, (n, 3))
    dv = rng.normal(0, 1e-2, (n, 3)) + [0, 0, 0.098]
    x0 = gf.NavState.from_euler(rng.uniform(-1, 1, 3), rng.normal(0, 5, 3), 0.5, 2.0, 100.0)
    batch = gf.Strapdown(x0).run(dth, dv, dt_s=0.01)
    fmu = run_sins_fmu(dth, dv, 0.01, x0)
    for name in ("q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"):
        np.testing.assert_array_equal(getattr(fmu, name), getattr(batch, name), err_msg=name)
