"""Errors of the accelerometers of an array: for simulation (``apply``) and, when they
are known (calibrated), for compensation (``compensate`` + ``actual_geometry``).

Sensor i reads

    A_i = (1 + s_i) theta'_i . [f + w_dot x u'_i + w x (w x u'_i)] + b_i + n_i(t)

with scale-factor error s_i, bias b_i, the sensing direction theta'_i tilted from its
nominal theta_i by two small angles about axes perpendicular to it, the position
u'_i = u_i + du_i, and noise n_i = white (std per sample) + band-limited (white noise
through a first-order low-pass of the given bandwidth, scaled to the given std).
Compensating a known set inverts the affine part, (A - b) / (1 + s), and solves with the
actual geometry (u', theta'); noise stays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.gyrofree.array import ArrayGeometry, forward_model
from gfins_fmi.nav.noise import first_order_lowpass_noise

__all__ = ["ArraySensorErrors"]


def _perpendicular_axes(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes perpendicular to each row of theta (and to each other)."""
    helper = np.eye(3)[np.argmin(np.abs(theta), axis=1)]
    e1 = np.cross(theta, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(theta, e1)


@dataclass
class ArraySensorErrors:
    """Errors of N accelerometers (SI units; see the module docstring).

    Parameters
    ----------
    bias_m_s2 : (N,)
    scale : (N,)
        Scale-factor errors (dimensionless, |s| < 1; 100 ppm = 1e-4).
    misalignment_rad : (N, 2)
        Tilts of each sensing direction about two axes perpendicular to it (< 1 rad).
    position_error_m : (N, 3)
    white_noise_m_s2 : float
        Std of the white noise per sample.
    band_noise_m_s2, band_hz : float
        Std and bandwidth of the band-limited noise (0 = none).
    """

    bias_m_s2: np.ndarray
    scale: np.ndarray
    misalignment_rad: np.ndarray
    position_error_m: np.ndarray
    white_noise_m_s2: float = 0.0
    band_noise_m_s2: float = 0.0
    band_hz: float = 0.0

    def __post_init__(self):
        b = np.asarray(self.bias_m_s2, float)
        n = b.shape[0] if b.ndim == 1 else -1
        if n < 1:
            raise ValueError(f"bias_m_s2 must have shape (N,); got {b.shape}")
        shapes = {"bias_m_s2": (n,), "scale": (n,), "misalignment_rad": (n, 2),
                  "position_error_m": (n, 3)}
        for name, shape in shapes.items():
            arr = np.asarray(getattr(self, name), float)
            if arr.shape != shape:
                raise ValueError(f"{name} must have shape {shape} for {n} sensors; got {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name} must be finite")
            object.__setattr__(self, name, arr)
        if np.any(np.abs(self.scale) >= 1):
            i = int(np.argmax(np.abs(self.scale)))
            raise ValueError(f"scale[{i}] = {float(self.scale[i])!r}: a scale-factor error must be "
                             "below 1 in magnitude (it is relative: 100 ppm = 1e-4)")
        if np.any(np.abs(self.misalignment_rad) >= 1):
            i = int(np.argmax(np.abs(self.misalignment_rad).max(axis=1)))
            raise ValueError(f"misalignment_rad[{i}] = {self.misalignment_rad[i].tolist()}: "
                             "misalignments must be below 1 rad (they are small angles)")
        for name in ("white_noise_m_s2", "band_noise_m_s2", "band_hz"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0; got {v!r}")
        if self.band_noise_m_s2 > 0 and not self.band_hz > 0:
            raise ValueError("band_noise_m_s2 > 0 needs band_hz > 0")

    @property
    def n_sensors(self) -> int:
        return int(self.bias_m_s2.shape[0])

    @classmethod
    def random(cls, n_sensors: int, rng: np.random.Generator, bias_std_m_s2: float = 0.0,
               scale_std: float = 0.0, misalignment_std_rad: float = 0.0,
               position_std_m: float = 0.0, **noise) -> "ArraySensorErrors":
        """Errors drawn from zero-mean normal distributions with the given stds."""
        return cls(rng.normal(0, bias_std_m_s2, n_sensors), rng.normal(0, scale_std, n_sensors),
                   rng.normal(0, misalignment_std_rad, (n_sensors, 2)),
                   rng.normal(0, position_std_m, (n_sensors, 3)), **noise)

    def _check(self, geometry: ArrayGeometry) -> None:
        if geometry.n_sensors != self.n_sensors:
            raise ValueError(f"the errors are for {self.n_sensors} sensors, the geometry has "
                             f"{geometry.n_sensors}")

    def actual_geometry(self, nominal: ArrayGeometry) -> ArrayGeometry:
        """The geometry the sensors really have: positions moved, directions tilted."""
        self._check(nominal)
        e1, e2 = _perpendicular_axes(nominal.theta)
        m = self.misalignment_rad
        ang = np.linalg.norm(m, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            axis = np.where(ang > 0, (m[:, :1] * e1 + m[:, 1:] * e2) / ang, 0.0)
        theta = np.cos(ang) * nominal.theta + np.sin(ang) * axis       # exact unit vectors
        theta /= np.linalg.norm(theta, axis=1, keepdims=True)
        return ArrayGeometry(nominal.u_m + self.position_error_m, theta)

    def noise(self, n_samples: int, dt_s: float, rng: np.random.Generator) -> np.ndarray:
        """Noise (n_samples, N): white plus band-limited (stationary from the start)."""
        out = rng.normal(0.0, self.white_noise_m_s2, (n_samples, self.n_sensors)) \
            if self.white_noise_m_s2 > 0 else np.zeros((n_samples, self.n_sensors))
        if self.band_noise_m_s2 > 0:
            out += first_order_lowpass_noise(n_samples, self.n_sensors, self.band_noise_m_s2,
                                             self.band_hz, dt_s, rng)
        return out

    def apply(self, nominal: ArrayGeometry, f_m_s2, omega_rad_s, omega_dot_rad_s2, dt_s: float,
              rng: np.random.Generator | None = None) -> np.ndarray:
        """Outputs (n, N) of the erroneous array riding a motion (rows of f, w, w_dot)."""
        A = forward_model(self.actual_geometry(nominal), f_m_s2, omega_rad_s, omega_dot_rad_s2)
        A = A * (1.0 + self.scale) + self.bias_m_s2
        if self.white_noise_m_s2 > 0 or self.band_noise_m_s2 > 0:
            if rng is None:
                raise ValueError("noise needs a random generator: pass rng=np.random.default_rng(seed)")
            A += self.noise(A.shape[0], dt_s, rng)
        return A

    def compensate(self, A_m_s2) -> np.ndarray:
        """Known bias and scale removed: (A - b) / (1 + s); solve the result with
        :meth:`actual_geometry`."""
        A = np.asarray(A_m_s2, float)
        if A.ndim != 2 or A.shape[1] != self.n_sensors:
            raise ValueError(f"A_m_s2 must have shape (n, {self.n_sensors}); got {A.shape}")
        return (A - self.bias_m_s2) / (1.0 + self.scale)
