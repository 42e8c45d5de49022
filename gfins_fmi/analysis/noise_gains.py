"""How sensor noise maps into the 9-accelerometer solution: its noise gains.

Its f (eq. 3), omega^2 (eq. 4) and omega_dot (eq. 6) are linear in the outputs A, so
independent white noise of standard deviation sigma on every accelerometer gives each
solved component a noise of sigma * ||row of the solution matrix||. The rate itself, |omega_k| = sqrt(omega_k^2),
has to first order delta omega_k = delta(omega_k^2) / (2 |omega_k|): it grows without
bound as omega_k -> 0, the weakness that seed 000 leaves open.

The error-growth models (attitude, velocity, position) are the python-control systems of
:mod:`gfins_fmi.analysis.strapdown_errors` and :mod:`gfins_fmi.analysis.gyrofree_errors`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.gyrofree.array import Accel9Solver

__all__ = ["Accel9NoiseGains", "accel9_noise_gains"]


@dataclass(frozen=True)
class Accel9NoiseGains:
    """Standard deviation of each solved quantity per unit accelerometer noise (1 m/s^2).

    Attributes
    ----------
    M_f, M_omega_sq, M_omega_dot : ndarray (3, 9)
        Linear maps from the 9 outputs (m/s^2) to f (m/s^2), omega^2 (rad^2/s^2) and
        omega_dot (rad/s^2).
    f, omega_sq, omega_dot : ndarray (3,)
        Row norms of those maps: noise std per unit output noise.
    """

    l_m: float
    M_f: np.ndarray
    M_omega_sq: np.ndarray
    M_omega_dot: np.ndarray

    @property
    def f(self) -> np.ndarray:
        return np.linalg.norm(self.M_f, axis=1)

    @property
    def omega_sq(self) -> np.ndarray:
        return np.linalg.norm(self.M_omega_sq, axis=1)

    @property
    def omega_dot(self) -> np.ndarray:
        return np.linalg.norm(self.M_omega_dot, axis=1)

    def omega_std(self, sigma_m_s2: float, omega_rad_s) -> np.ndarray:
        """First-order std of the solved rate (rad/s) at rate ``omega_rad_s`` (3,) for
        output noise ``sigma_m_s2``; inf where a component is zero."""
        w = np.abs(np.asarray(omega_rad_s, dtype=float))
        with np.errstate(divide="ignore"):
            return sigma_m_s2 * self.omega_sq / (2 * w)


def accel9_noise_gains(l_m: float) -> Accel9NoiseGains:
    """Noise gains of the 9-accelerometer solution for lever arm ``l_m`` (m).

    The maps are read off the C solver itself by solving the 9 unit outputs e_j, so
    they are exactly what the core computes (closed forms, checked in the tests:
    |row| = 1/sqrt(2) for f, sqrt(6)/(4 l) for omega^2, 1/l for omega_dot).
    """
    solver = Accel9Solver(l_m)
    sol = solver.solve(np.eye(9), 1.0)  # sample j is e_j; the linear parts ignore dt
    return Accel9NoiseGains(float(l_m), sol.f_m_s2.T.copy(), sol.omega_sq_rad2_s2.T.copy(),
                            sol.omega_dot_rad_s2.T.copy())
