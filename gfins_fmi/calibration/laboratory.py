"""Classical laboratory calibration of an IMU (seed 004): static multi-position tests and
rate-table rotations about up and down, solved by (Gauss-Newton) least squares for the
parameters of :class:`gfins_fmi.ImuErrors`, with a standard deviation for each.

Test plan (``test_plan``):
  * 18 static positions: each body axis up and down (6), and each pair of axes at 45
    degrees to the vertical (12), so that f_i takes the values 0, +-g/sqrt2 and +-g and
    bias, scale factor and K2 separate;
  * rate-table runs: each body axis up and down, turning at each table rate in both
    directions (an integer number of turns, so the Earth rate's horizontal part
    averages out); the turning also exposes the accelerometers' inner lever arms
    (centripetal r_i (w_j^2 + w_k^2)).
Each test gives the mean sensor output over its duration; the model is the exact one of
csrc/nav/gf_imu_error.h (at the reference temperature), fitted per axis:
  accelerometer i: b, s, K2, two cross-couplings N_ij, lever arm r_i;
  gyro i: b, s, two cross-couplings N_ij.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gfins_fmi.nav.earth import WGS84
from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, G0, PPM, UG, ImuErrors

__all__ = ["TestPlan", "test_plan", "CalibrationData", "simulate", "CalibrationResult",
           "calibrate"]

_OMEGA_IE = WGS84.omega_ie


@dataclass(frozen=True)
class TestPlan:
    """True mean specific force f (m, 3) and rate w (m, 3) in body axes per test."""
    f_m_s2: np.ndarray
    omega_rad_s: np.ndarray
    names: tuple


def test_plan(gravity_m_s2: float = G0, lat_rad: float = np.radians(30.0),
              table_rates_deg_s=(20.0, 100.0)) -> TestPlan:
    """The tests described in the module docstring at a site with this gravity and
    latitude. Static tests see the Earth rate projected on their attitude (north along
    the table's reference); rotating tests keep only its vertical part."""
    up_n, wie_n = np.array([0, 0, 1.0]), _OMEGA_IE * np.array([0, np.cos(lat_rad), np.sin(lat_rad)])
    f, w, names = [], [], []
    axes = np.eye(3)

    def body_frame(up_b):
        """A rotation C_n^b taking navigation up to the body vector up_b."""
        up_b = up_b / np.linalg.norm(up_b)
        helper = axes[np.argmin(np.abs(up_b))]
        north_b = np.cross(up_b, np.cross(helper, up_b))
        north_b /= np.linalg.norm(north_b)
        east_b = np.cross(north_b, up_b)
        return np.c_[east_b, north_b, up_b]          # columns: E, N, U in body axes

    statics = [s * axes[k] for k in range(3) for s in (1, -1)]
    for i in range(3):
        for j in range(i + 1, 3):
            for si in (1, -1):
                for sj in (1, -1):
                    statics.append(si * axes[i] + sj * axes[j])
    for up_b in statics:
        C = body_frame(up_b)
        f.append(C @ (gravity_m_s2 * up_n))
        w.append(C @ wie_n)
        names.append(f"static up={np.round(up_b / np.linalg.norm(up_b), 3).tolist()}")
    for k in range(3):
        for s in (1, -1):
            up_b = s * axes[k]
            for rate in table_rates_deg_s:
                for direction in (1, -1):
                    om = np.radians(rate) * direction
                    f.append(gravity_m_s2 * up_b)
                    # table spin about up + the Earth rate's vertical part (horizontal part
                    # averages to zero over whole turns)
                    w.append(up_b * (om + _OMEGA_IE * np.sin(lat_rad)))
                    names.append(f"table axis {'xyz'[k]}{'+' if s > 0 else '-'} up, "
                                 f"{direction * rate:+g} deg/s")
    return TestPlan(np.array(f), np.array(w), tuple(names))


@dataclass
class CalibrationData:
    """Mean sensor outputs per test and the std of each mean (m/s^2, rad/s)."""
    plan: TestPlan
    accel_mean_m_s2: np.ndarray
    gyro_mean_rad_s: np.ndarray
    accel_sigma_m_s2: float
    gyro_sigma_rad_s: float


def simulate(errors: ImuErrors, plan: TestPlan, rng: np.random.Generator,
             accel_noise_ug: float = 50.0, gyro_noise_deg_h: float = 0.05,
             samples_per_test: int = 10_000) -> CalibrationData:
    """Test data of an IMU with ``errors``: exact outputs of the error model plus the
    mean of ``samples_per_test`` white-noise samples (std given per sample)."""
    w_out, f_out = errors.apply(plan.omega_rad_s, plan.f_m_s2)
    sa = accel_noise_ug * UG / np.sqrt(samples_per_test)
    sg = gyro_noise_deg_h * DEG_H / np.sqrt(samples_per_test)
    return CalibrationData(plan, f_out + rng.normal(0, sa, f_out.shape),
                           w_out + rng.normal(0, sg, w_out.shape), sa, sg)


@dataclass
class CalibrationResult:
    """Estimated errors and the std of every parameter (datasheet units)."""
    errors: ImuErrors
    std: dict
    estimate: dict
    residual_rms_accel_m_s2: float
    residual_rms_gyro_rad_s: float

    def table(self) -> str:
        """Markdown table: parameter, estimate, std."""
        lines = ["| parameter | estimate | std |", "|---|---|---|"]
        for k in self.estimate:
            lines.append(f"| {k} | {self.estimate[k]:.6g} | {self.std[k]:.3g} |")
        return "\n".join(lines)


def _check_rank(J, names, axis, sensor):
    """Refuse a plan that cannot separate the parameters, naming them."""
    scale = np.maximum(np.abs(J).max(axis=0), 1e-300)
    _, sv, vt = np.linalg.svd(J / scale, full_matrices=False)
    weak = sv <= 1e-10 * sv[0]
    if np.any(weak):
        null = np.sqrt(np.sum(vt[weak] ** 2, axis=0))   # weight of each parameter in the null space
        involved = [n for n, v in zip(names, null) if v > 0.1]
        raise ValueError(f"the test plan cannot determine the {sensor} {axis}-axis parameters "
                         f"{', '.join(involved)} separately (add tilted positions or table rates)")


def _gauss_newton(model, n_params, y, sigma, names, axis, sensor):
    """Least squares on an exact sensor model: ``model(p)`` -> (prediction, Jacobian).
    Returns the parameters, their stds (white output noise sigma) and the residuals."""
    p = np.zeros(n_params)
    for _ in range(10):
        pred, J = model(p)
        _check_rank(J, names, axis, sensor)
        step, *_ = np.linalg.lstsq(J, y - pred, rcond=None)
        p += step
        if np.max(np.abs(step) / np.maximum(np.abs(p), 1e-30)) < 1e-13:
            break
    pred, J = model(p)
    cov = sigma ** 2 * np.linalg.inv(J.T @ J)
    return p, np.sqrt(np.diag(cov)), y - pred


def _fit_accel_axis(i, f, w, y, sigma):
    j, l = [x for x in range(3) if x != i]
    cen = w[:, j] ** 2 + w[:, l] ** 2            # centripetal factor of the lever arm

    def model(p):                                 # p = b, s, K2, N_ij, N_il, r
        b, s, k2, nj, nl, r = p
        u = f[:, i] + nj * f[:, j] + nl * f[:, l] - r * cen
        d = (1 + s) + 2 * k2 * u
        return ((1 + s) * u + k2 * u * u + b,
                np.c_[np.ones_like(u), u, u * u, d * f[:, j], d * f[:, l], -d * cen])
    names = ("bias", "scale", "K2", f"N_{'xyz'[i]}{'xyz'[j]}", f"N_{'xyz'[i]}{'xyz'[l]}", "lever arm")
    p, std, res = _gauss_newton(model, 6, y, sigma, names, "xyz"[i], "accelerometer")
    return p, std, (j, l), res


def _fit_gyro_axis(i, w, y, sigma):
    j, l = [x for x in range(3) if x != i]

    def model(p):                                 # p = b, s, N_ij, N_il
        b, s, nj, nl = p
        v = w[:, i] + nj * w[:, j] + nl * w[:, l]
        return (1 + s) * v + b, np.c_[np.ones_like(v), v, (1 + s) * w[:, j], (1 + s) * w[:, l]]
    names = ("bias", "scale", f"N_{'xyz'[i]}{'xyz'[j]}", f"N_{'xyz'[i]}{'xyz'[l]}")
    p, std, res = _gauss_newton(model, 4, y, sigma, names, "xyz"[i], "gyro")
    return p, std, (j, l), res


def calibrate(data: CalibrationData) -> CalibrationResult:
    """Least-squares estimates of the accelerometer and gyro parameters and their stds.

    Raises
    ------
    ValueError
        The test plan cannot determine a parameter (its normal matrix is singular); the
        message names the axis.
    """
    f, w = data.plan.f_m_s2, data.plan.omega_rad_s
    acc = dict(bias=np.zeros(3), scale=np.zeros(3), k2=np.zeros(3), lever=np.zeros(3),
               N=np.zeros((3, 3)))
    gyr = dict(bias=np.zeros(3), scale=np.zeros(3), N=np.zeros((3, 3)))
    est, std = {}, {}
    res_a, res_g = [], []
    for i, ax in enumerate("xyz"):
        pa, sa, (j, l), ra = _fit_accel_axis(i, f, w, data.accel_mean_m_s2[:, i], data.accel_sigma_m_s2)
        pg, sg, _, rg = _fit_gyro_axis(i, w, data.gyro_mean_rad_s[:, i], data.gyro_sigma_rad_s)
        res_a.append(ra)
        res_g.append(rg)
        acc["bias"][i], acc["scale"][i], acc["k2"][i] = pa[0], pa[1], pa[2]
        acc["N"][i, j], acc["N"][i, l], acc["lever"][i] = pa[3], pa[4], pa[5]
        gyr["bias"][i], gyr["scale"][i] = pg[0], pg[1]
        gyr["N"][i, j], gyr["N"][i, l] = pg[2], pg[3]
        for name, val, sd, unit in (
                (f"accel_bias_ug[{ax}]", pa[0], sa[0], UG), (f"accel_scale_ppm[{ax}]", pa[1], sa[1], PPM),
                (f"accel_k2_ug_g2[{ax}]", pa[2], sa[2], 1e-6 / G0),
                (f"accel_misalignment_arcsec[{ax}{'xyz'[j]}]", pa[3], sa[3], ARCSEC),
                (f"accel_misalignment_arcsec[{ax}{'xyz'[l]}]", pa[4], sa[4], ARCSEC),
                (f"lever_arm_cm[{ax}]", pa[5], sa[5], 0.01),
                (f"gyro_bias_deg_h[{ax}]", pg[0], sg[0], DEG_H), (f"gyro_scale_ppm[{ax}]", pg[1], sg[1], PPM),
                (f"gyro_misalignment_arcsec[{ax}{'xyz'[j]}]", pg[2], sg[2], ARCSEC),
                (f"gyro_misalignment_arcsec[{ax}{'xyz'[l]}]", pg[3], sg[3], ARCSEC)):
            est[name], std[name] = val / unit, sd / unit
    errors = ImuErrors(gyr["bias"] / DEG_H, gyr["scale"] / PPM, gyr["N"] / ARCSEC,
                       acc["bias"] / UG, acc["scale"] / PPM, acc["N"] / ARCSEC,
                       acc["k2"] * G0 / 1e-6, acc["lever"] / 0.01)
    return CalibrationResult(errors, std, est, float(np.sqrt(np.mean(np.square(res_a)))),
                             float(np.sqrt(np.mean(np.square(res_g)))))
