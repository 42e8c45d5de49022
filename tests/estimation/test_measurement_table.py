"""The filter's table of measurement kinds (csrc/est/gf_ins_meas.c) through the Python
layer: the kinds the C core enumerates are the ones Python names, and every kind's
Jacobian H is its own prediction's derivative. Truth: central differences of the C
prediction (gf_ins_meas_model), never the linearisation under test; the C test
tests/c/test_ins_meas.c does the same over 12 random states with every state enabled.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi._lib import ffi, lib, ptr
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.config import MEAS_TYPES

OMEGA_IE = 7.292115e-5          # rad/s, WGS-84 (written out: not from the core)


def c_kinds() -> dict:
    """code -> (name, rows) of every kind gf_ins_meas_kind_info answers for in 0..63."""
    out = {}
    rows, name = ffi.new("int32_t *"), ffi.new("char **")
    for k in range(-1, 64):
        st = lib.gf_ins_meas_kind_info(k, rows, ffi.cast("const char **", name))
        assert st in (lib.GF_OK, lib.GF_ERR_BAD_PARAMETER)
        if st == lib.GF_OK:
            out[k] = (ffi.string(name[0]).decode(), int(rows[0]))
    return out


def test_python_names_the_c_table_s_kinds():
    kinds = c_kinds()
    assert {k: v[0] for k, v in kinds.items()} == MEAS_TYPES
    assert all(1 <= r <= 3 for _, r in kinds.values())


def _filter(reversed_: bool):
    """A filter with all 38 states, lever arms, a boresight, a slave's mounting, lever arm,
    time offset and flexure, rates, sensor and transfer estimates."""
    rng = np.random.default_rng(7)
    cfg = FilterConfig(imu=gf.ImuNoise(gyro_arw_deg_sqrt_h=0.1, accel_vrw_ug_sqrt_hz=50,
                                       gyro_bias_instability_deg_h=1, accel_bias_instability_ug=100),
                       scale_factors=True, baro_bias=True, odometer_scale=True, odometer_mount=True,
                       gnss_lever_arm_m=(0.7, -1.1, 1.4), odometer_lever_arm_m=(-0.6, 1.8, -0.4),
                       odometer_mount_rad=(0.03, -0.02), master_mount=True, master_lever=True,
                       master_time_offset=True, flexure=True, master_mount_rad=(2.5, 0.4, -0.7),
                       master_lever_arm_m=(0.4, -2.0, 0.6), master_time_offset_s=-0.03)
    q = gf.euler_to_quat(np.array([2.1, 0.2, -0.3]))
    nav = gf.NavState(q, np.array([6.0, -9.0, 0.4]), 0.7, 2.0, 450.0, 100.0)
    sensors = np.r_[rng.uniform(-1e-4, 1e-4, 3), rng.uniform(-0.05, 0.05, 3),
                    rng.uniform(-1e-3, 1e-3, 6), 2.0, 0.01, 0.01, -0.015]
    f = IntegratedNavigator(cfg, InitialState(nav, sensors=sensors))._f
    f.w_ib_b_rad_s = [0.12, -0.07, 0.21]
    f.f_b_m_s2 = [0.8, -1.3, 9.6]
    f.transfer = list(rng.uniform(-0.01, 0.01, 13))
    f.still_w = [0.01, -0.02, 0.015]
    if reversed_:
        assert lib.gf_ins_reverse(f) == lib.GF_OK
    return f


def _model(f, kind, rows, dx=None):
    n = int(f.n_states)
    z = np.empty(rows)
    H = np.empty((rows, n))
    m = ffi.new("int32_t *")
    d = ffi.NULL if dx is None else ptr(dx, n)
    assert lib.gf_ins_meas_model(f, kind, ffi.NULL, d, ptr(z, rows), ptr(H, H.size), m) == lib.GF_OK
    assert m[0] == rows
    return z, H


def _step(j: int) -> float:
    """Central-difference step of state j in its unit (the C test's steps)."""
    if j < 3:
        return 1e-3
    if j < 6:
        return 1e-2 if j == 5 else 1e-7
    if j < 9:
        return 1e-5
    if j < 12:
        return 1e-6
    if j < 15:
        return 1e-4
    if 28 <= j < 31:                        # lever arm, m (the C test's step)
        return 1e-4
    return 1e-2 if j == 21 else 1e-5


@pytest.mark.parametrize("reversed_", [False, True], ids=["forward", "reversed"])
def test_every_kind_s_jacobian_is_its_prediction_s_derivative(reversed_):
    """H = -(z(+h e_j) - z(-h e_j)) / 2h column by column (z_err = predicted - measured =
    H dx, dx the error the feedback removes). Tolerance per entry, as in
    tests/c/test_ins_meas.c: 1e-6 |H| (truncation, h^2/6 of the third derivative: < 1e-7
    for these steps), 1e3 eps (1 + |z|) / h (rounding of two predictions), and the
    Earth-rate terms H leaves out on purpose (gf_ins_gnss.h): |w_ie| |l| per rad of
    attitude or latitude where w_eb^b x l enters, |w_ie| per rad of latitude for ZARU."""
    f = _filter(reversed_)
    n = int(f.n_states)
    lg, lo = np.array(list(f.cfg.gnss_lever_arm_m)), np.array(list(f.cfg.odometer_lever_arm_m))
    eps = np.finfo(float).eps
    for kind, (name, rows) in c_kinds().items():
        if name == "speed" and reversed_:
            continue                       # the speed model is the same either way in time
        z0, H = _model(f, kind, rows)
        cd = np.empty_like(H)
        for j in range(n):
            h = _step(j)
            e = np.zeros(n)
            e[j] = h
            zp, _ = _model(f, kind, rows, e)
            zm, _ = _model(f, kind, rows, -e)
            cd[:, j] = -(zp - zm) / (2 * h)
        allow = np.zeros_like(H)
        earth = {"gnss_vel": np.linalg.norm(lg), "odometer": 1.02 * np.linalg.norm(lo),
                 "nhc": 1.02 * np.linalg.norm(lo), "zaru": None}
        if name in earth:
            cols = [3] if name == "zaru" else [3, 6, 7, 8]
            allow[:, cols] = OMEGA_IE * (1.0 if earth[name] is None else earth[name])
        tol = 1e-6 * np.abs(H) + 1e3 * eps * (1 + np.abs(z0))[:, None] / np.array(
            [_step(j) for j in range(n)])[None, :] + allow
        bad = np.argwhere(np.abs(H - cd) > tol)
        assert bad.size == 0, (name, [(int(i), int(j), H[i, j], cd[i, j]) for i, j in bad[:5]])
