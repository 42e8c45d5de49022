"""End to end on a user's own recording (issue 20): a simulated town drive at 200 Hz with
1 Hz RTK GNSS written in KF-GINS's formats with a KF-GINS-style configuration file, then
the whole `gfins integrate --kfgins-config` command (KF-GINS's .nav, IMU error and std
outputs) and `gfins integrate ... OUT.parquet` timed in a child process under
/usr/bin/time -v: wall time, CPU time, peak resident memory, IMU samples per second.

    python bench/bench_own_data.py --minutes 30 [--folder DIR] [--keep]

The machine is shared: say its load with the figures (uptime is printed).
"""
from __future__ import annotations

import argparse
import os
import pathlib
import re
import subprocess
import sys
import tempfile

import numpy as np

from gfins_fmi.io.kfgins import (KFGINS_GNSS_FORMAT, KFGINS_NAV_FORMAT, kfgins_gnss_table, kfgins_imu_table,
                                 kfgins_nav_table)
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.sim.scenarios import NAVIGATION, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver

LEVER = (-0.3, 0.2, 1.2)


def _write_text(path, table, decimals):
    """A text table fast (polars), one space between the numbers."""
    import polars as pl
    pl.DataFrame({f"c{i}": table[:, i] for i in range(table.shape[1])}).write_csv(
        path, include_header=False, separator=" ", float_precision=decimals)


def make(folder: pathlib.Path, minutes: float) -> pathlib.Path:
    rx = GnssReceiver(rate_hz=1.0, lever_arm_m=LEVER, pos_std_m=(0.02, 0.02, 0.04), vel_std_m_s=(0.01, 0.01, 0.02))
    d = simulate_drive(town_drive(minutes * 60.0), minutes * 60.0, 0.005, imu=NAVIGATION, gnss=rx, seed=1)
    _write_text(folder / "imu.txt", kfgins_imu_table(d.imu), 15)
    np.savetxt(folder / "gnss.txt", kfgins_gnss_table(d.gnss), fmt=KFGINS_GNSS_FORMAT)
    tr = d.truth
    k = slice(None, None, 200)   # truth at 1 Hz
    np.savetxt(folder / "truth.nav", kfgins_nav_table(tr.t_s[k], tr.lat_rad[k], tr.lon_rad[k], tr.h_m[k],
                                                      tr.v_n_m_s[k], tr.euler_rad[k]), fmt=KFGINS_NAV_FORMAT)
    ImuRecord(t_s=d.imu.t_s, gyro=d.imu.gyro, accel=d.imu.accel, kind="increments").to_parquet(folder / "imu.parquet") \
        if hasattr(ImuRecord, "to_parquet") else None
    e = [float(x) for x in np.degrees(tr.euler_rad[0])]
    v = [float(x) for x in tr.v_n_m_s[0]]
    N = NAVIGATION
    ug = 9.80665e-6
    vrw = float(N.accel_vrw_ug_sqrt_hz * ug / np.sqrt(2.0) * 60.0)
    ab = float(N.accel_bias_instability_ug * ug / 1e-5)
    (folder / "out").mkdir(exist_ok=True)
    cfg = folder / "kf-gins.yaml"
    cfg.write_text(f"""imupath: "{folder / 'imu.txt'}"
gnsspath: "{folder / 'gnss.txt'}"
outputpath: "{folder / 'out'}"
imudatalen: 7
imudatarate: 200
starttime: {float(d.imu.t_s[0]) - 0.005!r}
endtime: -1
initpos: [ {float(np.degrees(tr.lat_rad[0]))!r}, {float(np.degrees(tr.lon_rad[0]))!r}, {float(tr.h_m[0])!r} ]
initvel: [ {v[1]!r}, {v[0]!r}, {-v[2]!r} ]
initatt: [ {e[2]!r}, {e[1]!r}, {e[0]!r} ]
initgyrbias: [ 0, 0, 0 ]
initaccbias: [ 0, 0, 0 ]
initgyrscale: [ 0, 0, 0 ]
initaccscale: [ 0, 0, 0 ]
initposstd: [ 0.005, 0.004, 0.008 ]
initvelstd: [ 0.003, 0.004, 0.004 ]
initattstd: [ 0.003, 0.003, 0.023 ]
imunoise:
  arw: [{N.gyro_arw_deg_sqrt_h}, {N.gyro_arw_deg_sqrt_h}, {N.gyro_arw_deg_sqrt_h}]
  vrw: [{vrw!r}, {vrw!r}, {vrw!r}]
  gbstd: [{N.gyro_bias_instability_deg_h}, {N.gyro_bias_instability_deg_h}, {N.gyro_bias_instability_deg_h}]
  abstd: [{ab!r}, {ab!r}, {ab!r}]
  gsstd: [300.0, 300.0, 300.0]
  asstd: [300.0, 300.0, 300.0]
  corrtime: {N.gyro_correlation_time_s / 3600.0!r}
antlever: [ {LEVER[1]!r}, {LEVER[0]!r}, {-LEVER[2]!r} ]
""")
    return cfg


def timed(argv: list[str]) -> dict:
    """The command under /usr/bin/time -v: wall s, user + system s, peak RSS MiB."""
    r = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "gfins_fmi.cli", *argv],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{r.stdout}\n{r.stderr}")

    def field(name):
        return re.search(rf"{re.escape(name)}: ([\d.:]+)", r.stderr).group(1)
    wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":")
    wall_s = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall)))
    return {"wall_s": wall_s, "cpu_s": float(field("User time (seconds)")) + float(field("System time (seconds)")),
            "peak_mib": int(field("Maximum resident set size (kbytes)")) / 1024.0, "stdout": r.stdout}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--folder", type=pathlib.Path, default=None)
    args = ap.parse_args()
    folder = args.folder or pathlib.Path(tempfile.mkdtemp(prefix="gfins_own_data_"))
    folder.mkdir(parents=True, exist_ok=True)
    cfg = folder / "kf-gins.yaml"
    if not cfg.exists():
        cfg = make(folder, args.minutes)
    n = sum(1 for _ in open(folder / "imu.txt"))
    print(f"{n} IMU samples ({n / 200 / 60:.1f} min at 200 Hz) in {folder}; load: {os.getloadavg()}")
    runs = {
        "kfgins-config (.nav, IMU error, std text)": ["integrate", "--kfgins-config", str(cfg)],
        "CSV in, Parquet out": ["integrate", str(folder / "imu.txt"), str(folder / "gnss.txt"),
                                str(folder / "sol.parquet"), "--imu-format", "kfgins", "--gnss-format", "kfgins",
                                "--grade", "navigation", "--lever-arm", ",".join(map(str, LEVER)),
                                "--initial", "truth", "--truth", str(folder / "truth.nav")],
        "kfgins-config + --smooth": ["integrate", "--kfgins-config", str(cfg), "--smooth"],
    }
    for name, argv in runs.items():
        t = timed(argv)
        print(f"{name}: wall {t['wall_s']:.2f} s, CPU {t['cpu_s']:.2f} s, peak {t['peak_mib']:.0f} MiB, "
              f"{n / t['cpu_s'] / 1e3:.0f} k samples per CPU second, {n / t['wall_s'] / 1e3:.0f} k per wall second")
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
