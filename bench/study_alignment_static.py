"""Static alignment by Monte Carlo (issue 13): a navigation-grade IMU (gyro bias 0.01 deg/h,
accelerometer bias 50 ug, random constants drawn per run; ARW 0.001 deg/sqrt(h), 5 ug/sqrt(Hz))
at rest at 30 deg latitude for 5 minutes; coarse alignment (levelling, gyrocompassing)
over the first 60 s, then the fine-alignment filter (zero velocity at the known position,
10 Hz) over the 5 minutes.

What physics allows (at rest the horizontal accelerometer biases look like tilt and the
east gyro bias like heading): phi_N = da_E / g, phi_E = -da_N / g,
phi_U = (W sinL phi_N - eps_E) / (W cos L), with the true biases in navigation axes.
Printed: RMS over the runs of the attitude errors against RMS of those limits (the same
runs), the fraction of error components beyond 3 sigma and the mean NEES with its bounds.

    python bench/study_alignment_static.py [--runs 100] [--seconds 300] [--lat-deg 30]
"""
from __future__ import annotations

import argparse

import numpy as np

from gfins_fmi.sim import trajectory as tj
from gfins_fmi.nav import earth
from gfins_fmi.estimation import FilterConfig
from gfins_fmi.estimation.alignment import coarse_align
from gfins_fmi.estimation.fine_alignment import fine_align
from gfins_fmi.estimation.evaluation import attitude_difference_rad, chi2_band
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.io.records import ImuRecord

DEG = np.pi / 180
UG = 9.80665e-6
OMEGA = 7.292115e-5


def run(runs=100, seconds=300.0, lat_deg=30.0, dt=0.01, seed0=0, heading_deg=37.0, verbose=True):
    lat = lat_deg * DEG
    motion = tj.Stationary(heading=heading_deg * DEG, pitch=1.5 * DEG, roll=-2.0 * DEG, lat=lat)
    tr = tj.sample(motion, seconds, dt)
    C = np.array(earth.quat_to_dcm(tr.q_bn[0]))
    noise = ImuNoise(gyro_arw_deg_sqrt_h=0.001, accel_vrw_ug_sqrt_hz=5.0)
    sig_g, sig_a = 0.01 * DEG / 3600, 50 * UG
    cfg = FilterConfig(imu=noise, gate_probability=None)
    err, lim, std = [], [], []
    n = len(tr.t_s) - 1
    for r in range(runs):
        rng = np.random.default_rng(seed0 + r)
        bg, ba = rng.normal(0, sig_g, 3), rng.normal(0, sig_a, 3)
        wn, an = noise.sample(n, dt, rng)
        imu = ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad + (bg + wn) * dt, accel=tr.dv_m_s + (ba + an) * dt,
                        kind="increments")
        co = coarse_align(imu, tr.t_s[0], 60.0, lat, gyro_bias_std_rad_s=sig_g, accel_bias_std_m_s2=sig_a)
        fa = fine_align(imu, lat, tr.lon_rad[0], tr.h_m[0], config=cfg, coarse=co, t0_s=tr.t_s[0],
                        gyro_bias_std_rad_s=sig_g, accel_bias_std_m_s2=sig_a)
        phi = -attitude_difference_rad(fa.q_bn, tr.q_bn[-1])[0]         # the filter's convention
        eps, da = C @ bg, C @ ba
        g = np.linalg.norm(tr.accel_m_s2[0])
        pN, pE = da[0] / g, -da[1] / g
        pU = (OMEGA * np.sin(lat) * pN - eps[0]) / (OMEGA * np.cos(lat))
        err.append(phi)
        lim.append([pE, pN, pU])
        std.append(fa.attitude_std_rad)
    err, lim, std = np.array(err), np.array(lim), np.array(std)
    rms_e, rms_l = np.sqrt(np.mean(err ** 2, 0)), np.sqrt(np.mean(lim ** 2, 0))
    z = err / std
    nees = np.mean(np.sum(z ** 2, 1))
    lo, hi = chi2_band(3, runs, 0.99)
    out = dict(rms_err=rms_e, rms_limit=rms_l, ratio=rms_e / rms_l, beyond3=float(np.mean(np.abs(z) > 3)),
               mean_nees=float(nees), nees_band=(lo, hi), err=err, lim=lim, std=std)
    if verbose:
        names = ("east (level)", "north (level)", "up (heading)")
        for i in range(3):
            print(f"{names[i]:14s}: RMS error {rms_e[i] / DEG * 3600:8.2f} arcsec, limit {rms_l[i] / DEG * 3600:8.2f} "
                  f"arcsec, ratio {rms_e[i] / rms_l[i]:.3f}; mean filter sigma {np.mean(std[:, i]) / DEG * 3600:.2f} arcsec")
        print(f"{runs} runs: |error| > 3 sigma in {100 * out['beyond3']:.2f}% of {3 * runs} components "
              f"(Gaussian: 0.27%); mean NEES {nees:.3f} (99% band of the mean of {runs} chi2(3): "
              f"[{lo:.3f}, {hi:.3f}])")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=300.0)
    ap.add_argument("--lat-deg", type=float, default=30.0)
    a = ap.parse_args(argv)
    run(a.runs, a.seconds, a.lat_deg)


if __name__ == "__main__":
    main()
