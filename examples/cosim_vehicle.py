"""Vehicle + navigator co-simulation: the vehicle FMU drives seed 001's run (60 s at
rest, a start to 15 m/s, two 180 deg turns; 600 s at 100 Hz) and feeds a navigator FMU
through the Python master on fmpy's slave classes (FMI 3.0). Four cases:

* strapdown INS (SINS FMU) with exact IMU outputs;
* strapdown INS, the vehicle's IMU carrying seed 001's error class, uncompensated;
* the same errors compensated inside the SINS FMU (its imu_comp parameters);
* compensated, plus the random errors of a navigation-grade IMU drawn inside the vehicle
  FMU (angle random walk 0.003 deg/sqrt(h), 10 ug/sqrt(Hz), 0.005 deg/h bias instability);
* gyro-free 9-accelerometer navigator (qin9, sqrt strategy) with exact array outputs.

Prints the navigation errors and writes docs/figures/cosim_vehicle.png; checks each
co-simulated solution against the navigator called through cffi on the same sensor
data (bit-identical).

    python examples/cosim_vehicle.py [--seconds 600] [--out docs/figures/cosim_vehicle.png]
"""
from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np

import gfins_fmi as gf
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.reference import differences_from_direct
from gfins_fmi.fmi.system import vehicle_navigation
from gfins_fmi.fmi import reference
from gfins_fmi.sim.vehicle import VehicleProfile

# seed 001's IMU class (0.01 deg/h gyros, 10 ug-class accelerometers), as in
# examples/imu_error_navigation.py
NOISE = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.003, gyro_bias_instability_deg_h=0.005,
                    gyro_correlation_time_s=300.0, accel_vrw_ug_sqrt_hz=10.0)
ERRORS = gf.ImuErrors(gyro_bias_deg_h=[0.01, -0.01, 0.008], gyro_scale_ppm=[20.0, -15.0, 10.0],
                      gyro_misalignment_arcsec=[[0, 10, -8], [12, 0, 9], [-10, 7, 0]],
                      accel_bias_ug=[50.0, -40.0, 30.0], accel_scale_ppm=[100.0, -80.0, 60.0],
                      accel_misalignment_arcsec=[[0, 10, -12], [8, 0, 10], [-9, 11, 0]],
                      accel_k2_ug_g2=[20.0, -20.0, 15.0], lever_arm_cm=[3.0, -2.5, 2.0])


def cases(seconds: float):
    prof = VehicleProfile.seed001(align_s=60.0)
    comp = dict(imu_comp=1, **ERRORS.fmu_parameters())
    return {
        "SINS, exact IMU": vehicle_navigation("sins", prof, stop_s=seconds),
        "SINS, IMU errors uncompensated": vehicle_navigation("sins", prof, stop_s=seconds,
                                                                   imu_errors=ERRORS),
        "SINS, IMU errors compensated in the FMU": vehicle_navigation(
            "sins", prof, stop_s=seconds, imu_errors=ERRORS, navigator_parameters=comp),
        "SINS, errors compensated + IMU noise": vehicle_navigation(
            "sins", prof, stop_s=seconds, imu_errors=ERRORS, navigator_parameters=comp,
            imu_noise=NOISE),
        "gyro-free qin9 (sqrt), exact array": vehicle_navigation("gfnav_qin9", prof,
                                                                       stop_s=seconds),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=600.0)
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/cosim_vehicle.png"))
    args = ap.parse_args()
    results = {}
    print("| case | max horizontal position error (m) | final (m) | max velocity error (m/s) "
          "| max attitude error (deg) | = cffi | wall time (s) |")
    print("|---|---|---|---|---|---|---|")
    for name, system in cases(args.seconds).items():
        t0 = time.perf_counter()
        with CoSimulation(system, fmi_version=3) as m:
            m.initialize()
            r = m.run(progress=False)
        wall = time.perf_counter() - t0
        e = reference.navigation_errors(r)
        results[name] = e
        # the recorded sensor data through the navigator called by cffi: bit-identical?
        same = max(differences_from_direct(system, r, imu_errors=ERRORS).values()) == 0.0
        print(f"| {name} | {e['horizontal_m'].max():.4g} | {e['horizontal_m'][-1]:.4g} | "
              f"{e['velocity_m_s'].max():.4g} | {np.degrees(e['attitude_rad'].max()):.3g} | "
              f"{'yes' if same else 'NO'} | {wall:.1f} |")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4), constrained_layout=True)
    for name, e in results.items():
        style = dict(ls="--", lw=2.5) if "compensated in" in name else dict(lw=1.2)
        ax[0].semilogy(e["t_s"], np.maximum(e["horizontal_m"], 1e-9), label=name, **style)
        ax[1].semilogy(e["t_s"], np.maximum(e["velocity_m_s"], 1e-12), label=name, **style)
    ax[0].set(xlabel="time (s)", ylabel="horizontal position error (m)",
              title="vehicle FMU -> navigator FMU (fmpy, FMI 3.0)")
    ax[1].set(xlabel="time (s)", ylabel="horizontal velocity error (m/s)",
              title="seed 001 run: rest 60 s, 15 m/s, turns (shaded)")
    for a in ax:
        a.grid(True, which="both", alpha=0.3)
        for t_turn in (300.0, 540.0):   # 60 s rest + 240 s / 480 s, 30 s each
            a.axvspan(t_turn, t_turn + 30.0, color="0.85", lw=0)
    ax[0].legend(fontsize=8)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
