"""Properties of the IMU error model (hypothesis): ImuErrors.compensate inverts
ImuErrors.apply.
"""
from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra: pip install '.[test]'")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gfins_fmi as gf  # noqa: E402
from support.properties import SOME  # noqa: E402


def _vec3(lim):
    return st.lists(st.floats(-lim, lim), min_size=3, max_size=3)


def _misalignment(lim):
    return st.lists(st.floats(-lim, lim), min_size=6, max_size=6).map(
        lambda o: [[0, o[0], o[1]], [o[2], 0, o[3]], [o[4], o[5], 0]])


@SOME
@given(gb=_vec3(3600.0), gs=_vec3(5e4), gm=_misalignment(3600.0), ab=_vec3(2e4), as_=_vec3(5e4),
       am=_misalignment(3600.0), k2=_vec3(100.0), lever=_vec3(5.0), seed=st.integers(0, 2**32 - 1),
       with_temperature=st.booleans())
def test_imu_errors_apply_then_compensate_is_identity(gb, gs, gm, ab, as_, am, k2, lever, seed,
                                                      with_temperature):
    """Datasheet-range errors (biases to 3600 deg/h and 2e4 ug, scale factors to 5 %,
    misalignments to 1 deg, K2 to 100 ug/g^2, lever arms to 5 cm, temperature terms)."""
    rng = np.random.default_rng(seed)
    tc = dict(gyro_bias_tc=rng.normal(0, 1.0, (2, 3)), gyro_scale_tc=rng.normal(0, 10.0, (2, 3)),
              accel_bias_tc=rng.normal(0, 10.0, (2, 3)), accel_scale_tc=rng.normal(0, 10.0, (2, 3))) \
        if with_temperature else {}
    e = gf.ImuErrors(gyro_bias_deg_h=gb, gyro_scale_ppm=gs, gyro_misalignment_arcsec=gm,
                     accel_bias_ug=ab, accel_scale_ppm=as_, accel_misalignment_arcsec=am,
                     accel_k2_ug_g2=k2, lever_arm_cm=lever, **tc)
    w = rng.uniform(-5, 5, (50, 3))
    f = rng.uniform(-50, 50, (50, 3))
    temp = rng.uniform(-20, 60, 50) if with_temperature else None
    w_out, f_out = e.apply(w, f, temp)
    w_back, f_back = e.compensate(w_out, f_out, temp)
    # exact inverse up to round-off: a few ulp of the largest term per operation (the
    # matrices are within 5 % of the identity): 1e-13 of the magnitudes, measured 1e-15
    np.testing.assert_allclose(w_back, w, rtol=0, atol=1e-13 * 5)
    np.testing.assert_allclose(f_back, f, rtol=0, atol=1e-13 * 50)
