"""Plausibility of finite inputs from the physics (gfins_fmi/nav/plausibility.py, issue 21).

Truth: closed forms — a body at rest at latitude L measures the Earth rate
Omega (0, cos L, sin L) in a level north-facing frame and gravity up, in any orientation
after a rotation; an accelerometer array on a smooth motion gives omega^2 and omega_dot
whose relation d(omega^2)/dt = 2 omega omega_dot fixes the sample interval.
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.nav.earth import rotation_matrix
from gfins_fmi.nav.plausibility import (interval_problem, latitude_from_earth_rate, latitude_problem,
                                        report, specific_force_problem, PlausibilityWarning)
from support.truth import OMEGA, smooth_motion


@pytest.mark.parametrize("lat_deg", [-80.0, -34.0, 0.0, 12.5, 60.0])
def test_latitude_from_the_earth_rate_in_any_orientation(lat_deg):
    """The latitude is the angle of the Earth rate above the horizontal plane of the
    measured vertical: independent of how the body sits (a random rotation here). Round-off
    only: 1e-12 rad."""
    lat = np.radians(lat_deg)
    w_n = OMEGA * np.array([0.0, np.cos(lat), np.sin(lat)])
    f_n = np.array([0.0, 0.0, 9.8])
    rng = np.random.default_rng(21)
    for _ in range(5):
        C = rotation_matrix(rng.normal(size=3))          # any body attitude
        assert abs(latitude_from_earth_rate(C.T @ w_n, C.T @ f_n) - lat) < 1e-12


def test_latitude_problem_needs_gyros_that_can_tell():
    lat = np.radians(34.0)
    w = OMEGA * np.array([0.0, np.cos(lat), np.sin(lat)])
    f = np.array([0.0, 0.0, 9.8])
    assert latitude_problem(lat, w, f, 1e-8) is None                       # the right one
    assert latitude_problem(np.radians(35.5), w, f, 1e-8) is None          # within 2 deg
    msg = latitude_problem(np.radians(60.0), w, f, 1e-8)
    assert msg and "is 26 deg from the one the gyros measure at rest, 34.0000 deg" in msg
    # gyro bias sigma 5 deg/h (1/3 of the Earth rate): a consumer gyro cannot say
    assert latitude_problem(np.radians(60.0), w, f, np.radians(5.0) / 3600) is None


@pytest.mark.parametrize("scale, hint", [(1.0, None), (1e-3, "times in ms where s are expected"),
                                         (1 / 9.80665, "accelerations in g"),
                                         (1000.0, "accelerations in mg or mm/s^2"),
                                         (3.28084, "ft/s^2")])
def test_specific_force_against_gravity(scale, hint):
    f = 9.80665 * scale * (1 + 0.05 * np.sin(np.arange(500.0)))
    msg = specific_force_problem(f, "rec.csv")
    assert (msg is None) == (hint is None)
    if hint:
        assert msg.startswith("rec.csv: the median specific force") and hint in msg
    assert specific_force_problem(np.zeros(10)) is None      # free fall or synthetic: nothing to say


def test_interval_from_the_records_own_rates():
    """omega^2 and omega_dot of a smooth motion sampled at 0.01 s: the interval they imply
    is 0.01 s (to the first order of the sampling: the factor-20 margin is far wider);
    given 10 s (ms read as s) it is named."""
    _, _, w, wd = smooth_motion(1001, 0.01)
    w2 = w ** 2
    assert interval_problem(0.01, w2, wd) is None
    msg = interval_problem(10.0, w2, wd, "rec")
    assert msg and "the interval given is 1000 times longer" in msg.replace("1e+03", "1000")
    assert "times in ms where s are expected" in msg
    assert interval_problem(0.01, np.zeros((100, 3)), np.zeros((100, 3))) is None   # no motion
    # one way only: noise makes the implied interval longer, so a given one far shorter
    # proves nothing: white noise alone (no motion to speak of) is not flagged
    rng = np.random.default_rng(25)
    assert interval_problem(1e-5, w2, wd) is None
    assert interval_problem(0.01, 1.0 + 1e-3 * rng.normal(size=(500, 3)),
                            1e-3 * rng.normal(size=(500, 3))) is None


def test_report_raises_warns_or_stays_quiet():
    with pytest.raises(KeyError, match="x"):
        report(["x", None], "raise", error=KeyError)
    with pytest.warns(PlausibilityWarning, match="x"):
        assert report([None, "x"], "warn") == ["x"]
    assert report(["x"], "off") == ["x"]
    with pytest.raises(ValueError, match="checks must be one of"):
        report([], "loud")
