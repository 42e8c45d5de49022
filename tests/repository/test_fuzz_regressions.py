"""Regression tests of the fuzzing findings (fuzz/README.md, table "Findings"), through
the Python API or the cffi binding; the C-only ones are replayed from the seed corpus by
tests/test_fuzz.py."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi._lib import ffi, lib
from gfins_fmi.io import ImuRecord
from gfins_fmi.io.errors import FileFormatError

A_M = 6378137.0


def test_1_earth_refuses_absurd_heights():
    g = ffi.new("double *")
    assert lib.gf_earth_gravity(0.5, 1.7e308, g) == lib.GF_ERR_BAD_PARAMETER
    assert lib.gf_earth_gravity(0.5, A_M / 3, g) == lib.GF_ERR_BAD_PARAMETER
    assert lib.gf_earth_gravity(0.5, 1e4, g) == lib.GF_OK and 9.7 < g[0] < 9.81
    e = ffi.new("gf_earth *")
    v = ffi.new("double[3]", [1.7e308, 0.0, 0.0])   # v tan L overflows
    assert lib.gf_earth_update(e, 1.5, 0.0, v, 1.0) == lib.GF_ERR_OUT_OF_RANGE


def test_5_set_navigation_keeps_the_latitude_limit():
    s = ffi.new("gf_sins_state *")
    cfg = ffi.new("gf_sins_config *")
    lib.gf_sins_config_default(cfg)
    q = ffi.new("double[4]", [1, 0, 0, 0])
    v = ffi.new("double[3]", [0, 0, 0])
    assert lib.gf_sins_init(s, cfg, q, v, 0.5, 0.1, 0.0, 0.0) == lib.GF_OK
    assert lib.gf_sins_set_navigation(s, q, v, 1.5704585, 0.1, 0.0) == lib.GF_ERR_BAD_PARAMETER
    # a quaternion of tiny components is made unit to round-off
    tiny = ffi.new("double[4]", [1e-160, 2e-160, 0, 0])
    assert lib.gf_sins_set_navigation(s, tiny, v, 0.5, 0.1, 0.0) == lib.GF_OK
    assert abs(sum(x * x for x in s.q_bn) - 1.0) < 1e-12


def test_9_10_imu_error_bounds():
    with pytest.raises(ValueError, match="gyro_bias"):
        gf.ImuErrors(gyro_bias_deg_h=[-1e308, 0, 0]).apply(np.zeros((1, 3)), np.zeros((1, 3)))
    e = gf.ImuErrors(accel_k2_ug_g2=[90.0, 0, 0])
    with pytest.raises(ValueError, match="sample 0"):   # beyond the K2 range: refused
        e.apply(np.zeros((1, 3)), np.array([[3e4, 0, 0]]))
    w, f = np.zeros((1, 3)), np.array([[900.0, 0, 0]])   # inside it: invertible
    np.testing.assert_allclose(e.compensate(*e.apply(w, f))[1], f, rtol=1e-14)


def test_11_biquad_overflow_is_reported():
    from gfins_fmi.nav.signal_conditioning import BiquadFilter
    flt = BiquadFilter([[1.0, 2.0, 1.0, 1.0, -0.5, 0.1]])
    with pytest.raises(gf.SampleError, match="overflows the filter") as ei:
        flt.filter(np.array([1.0, 1e308, 1.0]))
    assert ei.value.index == 1 and len(ei.value.partial) == 1


def test_12_from_csv_of_binary_bytes(tmp_path):
    p = tmp_path / "imu.csv"
    p.write_bytes(b"\xb6\xfc*")
    with pytest.raises(FileFormatError, match="not a text file"):
        ImuRecord.from_csv(p)


def test_19_gf9_reference_rate_overflow_is_refused():
    """A second sample over an absurd interval (1e307 s) with a large angular
    acceleration: the reference rate's trapezoid overflowed and gf9_step returned GF_OK
    with a state gf9_state_check refuses. Now: GF_ERR_OUT_OF_RANGE, state unchanged."""
    st = ffi.new("gf9_state *")
    assert lib.gf9_init(st, 0.1, ffi.new("double[3]", [0.0, 0.0, 0.0])) == lib.GF_OK
    out = ffi.new("gf9_output *")
    # outputs of angular acceleration w_dot = (0, 0, 100) rad/s^2 at rest, no rate:
    # A_k = (w_dot x u_k) . theta_k (tangential terms only) for the paper's layout
    geo = gf.accel9_geometry(0.1)
    A = gf.forward_model(geo, np.zeros((1, 3)), np.zeros((1, 3)), np.array([[0.0, 0.0, 100.0]]))[0]
    Ac = ffi.new("double[9]", list(A))
    assert lib.gf9_step(st, Ac, 0.01, out) == lib.GF_OK
    before = bytes(ffi.buffer(st))
    assert lib.gf9_step(st, Ac, 1e307, out) == lib.GF_ERR_OUT_OF_RANGE
    assert bytes(ffi.buffer(st)) == before


def test_13_15_rotation_schedule_bounds():
    """gf_rot_imu_static refuses a sample interval beyond 10 s (1e300 s overflowed the
    quadrature's piece count); gf_rot_eval refuses a damaged axis (it wrote beyond a
    quaternion)."""
    sched = ffi.new("gf_rot_schedule *")
    sched.q_mb0 = [1.0, 0.0, 0.0, 0.0]
    sched.n_segments = 1
    sched.segment[0].base_axis = -1
    sched.segment[0].imu_axis = 2
    sched.segment[0].imu_angle_rad = np.pi / 2
    sched.segment[0].move_s = 10.0
    sched.segment[0].ramp_s = 1.0
    sched.segment[0].dwell_s = 5.0
    st = ffi.new("gf_rot_state *")
    assert lib.gf_rot_init(st, sched, 0.0, ffi.NULL) == lib.GF_OK
    q = ffi.new("double[4]", [1, 0, 0, 0])
    th, dv, done = ffi.new("double[3]"), ffi.new("double[3]"), ffi.new("size_t *")
    assert lib.gf_rot_imu_static(st, q, 0.5, 0.0, 0.0, 1, 1e300, 0.0, th, dv, ffi.NULL, ffi.NULL,
                                 done) == lib.GF_ERR_BAD_TIME
    st.sched.segment[0].imu_axis = 55
    pose = ffi.new("gf_rot_pose *")
    assert lib.gf_rot_eval(st, 3.0, pose) == lib.GF_ERR_BAD_SIZE
