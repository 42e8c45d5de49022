"""Properties of the strapdown mechanization (hypothesis, a few derandomized cases): a run
followed by gf_sins_reverse and the same record backward returns to the initial state
(docs/sins.md); Strapdown.run in pieces or with a small chunk equals one run, bit for bit.
Truth: closed-form motions (gfins_fmi.sim.trajectory); the identities need no reference.
"""
from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra: pip install '.[test]'")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gfins_fmi as gf  # noqa: E402
from gfins_fmi.sim import trajectory as tj  # noqa: E402
from support.truth import attitude_error_rad, horizontal_error_m  # noqa: E402
from support.properties import FEW, SOME  # noqa: E402


def _circle(duration_s: float, dt_s: float, lat_rad: float, speed_m_s: float):
    motion = tj.Circle(speed_m_s=speed_m_s)
    motion.lat0_rad = lat_rad
    return tj.sample(motion, duration_s, dt_s)


@FEW
@given(duration_s=st.floats(2.0, 20.0), lat_rad=st.floats(-1.2, 1.2),
       speed_m_s=st.floats(1.0, 15.0), rates=st.booleans())
def test_forward_reverse_round_trip(duration_s, lat_rad, speed_m_s, rates):
    tr = _circle(duration_s, 0.01, lat_rad, speed_m_s)
    x0 = gf.NavState.from_trajectory(tr, 0)
    cfg = gf.SinsConfig(input="rates" if rates else "increments")
    gyro, accel = (tr.gyro_rad_s, tr.accel_m_s2) if rates else (tr.dtheta_rad, tr.dv_m_s)
    nav = gf.Strapdown(x0, cfg)
    nav.run(gyro, accel, dt_s=0.01)
    nav.reverse()
    nav.run(gyro, accel, dt_s=0.01)
    s = nav.state
    # bounds of the 600 s round trips of test_sins.py at 10 m/s (increments: 2e-5 m,
    # 4.6e-8 m/s; rates, whose mid-point extrapolation is not reversible: 1e-3 m,
    # 1e-9 rad); attitude of increments: 2.8e-11 rad measured at 15 m/s on the 100 m
    # circle (the coning truncation grows with the turn rate), bound 1e-10
    dpos = horizontal_error_m(np.array([s.lat_rad]), np.array([s.lon_rad]),
                              np.array([x0.lat_rad]), np.array([x0.lon_rad]))[0]
    datt = np.linalg.norm(attitude_error_rad(s.q_bn, x0.q_bn))
    assert abs(s.t_s - x0.t_s) < 1e-9
    assert dpos < (1e-3 if rates else 2e-5), f"position {dpos:.3g} m from the start"
    assert datt < (1e-9 if rates else 1e-10), f"attitude {datt:.3g} rad from the start"
    if not rates:
        assert np.abs(s.v_n_m_s - x0.v_n_m_s).max() < 4.6e-8
        assert abs(s.h_m - x0.h_m) < 1.3e-7


@SOME
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 400), data=st.data())
def test_strapdown_in_pieces_equals_whole(seed, n, data):
    rng = np.random.default_rng(seed)
    dth = rng.normal(0, 1e-3, (n, 3))          # any increments: the identity is exact
    dv = rng.normal(0, 1e-2, (n, 3)) + [0, 0, 0.098]
    x0 = gf.NavState.from_euler(rng.uniform(-1, 1, 3), rng.normal(0, 5, 3), 0.5, 2.0, 100.0)
    whole = gf.Strapdown(x0).run(dth, dv, dt_s=0.01)
    chunk = data.draw(st.integers(1, n), label="chunk")
    chunked = gf.Strapdown(x0).run(dth, dv, dt_s=0.01, chunk=chunk)
    cut = data.draw(st.integers(1, n - 1), label="cut")
    nav = gf.Strapdown(x0)
    a, b = nav.run(dth[:cut], dv[:cut], dt_s=0.01), nav.run(dth[cut:], dv[cut:], dt_s=0.01)
    for name in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"):
        w = getattr(whole, name)
        np.testing.assert_array_equal(getattr(chunked, name), w, err_msg=f"chunk={chunk}: {name}")
        np.testing.assert_array_equal(np.concatenate([getattr(a, name), getattr(b, name)]), w,
                                      err_msg=f"cut at {cut}: {name}")
