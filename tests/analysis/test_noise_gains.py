"""The noise gains of the 9-accelerometer solution (gfins_fmi.analysis.noise_gains): the
closed forms of seed 000's linear maps, and a Monte Carlo of the solver.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.analysis.noise_gains import accel9_noise_gains


@pytest.mark.parametrize("l", [0.05, 0.1, 0.3])
def test_noise_gains_closed_form(l):
    """Row norms of eq. 3, 4, 6 worked by hand: f_x = (A1 - A4)/2 -> 1/sqrt(2);
    w_x^2 = (A1 - A2 - A3 + A4 - A5 - A6)/(4l) -> sqrt(6)/(4l);
    wd_x = -(A2 - A6 - sqrt2 A9)/(2l) -> sqrt(1 + 1 + 2)/(2l) = 1/l."""
    g = accel9_noise_gains(l)
    np.testing.assert_allclose(g.f, np.full(3, np.sqrt(0.5)), rtol=1e-15)
    np.testing.assert_allclose(g.omega_sq, np.full(3, np.sqrt(6) / (4 * l)), rtol=1e-15)
    np.testing.assert_allclose(g.omega_dot, np.full(3, 1 / l), rtol=1e-15)


def test_noise_gains_match_monte_carlo():
    """Predicted std vs 200 000 noisy samples: the sample std of a Gaussian has a
    relative standard error 1/sqrt(2N) = 0.16%; allow 1.5% (about 9 sigma)."""
    l, sigma, n = 0.1, 1e-3, 200_000
    rng = np.random.default_rng(3)
    noise = rng.normal(0, sigma, (n, 9))
    sol = gf.solve_accel9(noise, 0.01, l)  # zero motion: the solution is pure noise
    g = accel9_noise_gains(l)
    np.testing.assert_allclose(sol.f_m_s2.std(axis=0), sigma * g.f, rtol=0.015)
    np.testing.assert_allclose(sol.omega_sq_rad2_s2.std(axis=0), sigma * g.omega_sq, rtol=0.015)
    np.testing.assert_allclose(sol.omega_dot_rad_s2.std(axis=0), sigma * g.omega_dot, rtol=0.015)
