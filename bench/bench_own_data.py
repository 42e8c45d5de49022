"""End to end on a user's own recording (issue 20): a simulated town drive at 200 Hz with
1 Hz RTK GNSS written in KF-GINS's formats with a KF-GINS-style configuration file, then
the whole `gfins integrate --kfgins-config` command (KF-GINS's .nav, IMU error and std
outputs) and `gfins integrate ... OUT.parquet` timed in a child process under
/usr/bin/time -v: wall time, CPU time, peak resident memory, IMU samples per second.

    python bench/bench_own_data.py --minutes 30 [--folder DIR]
    python bench/bench_own_data.py --static-hours 10 --folder DIR [--one-core]
    python bench/bench_own_data.py --static-hours 10 --folder /tmp/own10h --out DIR --only smooth

``--static-hours`` also writes the record's KF-GINS binary form (imu.bin) and times the
Parquet-output run from it as well as from the text. Every set has runs with ``--smooth``
(the smoother in chunks: its peak memory, CPU and temporary disk). ``--out DIR``: the
outputs (and the smoother's temporary folder) go there, the record's folder is only read;
``--only TEXT``: the runs whose name holds TEXT. ``--api``: instead, the Python API's
smoothers on the record (IntegratedSolution.smooth() against StreamingSmoother fed
pieces of 48 000 samples), each in a child process under /usr/bin/time -v.
``--our-formats`` (with ``--static-hours``): instead, the record converted to our
ImuRecord CSV and Parquet (in ``--out``) and each timed with the default start (static
alignment) and with ``--initial`` (issue 20: every IMU format and start in chunks):

    python bench/bench_own_data.py --static-hours 10 --folder /tmp/own10h --out DIR --our-formats --one-core

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

from gfins_fmi.cli.kfgins_config import kfgins_config_text, kfgins_noise_block
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
    (folder / "out").mkdir(exist_ok=True)
    cfg = folder / "kf-gins.yaml"
    cfg.write_text(kfgins_config_text(folder / "imu.txt", folder / "gnss.txt", folder / "out",
                                      float(d.imu.t_s[0]) - 0.005, tr.lat_rad[0], tr.lon_rad[0], tr.h_m[0],
                                      tr.v_n_m_s[0], tr.euler_rad[0], LEVER, kfgins_noise_block(NAVIGATION)))
    return cfg


def make_static(folder: pathlib.Path, hours: float) -> pathlib.Path:
    """A long record without a long simulation: a vehicle at rest for ``hours`` (level,
    heading north, 30 deg N), 200 Hz increments of gravity and the Earth rate with
    navigation-grade white noise (seeded), 1 Hz GNSS fixes (2 cm), written a chunk at a
    time. The filter's work per sample does not depend on the motion; what is measured is
    the pipeline's memory and throughput on 7.2 M samples."""
    import polars as pl
    from gfins_fmi.nav.earth import WGS84, gravity
    lat, h, dt = np.radians(30.0), 20.0, 0.005
    g = float(gravity(lat, h))
    w = 7.292115e-5
    n = int(round(hours * 3600 / dt))
    rng = np.random.default_rng(5)
    arw = np.radians(NAVIGATION.gyro_arw_deg_sqrt_h) / 60.0          # rad/sqrt(s)
    vrw = NAVIGATION.accel_vrw_ug_sqrt_hz * 9.80665e-6 / np.sqrt(2.0)  # m/s/sqrt(s)
    with open(folder / "imu.txt", "wb") as f:
        for lo in range(0, n, 1_000_000):
            m = min(n, lo + 1_000_000) - lo
            t = (lo + 1 + np.arange(m)) * dt
            dth = np.tile([w * np.cos(lat) * dt, 0.0, -w * np.sin(lat) * dt], (m, 1)) + rng.normal(0, arw * np.sqrt(dt), (m, 3))
            dv = np.tile([0.0, 0.0, -g * dt], (m, 1)) + rng.normal(0, vrw * np.sqrt(dt), (m, 3))
            pl.DataFrame({"t": t, **{f"g{i}": dth[:, i] for i in range(3)}, **{f"a{i}": dv[:, i] for i in range(3)}}
                         ).write_csv(f, include_header=False, separator=" ", float_precision=15)
    k = int(hours * 3600)
    tg = np.arange(1, k + 1, dtype=float)
    dn, de, du = rng.normal(0, 0.02, (3, k))
    RM = WGS84.a * (1 - WGS84.e2) / (1 - WGS84.e2 * np.sin(lat) ** 2) ** 1.5
    RN = WGS84.a / np.sqrt(1 - WGS84.e2 * np.sin(lat) ** 2)
    gn = np.column_stack([tg, np.degrees(lat + dn / (RM + h)), np.degrees(np.radians(114.0) + de / ((RN + h) * np.cos(lat))),
                          h + du, np.full(k, 0.02), np.full(k, 0.02), np.full(k, 0.04)])
    np.savetxt(folder / "gnss.txt", gn, fmt=KFGINS_GNSS_FORMAT)
    (folder / "out").mkdir(exist_ok=True)
    cfg = folder / "kf-gins.yaml"
    cfg.write_text(kfgins_config_text(folder / "imu.txt", folder / "gnss.txt", folder / "out", 0.0, lat,
                                      np.radians(114.0), h, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                                      kfgins_noise_block(NAVIGATION)))
    return cfg


def write_bin(folder: pathlib.Path) -> pathlib.Path:
    """imu.bin beside imu.txt: KF-GINS's binary IMU form (seven little-endian float64 a
    sample, the text's columns), written from the text a block at a time."""
    from gfins_fmi.io.tables import TableReader
    out = folder / "imu.bin"
    if not out.exists():
        tmp = folder / "imu.bin.part"
        with open(tmp, "wb") as f, TableReader(folder / "imu.txt", chunk_rows=1_000_000, what="KF-GINS IMU",
                                               whitespace=True, block_bytes=4 << 20) as r:
            for _, block in r:
                np.ascontiguousarray(block[:, :7], dtype="<f8").tofile(f)
        tmp.rename(out)
    return out


def _outputs_in(cfg: pathlib.Path, out: pathlib.Path | None) -> pathlib.Path:
    """The KF-GINS configuration with its outputpath in ``out`` (a copy there), or itself."""
    if out is None:
        return cfg
    (out / "out").mkdir(parents=True, exist_ok=True)
    text = re.sub(r'(?m)^outputpath: .*$', f'outputpath: "{out / "out"}"', cfg.read_text())
    copy = out / "kf-gins.yaml"
    copy.write_text(text)
    return copy


def _report(name: str, t: dict, n: int) -> None:
    print(f"{name}: wall {t['wall_s']:.2f} s, CPU {t['cpu_s']:.2f} s, peak {t['peak_mib']:.0f} MiB, "
          f"{n / t['cpu_s'] / 1e3:.0f} k samples per CPU second, {n / t['wall_s'] / 1e3:.0f} k per wall second; "
          f"load {os.getloadavg()[0]:.1f}", flush=True)
    for line in t["stdout"].splitlines():
        if "(smoothed)" in line:
            print("   ", line)


#: the Python API on the record: the whole-record smoother or the streaming one (argv: imu gnss kind)
_API = """
import sys
import numpy as np
from gfins_fmi import io
from gfins_fmi.cli.integrate_stream import time_slice
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator, StreamingSmoother
from gfins_fmi.nav.strapdown import NavState, euler_to_quat
imu = io.read_kfgins_imu(sys.argv[1])
gnss = io.read_kfgins_gnss(sys.argv[2])
from gfins_fmi.sim.scenarios import NAVIGATION
t0 = float(imu.t_s[0]) - 0.005
if sys.argv[4] != "-":       # the drive: its truth's first row, the antenna's lever arm
    tr = io.read_kfgins_nav(sys.argv[4])
    nav0 = NavState(euler_to_quat(tr.euler_rad[0]), tr.v_enu_m_s[0], tr.lat_rad[0], tr.lon_rad[0], tr.h_m[0], t0)
    cfg = FilterConfig(imu=NAVIGATION, gnss_lever_arm_m=(-0.3, 0.2, 1.2))
else:                        # the static record: at rest at 30 N, 114 E, heading north
    nav0 = NavState(euler_to_quat(np.zeros(3)), np.zeros(3), np.radians(30.0), np.radians(114.0), 20.0, t0)
    cfg = FilterConfig(imu=NAVIGATION)
init = InitialState(nav0, position_std_m=5.0, velocity_std_m_s=0.5, attitude_std_rad=(0.03, 0.03, 0.2))
nav = IntegratedNavigator(cfg, init)
if sys.argv[3] == "whole":
    sm = nav.run(imu, gnss, smoother=True, checks="off").smooth()
    print(len(sm), "rows smoothed, whole record")
else:
    n = 0
    with StreamingSmoother(nav) as s:
        lo = nav.t_s
        for a in range(0, len(imu.t_s), 48_000):
            piece = io.ImuRecord(imu.t_s[a:a + 48_000], imu.gyro[a:a + 48_000], imu.accel[a:a + 48_000], imu.kind)
            hi = float(piece.t_s[-1]) + 1e-9
            s.run(piece, time_slice(gnss, lo, hi), checks="off")
            lo = hi
        s.smooth()
        for rows in s.solutions(48_000):
            n += len(rows)
    print(n, "rows smoothed, streaming")
"""


def api_runs(folder: pathlib.Path, n: int) -> None:
    """The two API smoothers in child processes (the IMU record itself is held whole by
    both: 7 float64 a sample)."""
    for kind in ("whole", "streaming"):
        r = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-c", _API, str(folder / "imu.txt"),
                            str(folder / "gnss.txt"), kind,
                            str(folder / "truth.nav") if (folder / "truth.nav").exists() else "-"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit(f"API {kind} failed:\n{r.stdout}\n{r.stderr}")
        peak = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", r.stderr).group(1)) / 1024.0
        cpu = sum(float(re.search(rf"{k} time \(seconds\): ([\d.]+)", r.stderr).group(1)) for k in ("User", "System"))
        print(f"API, {kind}: CPU {cpu:.2f} s, peak {peak:.0f} MiB ({r.stdout.strip()}); load {os.getloadavg()[0]:.1f}",
              flush=True)


def write_ours(folder: pathlib.Path, out: pathlib.Path) -> dict:
    """The record as our ImuRecord table (increments, body right-front-up): CSV text and
    Parquet, in ``out``, converted from the KF-GINS file a chunk at a time (the IMU
    formats `gfins integrate --imu-format csv` reads)."""
    from gfins_fmi.io.imu_stream import ImuChunks
    from gfins_fmi.io.table_writer import TableWriter
    src = folder / "imu.bin" if (folder / "imu.bin").exists() else folder / "imu.txt"
    names = ["t_s"] + [f"gyro_{x}_rad" for x in "xyz"] + [f"accel_{x}_m_s" for x in "xyz"]
    paths = {}
    for fmt in ("csv", "parquet"):
        path = out / f"imu_ours.{fmt}"
        if not path.exists():
            with TableWriter(path, names, comments=["gfins_fmi ImuRecord", f"source: {src.name}"], format=fmt) as w:
                for rec in ImuChunks(src, "kfgins", chunk=1_000_000):
                    w.write([rec.t_s, *rec.gyro.T, *rec.accel.T])
                w.commit()
        paths[fmt] = path
    return paths


def our_runs(folder: pathlib.Path, out: pathlib.Path) -> dict:
    """Our CSV and Parquet IMU records with the default start and with --initial (the
    record at rest at 30 N, 114 E, heading north)."""
    ours = write_ours(folder, out)
    starts = {"default start (static alignment, 5 s)": [], "--initial": ["--initial", "30,114,20,0,0,0"]}
    return {f"our {fmt} IMU in, {suffix} out, {start}": [
                "integrate", str(ours[fmt]), str(folder / "gnss.txt"), str(out / f"sol.{suffix}"), "--gnss-format",
                "kfgins", "--imu-format", "csv", "--grade", "navigation", *starts[start]]
            for fmt, suffix, start in (("csv", "parquet", "default start (static alignment, 5 s)"),
                                       ("csv", "parquet", "--initial"), ("csv", "npz", "--initial"),
                                       ("parquet", "parquet", "default start (static alignment, 5 s)"),
                                       ("parquet", "parquet", "--initial"))}


def timed(argv: list[str], one_core: bool = False) -> dict:
    """The command under /usr/bin/time -v (pinned to CPU 0 with ``one_core``): wall s,
    user + system s, peak RSS MiB."""
    pin = ["taskset", "-c", "0"] if one_core else []
    r = subprocess.run(["/usr/bin/time", "-v", *pin, sys.executable, "-m", "gfins_fmi.cli", *argv],
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
    ap.add_argument("--static-hours", type=float, default=None,
                    help="instead: a record at rest of this many hours (memory and throughput on long records)")
    ap.add_argument("--folder", type=pathlib.Path, default=None)
    ap.add_argument("--one-core", action="store_true", help="pin each command to CPU 0 (taskset -c 0)")
    ap.add_argument("--out", type=pathlib.Path, default=None,
                    help="the outputs go here (default: the record's folder)")
    ap.add_argument("--only", default="", help="the runs whose name holds this text")
    ap.add_argument("--api", action="store_true", help="instead: the Python API's two smoothers")
    ap.add_argument("--our-formats", action="store_true",
                    help="with --static-hours, instead: our ImuRecord CSV and Parquet in (converted into --out), "
                         "with the default start and with --initial")
    args = ap.parse_args()
    folder = args.folder or pathlib.Path(tempfile.mkdtemp(prefix="gfins_own_data_"))
    folder.mkdir(parents=True, exist_ok=True)
    cfg = folder / "kf-gins.yaml"
    if not cfg.exists():
        cfg = make(folder, args.minutes) if args.static_hours is None else make_static(folder, args.static_hours)
    out = args.out or folder
    out.mkdir(parents=True, exist_ok=True)
    kcfg = _outputs_in(cfg, args.out)
    n = sum(1 for _ in open(folder / "imu.txt"))
    if args.api:
        print(f"{n} IMU samples in {folder}; load: {os.getloadavg()}")
        api_runs(folder, n)
        return
    if args.static_hours is not None:
        print(f"{n} IMU samples ({n / 200 / 3600:.2f} h at 200 Hz) in {folder}; load: {os.getloadavg()}")
    if args.static_hours is not None and args.our_formats:
        runs = our_runs(folder, out)
    elif args.static_hours is not None:
        imu_bin = write_bin(folder)
        parquet = [str(folder / "gnss.txt"), str(out / "sol.parquet"), "--imu-format", "kfgins", "--gnss-format",
                   "kfgins", "--grade", "navigation", "--initial", "30,114,20,0,0,0"]
        runs = {"kfgins-config (.nav, IMU error, std text)": ["integrate", "--kfgins-config", str(kcfg)],
                "IMU text in, Parquet out": ["integrate", str(folder / "imu.txt"), *parquet],
                "IMU .bin in, Parquet out": ["integrate", str(imu_bin), *parquet],
                "kfgins-config + --smooth": ["integrate", "--kfgins-config", str(kcfg), "--smooth"],
                "IMU .bin in, Parquet out + --smooth": ["integrate", str(imu_bin), *parquet, "--smooth"]}
    else:
        print(f"{n} IMU samples ({n / 200 / 60:.1f} min at 200 Hz) in {folder}; load: {os.getloadavg()}")
        runs = {
            "kfgins-config (.nav, IMU error, std text)": ["integrate", "--kfgins-config", str(kcfg)],
            "CSV in, Parquet out": ["integrate", str(folder / "imu.txt"), str(folder / "gnss.txt"),
                                    str(out / "sol.parquet"), "--imu-format", "kfgins", "--gnss-format", "kfgins",
                                    "--grade", "navigation", "--lever-arm", ",".join(map(str, LEVER)),
                                    "--initial", "truth", "--truth", str(folder / "truth.nav")],
            "kfgins-config + --smooth": ["integrate", "--kfgins-config", str(kcfg), "--smooth"],
        }
        runs["CSV in, Parquet out + --smooth"] = runs["CSV in, Parquet out"] + ["--smooth"]
    for name, argv in runs.items():
        if args.only in name:
            _report(name, timed(argv, one_core=args.one_core), n)
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
