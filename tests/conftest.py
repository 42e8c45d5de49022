"""Shared test fixtures: truth that does not come from the code under test.

The sensor outputs of a motion are computed here with numpy from the output equation
(seed 000, eq. 1-2) written with the identity omega x (omega x u) = omega (omega.u) -
|omega|^2 u, and the 9-accelerometer layout is typed in from the paper's table.
"""
from __future__ import annotations

import os
import pathlib
import sys

# One BLAS thread (before numpy loads OpenBLAS): the tests' matrices are small, and
# OpenBLAS's threads spin-wait for work — on a busy 2-core machine a scipy expm of a
# 16 x 16 matrix took minutes (threads spinning against each other and other jobs).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Tests exercise the installed package (with its compiled core and FMUs), never the
# source folder: `python -m pytest` from the root would otherwise import ./gfins_fmi.
sys.path[:] = [p for p in sys.path if pathlib.Path(p or ".").resolve() != ROOT]
# Imported once here, before any test captures output: an editable install rebuilds the
# core on first import and its build writes to the real stdout.
import gfins_fmi  # noqa: E402,F401

EPS = np.finfo(float).eps
S2 = np.sqrt(0.5)


def paper_layout(l_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(u, theta) of seed 000 section 1, with u_7..u_9 = l[...] (not sqrt(l))."""
    u = l_m * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
                        [1, -1, 0], [1, 0, -1], [0, 1, -1]], float)
    th = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
                   [S2, S2, 0], [S2, 0, S2], [0, S2, S2]])
    return u, th


def numpy_outputs(u, th, f, w, wd) -> np.ndarray:
    """A[k, i] = th_i . (f_k + wd_k x u_i + w_k (w_k . u_i) - |w_k|^2 u_i), in numpy."""
    wdxu = np.cross(wd[:, None, :], u[None, :, :])                  # (n, N, 3)
    centripetal = w[:, None, :] * (w @ u.T)[:, :, None] - (w * w).sum(1)[:, None, None] * u[None]
    a = f[:, None, :] + wdxu + centripetal
    return np.einsum("nij,ij->ni", a, th)


#: rate of smooth_motion at t = 0 (rad/s): the omega_init its solutions start from
W0 = [0.0, 1.8, -2.0]


def smooth_motion(n: int, dt: float):
    """Closed-form f (m/s^2), omega (rad/s), omega_dot (rad/s^2) with zero crossings of
    omega_x (at t = 2 pi k) and omega_z (at t = 20 s)."""
    t = np.arange(n) * dt
    f = np.c_[1 + np.sin(0.7 * t), -2 + 0.5 * np.cos(1.3 * t), 9.8 + 0.2 * np.sin(0.3 * t)]
    w = np.c_[0.8 * np.sin(0.5 * t), 1.5 + 0.3 * np.cos(0.9 * t), -2 + 0.1 * t]
    wd = np.c_[0.4 * np.cos(0.5 * t), -0.27 * np.sin(0.9 * t), np.full(n, 0.1)]
    return t, f, w, wd


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


def attitude_error_rad(q_est, q_true) -> np.ndarray:
    """Rotation vector (n, 3), in the navigation frame, of q_est (x) q_true^*: the
    attitude error. atan2 form, accurate for small angles (arccos of the dot product
    is not: it bottoms out at ~1e-8 rad)."""
    qe, qt = np.atleast_2d(q_est), np.atleast_2d(q_true)
    # d = qe (x) conj(qt)
    w = np.sum(qe * qt, axis=1)
    v = (qt[:, :1] * qe[:, 1:] - qe[:, :1] * qt[:, 1:]
         - np.cross(qe[:, 1:], qt[:, 1:]))
    s = np.sign(w)[:, None]
    norm_v = np.linalg.norm(v, axis=1)
    angle = 2 * np.arctan2(norm_v, np.abs(w))
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(norm_v[:, None] > 0, v / norm_v[:, None], 0.0)
    return s * axis * angle[:, None]


def horizontal_error_m(lat, lon, lat_true, lon_true) -> np.ndarray:
    """Horizontal position error (m), small-difference approximation with the mean
    Earth radius (ample for errors below kilometres)."""
    R = 6371000.0
    return np.hypot((lat - lat_true) * R, (lon - lon_true) * R * np.cos(lat_true))


def navigate_init_args(tr) -> list:
    """`gfins navigate` options giving the initial state of a trajectory's first sample
    (degrees, full precision)."""
    import gfins_fmi as gf
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    return ["--lat0", repr(float(np.degrees(tr.lat_rad[0]))), "--lon0",
            repr(float(np.degrees(tr.lon_rad[0]))), "--h0", repr(float(tr.h_m[0])),
            "--heading0", repr(float(e[0])), "--pitch0", repr(float(e[1])), "--roll0",
            repr(float(e[2])), "--v0=" + ",".join(repr(float(x)) for x in tr.v_n_m_s[0])]
