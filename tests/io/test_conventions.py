"""The frame conventions (gfins_fmi.io.conventions): our DCM formula is the C core's
convention.
"""
from __future__ import annotations

import math

import numpy as np

import gfins_fmi as gf


def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def dcm_ours(heading, pitch, roll):
    """C_b^n of a right-front-up body in east-north-up (CONVENTIONS_AIDING, gf_sins.h)."""
    return rz(-heading) @ rx(pitch) @ ry(roll)


def dcm_of_quat(q):
    """Rotation matrix of a unit quaternion, scalar first (Hamilton)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_our_dcm_formula_is_the_c_cores_convention(rng):
    """The formula this file uses for our C_b^n is what the core's euler_to_quat encodes
    (to round-off: ~10 operations per entry, 1e-15)."""
    for _ in range(50):
        e = np.array([rng.uniform(0, 2 * np.pi), rng.uniform(-1.5, 1.5), rng.uniform(-3.1, 3.1)])
        assert np.abs(dcm_of_quat(gf.euler_to_quat(e)) - dcm_ours(*e)).max() < 1e-15
