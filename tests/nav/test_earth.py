"""The Earth model and the Euler conventions: the C core's gf_earth against the independent
formulas of gfins_fmi.nav.earth and published values, and seed 002's Euler convention in
the C core and in numpy.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.nav import earth
from gfins_fmi._lib import ffi, lib

DEG = np.pi / 180


def test_earth_model_matches_independent_and_published_values():
    lat = np.radians([0.0, 30.0, 45.0, 60.0, 89.0])
    h = np.array([0.0, 100.0, 1000.0, -50.0, 5000.0])
    RM, RN, g = (np.empty(5) for _ in range(3))
    done = ffi.new("size_t *")
    assert lib.gf_earth_batch(5, ffi.from_buffer("double[]", lat), ffi.from_buffer("double[]", h),
                              ffi.from_buffer("double[]", RM), ffi.from_buffer("double[]", RN),
                              ffi.from_buffer("double[]", g), done) == lib.GF_OK
    rm, rn, _, _ = earth.radii(lat)
    np.testing.assert_allclose(RM, rm, rtol=4e-16)
    np.testing.assert_allclose(RN, rn, rtol=4e-16)
    np.testing.assert_allclose(g, earth.gravity(lat, h), rtol=4e-16)
    # published WGS-84 values (NIMA TR8350.2): normal gravity on the ellipsoid at the
    # equator and the pole; R_N at the equator is a, R_M there is a (1 - e^2)
    def grav(lat, h):
        g = ffi.new("double *")
        assert lib.gf_earth_gravity(lat, h, g) == lib.GF_OK
        return g[0]
    assert grav(0.0, 0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert grav(np.pi / 2 - 1e-12, 0.0) == pytest.approx(9.8321849378, abs=1e-9)
    assert RN[0] == pytest.approx(6378137.0, abs=1e-6)
    assert RM[0] == pytest.approx(6378137.0 * (1 - 0.00669437999014), abs=1e-3)
    # free-air gradient ~ -3.086e-6 s^-2 at the surface
    assert (grav(0.0, 1.0) - grav(0.0, 0.0)) == pytest.approx(-3.086e-6, rel=2e-3)


def test_euler_conventions_of_seed_002():
    # heading 90 deg (clockwise from north): the body's front axis points east
    q = gf.euler_to_quat([90 * DEG, 0, 0])
    C = earth.quat_to_dcm(q)
    np.testing.assert_allclose(C @ [0, 1, 0], [1, 0, 0], atol=1e-15)
    # pitch +10 deg: nose up; roll +10 deg: right wing down
    C = earth.quat_to_dcm(gf.euler_to_quat([0, 10 * DEG, 0]))
    assert (C @ [0, 1, 0])[2] == pytest.approx(np.sin(10 * DEG), abs=1e-15)
    C = earth.quat_to_dcm(gf.euler_to_quat([0, 0, 10 * DEG]))
    assert (C @ [1, 0, 0])[2] == pytest.approx(-np.sin(10 * DEG), abs=1e-15)
    # round trip over the documented ranges; heading wraps into [0, 2 pi)
    rng = np.random.default_rng(5)
    e = np.c_[rng.uniform(0, 2 * np.pi, 500), rng.uniform(-1.5, 1.5, 500), rng.uniform(-3.1, 3.1, 500)]
    q = np.array([gf.euler_to_quat(x) for x in e])
    np.testing.assert_allclose(gf.quat_to_euler(q), e, atol=2e-13)
    np.testing.assert_allclose(earth.euler_to_quat(e[:, 0], e[:, 1], e[:, 2]), q, atol=1e-15)
