"""Navigation with IMU errors on the vehicle run of seed 001 (10 min at rest, 15 m/s,
two 180 deg turns): uncompensated, compensated with the calibrated parameters, and
compensated with the true ones. Writes the table of docs/imu_errors.md and its figure.

    python examples/imu_error_navigation.py [--out docs/figures/imu_errors_vehicle.png]
"""
from __future__ import annotations

import argparse
import pathlib

import numpy as np

import gfins_fmi as gf
from gfins_fmi.calibration import laboratory as cal
from gfins_fmi.sim import trajectory as tj

# seed 001's IMU class: 0.01 deg/h gyros, 10 ug-class accelerometers; errors that a
# rotating INS does not modulate away: scale, misalignment, K2, inner lever arms
ERRORS = dict(gyro_bias_deg_h=[0.01, -0.01, 0.008], gyro_scale_ppm=[20.0, -15.0, 10.0],
              gyro_misalignment_arcsec=[[0, 10, -8], [12, 0, 9], [-10, 7, 0]],
              accel_bias_ug=[50.0, -40.0, 30.0], accel_scale_ppm=[100.0, -80.0, 60.0],
              accel_misalignment_arcsec=[[0, 10, -12], [8, 0, 10], [-9, 11, 0]],
              accel_k2_ug_g2=[20.0, -20.0, 15.0], lever_arm_cm=[3.0, -2.5, 2.0])


def run(duration_s: float = 1320.0, dt_s: float = 0.01, seed: int = 1):
    truth = tj.sample(tj.VehicleRun(), duration_s, dt_s)
    errors = gf.ImuErrors(**ERRORS)
    w_out, f_out = errors.apply(truth.gyro_rad_s, truth.accel_m_s2)
    rng = np.random.default_rng(seed)
    calibrated = cal.calibrate(cal.simulate(errors, cal.test_plan(), rng)).errors
    x0 = gf.NavState.from_trajectory(truth, 0)
    cfg = gf.SinsConfig(input="rates", vertical="hold", hold_height_m=float(truth.h_m[0]))
    cases = {"uncompensated": (w_out, f_out),
             "compensated, calibrated parameters": calibrated.compensate(w_out, f_out),
             "compensated, true parameters": errors.compensate(w_out, f_out),
             "error-free sensors (reference)": (truth.gyro_rad_s, truth.accel_m_s2)}
    R = 6371000.0
    out = {}
    for name, (w, f) in cases.items():
        sol = gf.Strapdown(x0, cfg).run(w, f, dt_s=dt_s)
        pos = np.hypot((sol.lat_rad - truth.lat_rad) * R,
                       (sol.lon_rad - truth.lon_rad) * R * np.cos(truth.lat_rad))
        vel = np.linalg.norm(sol.v_n_m_s[:, :2] - truth.v_n_m_s[:, :2], axis=1)
        out[name] = dict(t=sol.t_s, pos=pos, vel=vel)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/imu_errors_vehicle.png"))
    args = ap.parse_args()
    res = run()
    print("| sensors | max horizontal position error (m) | final (m) | max horizontal velocity error (m/s) |")
    print("|---|---|---|---|")
    for name, r in res.items():
        print(f"| {name} | {r['pos'].max():.4g} | {r['pos'][-1]:.4g} | {r['vel'].max():.4g} |")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
    for name, r in res.items():
        ax[0].semilogy(r["t"] / 60, r["pos"] + 1e-6, label=name)
        ax[1].semilogy(r["t"] / 60, r["vel"] + 1e-9, label=name)
    ax[0].set(xlabel="time (min)", ylabel="horizontal position error (m)",
              title="Vehicle run of seed 001 (turns at 14 and 18 min)")
    ax[1].set(xlabel="time (min)", ylabel="horizontal velocity error (m/s)")
    for a in ax:
        a.legend(fontsize=8)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=100)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
