"""Characterise a consumer MEMS IMU without a turntable (docs/characterise_imu.md): the
worked example of that page, on simulated records so that the truth is known.

    python examples/characterise_imu.py [--out docs/figures/characterise_imu] [--hours 3]

1. A hand-turned record (36 poses at random orientations, 5-10 s still, 1-3 s turns,
   100 Hz) of an IMU with consumer-MEMS errors -> ``gfins calibrate poses`` -> cal.toml.
2. A static record (``--hours`` at 50 Hz) of the same IMU's noise -> ``gfins noise`` ->
   noise.toml.
3. A 10-minute drive with that IMU, 1 Hz GNSS and a 60 s outage -> ``gfins integrate``
   raw, and with ``--imu-errors cal.toml --noise-file noise.toml``: the drift in the
   outage against the truth.
Prints what each step finds against the truth; writes the figures to ``--out``.
"""
from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

from gfins_fmi.calibration.poses import pose_frame_truth
from gfins_fmi.calibration.poses_report import UNITS
from gfins_fmi.estimation.noise_file import read_imu_errors, read_noise_file
from gfins_fmi.io import ImuRecord
from gfins_fmi.nav.imu_errors import ImuErrors, ImuNoise
from gfins_fmi.nav.strapdown import quat_to_euler
from gfins_fmi.sim.hand_poses import CONSUMER_MEMS_ERRORS, hand_turned_record
from gfins_fmi.sim.scenarios import simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver

#: the IMU's random errors (a consumer MEMS: white noise, Gauss-Markov biases, a slow walk)
NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.6, gyro_bias_instability_deg_h=15.0, gyro_correlation_time_s=100.0,
                 gyro_rrw_deg_h_sqrt_h=20.0, accel_vrw_ug_sqrt_hz=150.0, accel_bias_instability_ug=300.0,
                 accel_correlation_time_s=100.0, accel_rrw_ug_sqrt_s=2.0)


def gfins(*args) -> str:
    exe = pathlib.Path(sys.executable).with_name("gfins")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "gfins_fmi.cli"]
    p = subprocess.run(cmd + [str(a) for a in args], capture_output=True, text=True)
    if p.returncode not in (0, 1):
        raise SystemExit(f"gfins {' '.join(map(str, args))} failed:\n{p.stderr}")
    return p.stdout


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/characterise_imu"))
    ap.add_argument("--hours", type=float, default=3.0)
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(tempfile.mkdtemp(prefix="characterise_imu_"))
    errs = ImuErrors.random(np.random.default_rng(2026), **CONSUMER_MEMS_ERRORS)
    # 1. calibration at unknown poses (white noise only during the few minutes of turning)
    rec = hand_turned_record(errs, ImuNoise(gyro_arw_deg_sqrt_h=NOISE.gyro_arw_deg_sqrt_h,
                                            accel_vrw_ug_sqrt_hz=NOISE.accel_vrw_ug_sqrt_hz),
                             n_poses=36, seed=2026, lat_rad=np.radians(48.0), h_m=300.0)
    rec.imu.to_csv(work / "hand.csv")
    out = gfins("calibrate", "poses", work / "hand.csv", "--lat", 48, "--height", 300, "--output",
                work / "cal.toml", "--plot", a.out, "--table", work / "res")
    print("\n".join(line for line in out.splitlines() if line.startswith("- ")))
    cal = read_imu_errors(work / "cal.toml")
    truth = pose_frame_truth(errs)
    est = np.r_[cal.accel_scale_ppm, [cal.accel_misalignment_arcsec[i, j] for i, j in ((1, 0), (2, 0), (2, 1))],
                cal.accel_bias_ug, cal.gyro_scale_ppm,
                [cal.gyro_misalignment_arcsec[i, j] for i, j in ((0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1))],
                cal.gyro_bias_deg_h]
    names = ["accel_scale"] * 3 + ["accel_mis"] * 3 + ["accel_bias"] * 3 + ["gyro_scale"] * 3 + \
        ["gyro_mis"] * 6 + ["gyro_bias"] * 3
    tr_units = np.array([t * UNITS[n][1] for t, n in zip(truth, names)])
    print("| quantity | largest true value | largest error after calibration |")
    print("|---|---|---|")
    for pref in ("accel_scale", "accel_mis", "accel_bias", "gyro_scale", "gyro_mis", "gyro_bias"):
        sel = [i for i, n in enumerate(names) if n == pref]
        print(f"| {pref} ({UNITS[pref][0]}) | {np.abs(tr_units[sel]).max():.4g} | "
              f"{np.abs(est[sel] - tr_units[sel]).max():.3g} |")
    # 2. noise identification on a static record
    dt = 0.02
    n = int(a.hours * 3600 / dt)
    g, acc = NOISE.sample(n, dt, np.random.default_rng(7))
    t = np.arange(1, n + 1) * dt
    ImuRecord(t, g * dt, (acc + [0.0, 0.0, 9.81]) * dt, "increments", "static").to_csv(work / "static.csv")
    out = gfins("noise", work / "static.csv", "--output", work / "noise.toml", "--plot", a.out)
    print(out)
    model = read_noise_file(work / "noise.toml")
    # 3. a drive with that IMU: raw, and with the calibration and the identified noise
    T = 600.0
    rx = GnssReceiver(rate_hz=1.0, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1),
                      outages_s=((400.0, 460.0),))
    d = simulate_drive(town_drive(T), T, 0.01, imu=NOISE, gnss=rx, seed=3)
    tr = d.truth
    # the IMU's deterministic errors on top (mean rates over each interval)
    gy, ac = errs.apply_increments(d.imu.gyro, d.imu.accel, 0.01)
    ImuRecord(d.imu.t_s, gy, ac, "increments").to_csv(work / "drive_imu.csv")
    d.gnss.to_csv(work / "drive_gnss.csv")
    e = [float(x) for x in np.degrees(quat_to_euler(tr.q_bn[0]))]
    p0 = [float(np.degrees(tr.lat_rad[0])), float(np.degrees(tr.lon_rad[0])), float(tr.h_m[0])]
    base = ["integrate", work / "drive_imu.csv", work / "drive_gnss.csv", work / "out.csv", "--imu-format", "csv",
            "--gnss-format", "csv", f"--initial={p0[0]!r},{p0[1]!r},{p0[2]!r},{e[0]!r},{e[1]!r},{e[2]!r}"]
    for label, extra in (("raw record, --grade consumer", ["--grade", "consumer"]),
                         ("calibrated, identified noise", ["--imu-errors", work / "cal.toml", "--noise-file",
                                                           work / "noise.toml"])):
        gfins(*base, *extra)
        sol = np.loadtxt(work / "out.csv", delimiter=",", skiprows=1)
        k = np.searchsorted(sol[:, 0], 459.9)
        j = np.searchsorted(tr.t_s, sol[k, 0])
        from gfins_fmi.nav.earth import radii
        RM, RN, _, _ = radii(tr.lat_rad[j])
        dn = (np.radians(sol[k, 1]) - tr.lat_rad[j]) * RM
        de = (np.radians(sol[k, 2]) - tr.lon_rad[j]) * RN * np.cos(tr.lat_rad[j])
        print(f"{label}: horizontal error at the end of the 60 s GNSS outage {np.hypot(dn, de):.1f} m")
    print(f"identified noise model: {model}")
    print(f"work files: {work}")


if __name__ == "__main__":
    main()
