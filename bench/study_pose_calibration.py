"""Calibration at unknown poses on simulated hand-turned consumer MEMS records (issue 23's
acceptance): N random error sets (scale 2% std, misalignment 0.5 deg std, accelerometer
bias 0.3 m/s^2, gyro bias 2 deg/s std -- ImuErrors.random with CONSUMER_MEMS_ERRORS),
36 poses at random orientations, 5-10 s still, 1-3 s minimum-jerk turns with a wobble,
100 Hz, white noise 0.6 deg/sqrt(h) and 150 ug/sqrt(Hz), on a rotating Earth. Each
fitted parameter is compared with the truth in the accelerometer-defined frame
(pose_frame_truth): the fraction of (set, parameter) pairs within 3 stated sigma, the
largest |z|, the pose-mean gravity-norm residual against its noise floor and the
gravity-direction residual of the gyro fit against its own.

    python bench/study_pose_calibration.py [--sets 50] [--first-seed 0] [--poses 36]

Results: docs/characterise_imu.md, "How well it works".
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.calibration.poses import calibrate_poses, pose_frame_truth
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.sim.hand_poses import CONSUMER_MEMS_ERRORS, hand_turned_record

NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.6, accel_vrw_ug_sqrt_hz=150.0)


def one(seed, poses):
    errs = ImuErrors.random(np.random.default_rng(100 + seed), **CONSUMER_MEMS_ERRORS)
    rec = hand_turned_record(errs, NOISE, n_poses=poses, seed=seed)
    cal = calibrate_poses(rec.imu, lat_rad=rec.lat_rad, h_m=rec.h_m)
    z = (cal.values - pose_frame_truth(errs)) / cal.std
    pt, tt = cal.pose_table, cal.turn_table
    return dict(z=z, names=cal.names,
                acc_rms=np.sqrt(np.mean(pt["norm_minus_g_m_s2"] ** 2)),
                acc_floor=np.sqrt(np.mean(pt["sigma_m_s2"] ** 2)),
                acc_nominal=np.sqrt(np.mean(pt["norm_minus_g_nominal_m_s2"] ** 2)),
                gyro_rms=np.sqrt(np.mean(tt["residual_rad"] ** 2)),
                gyro_floor=np.sqrt(np.mean(2 * tt["sigma_rad"] ** 2)),
                gyro_nominal=np.sqrt(np.mean(tt["residual_nominal_rad"] ** 2)),
                chi2a=cal.accel_chi2, chi2g=cal.gyro_chi2)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", type=int, default=50)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--poses", type=int, default=36)
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    res = []
    for s in range(a.first_seed, a.first_seed + a.sets):
        res.append(one(s, a.poses))
        print(f"set {s}: max |z| {np.abs(res[-1]['z']).max():.2f} ({time.perf_counter() - t0:.0f} s)", flush=True)
    Z = np.array([r["z"] for r in res])
    names = res[0]["names"]
    inside = np.abs(Z) <= 3
    print(f"\n{a.sets} error sets x {Z.shape[1]} parameters = {Z.size} pairs: {100 * inside.mean():.2f}% within "
          f"3 sigma (Gaussian: 99.73%); largest |z| {np.abs(Z).max():.2f}; RMS z {np.sqrt(np.mean(Z ** 2)):.3f}")
    print("| parameter | RMS z | max abs z | within 3 sigma |")
    print("|---|---|---|---|")
    for j, n in enumerate(names):
        print(f"| {n} | {np.sqrt(np.mean(Z[:, j] ** 2)):.2f} | {np.abs(Z[:, j]).max():.2f} | {inside[:, j].mean():.2f} |")
    m = lambda k: np.mean([r[k] for r in res])   # noqa: E731
    print(f"\npose-mean |f| - g, RMS over poses, mean over sets: nominal {m('acc_nominal'):.3g} m/s^2 -> calibrated "
          f"{m('acc_rms'):.3g} m/s^2; noise floor of a pose mean (its samples' noise along gravity) {m('acc_floor'):.3g} m/s^2")
    print(f"gravity-direction residual of the gyro fit, RMS over turns: nominal {np.degrees(m('gyro_nominal')):.3g} deg -> "
          f"{np.degrees(m('gyro_rms')):.3g} deg; noise floor (ARW over the turn and the directions' noise, 2 axes) "
          f"{np.degrees(m('gyro_floor')):.3g} deg")
    ca = np.array([r["chi2a"] for r in res])
    cg = np.array([r["chi2g"] for r in res])
    print(f"chi-square / dof: accelerometers {np.mean(ca[:, 0] / ca[:, 1]):.3f}, gyros {np.mean(cg[:, 0] / cg[:, 1]):.3f}")


if __name__ == "__main__":
    main()
