"""Classical calibration (multi-position static + rate table) on simulated data: the
estimates are unbiased and the reported stds are right (z-scores ~ N(0, 1))."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.calibration import laboratory as cal

DATASHEET = dict(gyro_bias_deg_h=10.0, gyro_scale_ppm=1000.0, gyro_misalignment_arcsec=100.0,
                 accel_bias_ug=1000.0, accel_scale_ppm=1000.0, accel_misalignment_arcsec=100.0,
                 accel_k2_ug_g2=50.0, lever_arm_cm=3.0)


def truth_of(e: gf.ImuErrors) -> dict:
    t = {}
    for i, ax in enumerate("xyz"):
        j, l = [x for x in range(3) if x != i]
        t[f"accel_bias_ug[{ax}]"] = e.accel_bias_ug[i]
        t[f"accel_scale_ppm[{ax}]"] = e.accel_scale_ppm[i]
        t[f"accel_k2_ug_g2[{ax}]"] = e.accel_k2_ug_g2[i]
        t[f"lever_arm_cm[{ax}]"] = e.lever_arm_cm[i]
        t[f"gyro_bias_deg_h[{ax}]"] = e.gyro_bias_deg_h[i]
        t[f"gyro_scale_ppm[{ax}]"] = e.gyro_scale_ppm[i]
        for k in (j, l):
            t[f"accel_misalignment_arcsec[{ax}{'xyz'[k]}]"] = e.accel_misalignment_arcsec[i, k]
            t[f"gyro_misalignment_arcsec[{ax}{'xyz'[k]}]"] = e.gyro_misalignment_arcsec[i, k]
    return t


def test_calibration_recovers_every_parameter_within_its_uncertainty():
    """50 random datasheet-level sets (30 parameters each). With Gaussian noise a z-score
    exceeds 3 in 0.27% of cases, so: at most 1% of the 1500 beyond 3 sigma, none beyond
    4.5, and mean z^2 within 1 +- 0.15 (chi-square over 1500 terms: std 0.037), which
    checks that the reported stds are the true ones. Measured: max |z| 3.09, 1 of 1500
    beyond 3, mean z^2 1.013."""
    plan = cal.test_plan()
    zs = []
    for seed in range(50):
        rng = np.random.default_rng(seed)
        e = gf.ImuErrors.random(rng, **DATASHEET)
        res = cal.calibrate(cal.simulate(e, plan, rng))
        truth = truth_of(e)
        assert set(truth) == set(res.estimate)
        zs.append([(res.estimate[k] - truth[k]) / res.std[k] for k in truth])
    zs = np.array(zs)
    print(f"calibration z-scores: max {np.abs(zs).max():.3f}, beyond 3: "
          f"{np.mean(np.abs(zs) > 3):.4f}, mean z^2 {np.mean(zs ** 2):.3f}")
    assert np.abs(zs).max() < 4.5
    assert np.mean(np.abs(zs) > 3) <= 0.01
    assert abs(np.mean(zs ** 2) - 1.0) <= 0.15


def test_compensation_with_the_calibrated_parameters():
    """Compensating with the estimates leaves residuals at the noise level of the fit."""
    rng = np.random.default_rng(99)
    e = gf.ImuErrors.random(rng, **DATASHEET)
    res = cal.calibrate(cal.simulate(e, cal.test_plan(), rng))
    w = rng.uniform(-1, 1, (200, 3))
    f = rng.uniform(-10, 10, (200, 3))
    w_out, f_out = e.apply(w, f)
    w2, f2 = res.errors.compensate(w_out, f_out)
    assert np.abs(f2 - f).max() < 1e-5 * 9.8        # < 10 ug: noise-limited estimates
    assert np.abs(w2 - w).max() < 1e-6              # rad/s
    assert np.abs(f_out - f).max() > 1e-3           # uncompensated: ~ the errors' size


def test_plan_that_cannot_determine_a_parameter_names_it():
    """Only the z axis up and down (static and on the table): the x accelerometer never
    sees a specific force along its axis or along y, so its scale factor, K2 and the
    y cross-coupling are undetermined."""
    full = cal.test_plan()
    keep = [k for k, n in enumerate(full.names) if "[0.0, 0.0, 1.0]" in n or "[0.0, 0.0, -1.0]" in n
            or n.startswith("table axis z")]
    plan = cal.TestPlan(full.f_m_s2[keep], full.omega_rad_s[keep], tuple(full.names[k] for k in keep))
    rng = np.random.default_rng(1)
    data = cal.simulate(gf.ImuErrors.random(rng, **DATASHEET), plan, rng)
    with pytest.raises(ValueError, match="cannot determine the accelerometer x-axis parameters "
                                         "scale, K2, N_xy"):
        cal.calibrate(data)


def test_stds_and_residuals_are_those_of_the_sensor_model():
    """The reported std of every parameter is sqrt(diag(sigma^2 (J^T J)^-1)) and the residual
    rms that of y - model, with the sensor model written out here from its documentation,
        accelerometer i: y = (1+s) u + K2 u^2 + b,  u = f_i + N_ij f_j + N_il f_l - r (w_j^2 + w_l^2)
        gyro i:          y = (1+s) (w_i + N_ij w_j + N_il w_l) + b
    and J taken by central differences at the reported estimate (the models are quadratic
    in the parameters: the differences are exact but for round-off, ~1e-10 relative with
    these steps). Tolerance 1e-6 relative: the estimate goes through the datasheet units
    and back."""
    rng = np.random.default_rng(7)
    e = gf.ImuErrors.random(rng, **DATASHEET)
    data = cal.simulate(e, cal.test_plan(), rng)
    res = cal.calibrate(data)
    f, w = data.plan.f_m_s2, data.plan.omega_rad_s
    ug, ppm, arcsec, deg_h = 9.80665e-6, 1e-6, np.pi / 180 / 3600, np.pi / 180 / 3600
    k2_unit = 1e-6 / 9.80665                       # ug/g^2 -> 1/(m/s^2)

    def fit_check(model, names, units, steps, y, sigma):
        p = np.array([res.estimate[n] * u for n, u in zip(names, units)])
        J = np.empty((len(y), len(p)))
        for k, h in enumerate(steps):
            dp = np.zeros(len(p))
            dp[k] = h
            J[:, k] = (model(p + dp) - model(p - dp)) / (2 * h)
        std = sigma * np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
        np.testing.assert_allclose([res.std[n] * u for n, u in zip(names, units)], std, rtol=1e-6)
        return y - model(p)

    ra, rg = [], []
    for i, ax in enumerate("xyz"):
        j, l = [x for x in range(3) if x != i]
        mis = [f"[{ax}{'xyz'[j]}]", f"[{ax}{'xyz'[l]}]"]
        cen = w[:, j] ** 2 + w[:, l] ** 2

        def accel(p, i=i, j=j, l=l, cen=cen):
            b, s, k2, nj, nl, r = p
            u = f[:, i] + nj * f[:, j] + nl * f[:, l] - r * cen
            return (1 + s) * u + k2 * u * u + b

        def gyro(p, i=i, j=j, l=l):
            b, s, nj, nl = p
            return (1 + s) * (w[:, i] + nj * w[:, j] + nl * w[:, l]) + b
        ra.append(fit_check(accel, [f"accel_bias_ug[{ax}]", f"accel_scale_ppm[{ax}]",
                                    f"accel_k2_ug_g2[{ax}]"] +
                            [f"accel_misalignment_arcsec{m}" for m in mis] + [f"lever_arm_cm[{ax}]"],
                            [ug, ppm, k2_unit, arcsec, arcsec, 0.01],
                            [1e-4, 1e-4, 1e-6, 1e-4, 1e-4, 1e-4],
                            data.accel_mean_m_s2[:, i], data.accel_sigma_m_s2))
        rg.append(fit_check(gyro, [f"gyro_bias_deg_h[{ax}]", f"gyro_scale_ppm[{ax}]"] +
                            [f"gyro_misalignment_arcsec{m}" for m in mis],
                            [deg_h, ppm, arcsec, arcsec], [1e-6, 1e-4, 1e-4, 1e-4],
                            data.gyro_mean_rad_s[:, i], data.gyro_sigma_rad_s))
    assert res.residual_rms_accel_m_s2 == pytest.approx(np.sqrt(np.mean(np.square(ra))), rel=1e-6)
    assert res.residual_rms_gyro_rad_s == pytest.approx(np.sqrt(np.mean(np.square(rg))), rel=1e-6)
