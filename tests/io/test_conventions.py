"""The frame conventions (gfins_fmi.io.conventions): our DCM formula is the C core's
convention.
"""
from __future__ import annotations

import itertools
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


def test_single_vectors_and_scalar_angles_keep_their_shape():
    """One vector (3,) maps to one vector; scalar angles give one (3,) attitude; a yaw a
    hair below zero wraps to a heading of exactly 0 (np.mod gives 2 pi there), not 2 pi."""
    from gfins_fmi.io.conventions import frd_to_rfu, ned_to_enu, rpy_frd_ned_to_euler_rfu_enu
    np.testing.assert_array_equal(frd_to_rfu(np.array([1.0, 2.0, 3.0])), [2.0, 1.0, -3.0])
    np.testing.assert_array_equal(ned_to_enu([4.0, 5.0, 6.0]), [5.0, 4.0, -6.0])
    np.testing.assert_array_equal(rpy_frd_ned_to_euler_rfu_enu(0.1, 0.2, 0.3), [0.3, 0.2, 0.1])
    e = rpy_frd_ned_to_euler_rfu_enu([0.0, 0.0], [0.0, 0.0], [-1e-300, -1e-17])
    assert e[0, 0] == 0.0 and 0.0 <= e[1, 0] < 2 * math.pi


def test_calendar_fields_at_their_limits():
    """Every field of a GPST calendar time at its limits: the first and last valid values
    pass (a leap second's 60.x included), one past either end is refused, with the first
    refused time and its index in the message (closed-form seconds since 1980-01-06)."""
    import pytest
    from gfins_fmi.io.conventions import gps_seconds_from_calendar as gps

    def one(*f):
        return float(gps(*(np.array([x]) for x in f))[0])
    day = 86400.0
    assert one(1980, 1, 6, 0, 0, 0.0) == 0.0
    assert one(1980, 1, 7, 23, 59, 60.5) == day + 23 * 3600 + 59 * 60 + 60.5
    assert one(1980, 12, 31, 0, 0, 0.0) == (366 - 6) * day       # 1980: a leap year
    assert one(1981, 1, 1, 0, 0, 0.0) == (366 - 5) * day
    assert one(1980, 2, 29, 0, 0, 0.0) == (31 - 5 + 28) * day
    for bad in [(1980, 0, 10, 0, 0, 0.0), (1980, 13, 10, 0, 0, 0.0), (1980, 1, 0, 0, 0, 0.0),
                (1980, 1, 32, 0, 0, 0.0), (1981, 2, 29, 0, 0, 0.0), (1980, 1, 10, -1, 0, 0.0),
                (1980, 1, 10, 24, 0, 0.0), (1980, 1, 10, 0, -1, 0.0), (1980, 1, 10, 0, 60, 0.0),
                (1980, 1, 10, 0, 0, -0.1), (1980, 1, 10, 0, 0, 61.0), (1980, 1, 10, 0, 0, 61.5),
                (1980, 1, 10, 0, 0, np.nan)]:
        with pytest.raises(ValueError, match="not a calendar time"):
            one(*bad)
    # two fields wrong in the same time: refused as well (the checks of different fields
    # must not cancel each other)
    good = (1980, 1, 10, 0, 0, 0.0)
    wrong = {1: (0, 13), 2: (0, 32), 3: (-1, 24), 4: (-1, 60), 5: (-0.1, 61.0, np.nan)}
    for i, j in itertools.combinations(wrong, 2):
        for a, b in itertools.product(wrong[i], wrong[j]):
            t = list(good)
            t[i], t[j] = a, b
            with pytest.raises(ValueError, match="not a calendar time"):
                one(*t)
    # several bad times: the first is named, with its index
    cols = [np.array(c) for c in zip((1980, 1, 10, 0, 0, 0.0), (1980, 13, 10, 0, 0, 0.0),
                                     (1980, 1, 10, 0, 0, 0.0), (1980, 1, 10, 25, 0, 0.0))]
    with pytest.raises(ValueError, match=r"1980/13/10 0:0:0.0 \(at index \[1\]\)"):
        gps(*cols)
