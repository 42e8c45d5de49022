"""Record I/O of the record commands: a 10^7-row record through ``gfins navigate``,
``solve9`` and ``gfnav``, end to end (read, solve, write), in CSV, npz and Parquet.

    python bench/bench_record_io.py [--rows 10000000] [--dir /tmp/gfins_bench_io]
                                    [--commands navigate,solve9,gfnav] [--formats csv,npz,parquet]
                                    [--one-core] [--keep]

The records are generated once into --dir (never into the repository): at rest at 1 kHz
(t from 1000 s, times rounded to microseconds), full-precision noise on every value
(the worst case for text: 17 significant digits):
  * strapdown: t, gyro increments (Earth rate at 30 deg N + 1e-7 rad noise), accel
    increments (g dt + 1e-5 m/s noise); navigate with the height held (a free vertical
    channel diverges over 10^4 s);
  * array: t, the 9 outputs of the qin9 layout (l = 0.1 m) at rest plus 1e-6 m/s^2
    noise, read by solve9 and by gfnav (height held).
Each run is a separate process under /usr/bin/time -v: user and system CPU time, wall
time and peak resident memory, with the load average before and after (the machine is
shared: CPU time is the figure that does not depend on the other jobs). --one-core pins
the process to CPU 0 (taskset) and limits polars to one thread. The C work alone is
timed in-process on the same record (chunks from the npz file, CPU time of the solver
calls only).
"""
from __future__ import annotations

import argparse
import os
import pathlib
import platform
import re
import shutil
import subprocess
import sys
import time

import numpy as np

HZ = 1000.0
LAT_DEG, LON_DEG = 30.0, 114.0
EARTH_RATE_RAD_S = 7.292115e-5
#: body rate at rest, level, heading north, at 30 deg N (rad/s): the omega_init of the array
W_REST = (0.0, float(EARTH_RATE_RAD_S * np.cos(np.radians(LAT_DEG))),
          float(EARTH_RATE_RAD_S * np.sin(np.radians(LAT_DEG))))


def generate(kind: str, path: pathlib.Path, n: int, chunk: int = 1 << 20) -> None:
    """Write the strapdown ("nav") or array ("arr") record of ``n`` rows to ``path``."""
    from gfins_fmi import layout
    from gfins_fmi.gyrofree.array import forward_model
    from gfins_fmi.io.table_writer import TableWriter
    rng = np.random.default_rng(2026)
    dt = 1.0 / HZ
    if kind == "nav":
        names = ["t_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad", "dv_x_m_s", "dv_y_m_s",
                 "dv_z_m_s"]
    else:
        names = ["t_s"] + [f"A{i}_m_s2" for i in range(1, 10)]
        g = layout("qin9", 0.1)
    with TableWriter(path, names) as w:
        for lo in range(0, n, chunk):
            m = min(n, lo + chunk) - lo
            t = np.round(1000.0 + (lo + np.arange(m)) * dt, 6)
            if kind == "nav":
                gyro = np.array(W_REST) * dt + rng.normal(0.0, 1e-7, (m, 3))
                accel = np.array([0.0, 0.0, 9.7936]) * dt + rng.normal(0.0, 1e-5, (m, 3))
                cols = [gyro[:, j] for j in range(3)] + [accel[:, j] for j in range(3)]
            else:
                A = forward_model(g, np.tile([0.0, 0.0, 9.7936], (m, 1)), np.tile(W_REST, (m, 1)),
                                  np.zeros((m, 3))) + rng.normal(0.0, 1e-6, (m, 9))
                cols = [A[:, j] for j in range(9)]
            w.write([t] + cols)
        w.commit()


def command(name: str, src: pathlib.Path, dst: pathlib.Path) -> list[str]:
    w0 = "--omega-init=" + ",".join(repr(x) for x in W_REST)
    nav = ["--lat0", str(LAT_DEG), "--lon0", str(LON_DEG), "--vertical", "hold"]
    args = {"navigate": ["navigate", str(src), str(dst), *nav],
            "solve9": ["solve9", str(src), str(dst), "--lever-arm", "0.1", w0],
            "gfnav": ["gfnav", str(src), str(dst), "--layout", "qin9", "--lever-arm", "0.1", w0,
                      *nav]}[name]
    header = ["--header"] if src.suffix == ".csv" else []     # the generator names the columns
    return [sys.executable, "-m", "gfins_fmi.cli", *args, *header, "--no-progress"]


def timed(argv: list[str], one_core: bool) -> dict:
    env = dict(os.environ)
    if one_core:
        env["POLARS_MAX_THREADS"] = "1"
        argv = ["taskset", "-c", "0", *argv]
    load0 = os.getloadavg()[0]
    proc = subprocess.run(["/usr/bin/time", "-v", *argv], capture_output=True, text=True, env=env)
    load1 = os.getloadavg()[0]
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed:\n{proc.stdout}\n{proc.stderr}")

    def field(label):
        return re.search(rf"{re.escape(label)}: (.+)", proc.stderr).group(1)
    h_m_s = [float(x) for x in field("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":")]
    wall = sum(x * 60 ** k for k, x in enumerate(reversed(h_m_s)))
    return {"user_s": float(field("User time (seconds)")), "sys_s": float(field("System time (seconds)")),
            "wall_s": wall, "rss_mb": int(field("Maximum resident set size (kbytes)")) / 1024,
            "load": (load0, load1)}


def c_work(name: str, src: pathlib.Path) -> float:
    """CPU seconds of the solver calls alone on the record (chunks read from ``src``)."""
    import gfins_fmi as gf
    from gfins_fmi.io.tables import TableReader
    deg = np.pi / 180
    spent = 0.0
    solver = None
    for start, block in TableReader(src, chunk_rows=1 << 18):
        if solver is None:        # at rest, level, heading north; increments start a step early
            t0 = block[0, 0] - (block[1, 0] - block[0, 0]) if name == "navigate" else block[0, 0]
            x0 = gf.NavState.from_euler([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], LAT_DEG * deg,
                                        LON_DEG * deg, 0.0, t0)
            hold = gf.SinsConfig(vertical="hold")
            if name == "navigate":
                solver = gf.Strapdown(x0, hold)
            elif name == "solve9":
                solver = gf.Accel9Solver(0.1, W_REST)
            else:
                solver = gf.GyroFreeNavigator(gf.layout("qin9", 0.1), x0, "integrate", W_REST,
                                              sins=hold)
        c0 = time.process_time()
        if name == "navigate":
            solver.run(block[:, 1:4], block[:, 4:7], t_s=block[:, 0])
        elif name == "solve9":
            solver.solve(block[:, 1:], 1.0 / HZ)
        else:
            solver.run(block[:, 1:], 1.0 / HZ)
        spent += time.process_time() - c0
    return spent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--dir", type=pathlib.Path, default=pathlib.Path("/tmp/gfins_bench_io"))
    ap.add_argument("--commands", default="navigate,solve9,gfnav")
    ap.add_argument("--formats", default="csv,npz,parquet")
    ap.add_argument("--one-core", action="store_true", help="taskset -c 0, one polars thread")
    ap.add_argument("--keep", action="store_true", help="keep the outputs")
    args = ap.parse_args()
    args.dir.mkdir(parents=True, exist_ok=True)
    import polars
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} logical CPUs; "
          f"Python {platform.python_version()}, numpy {np.__version__}, polars {polars.__version__}")
    formats = args.formats.split(",")
    rows = []
    for name in args.commands.split(","):
        kind = "nav" if name == "navigate" else "arr"
        for fmt in formats:
            src = args.dir / f"{kind}_{args.rows}.{fmt}"
            if not src.exists():
                t0 = time.perf_counter()
                generate(kind, src, args.rows)
                print(f"generated {src} ({src.stat().st_size / 2**20:.0f} MiB) in "
                      f"{time.perf_counter() - t0:.0f} s")
            dst = args.dir / f"out_{name}.{fmt}"
            r = timed(command(name, src, dst), args.one_core)
            r.update(command=name, fmt=fmt, in_mib=src.stat().st_size / 2**20,
                     out_mib=dst.stat().st_size / 2**20)
            rows.append(r)
            print(f"{name:8s} {fmt:7s} cpu {r['user_s'] + r['sys_s']:6.1f} s (user {r['user_s']:.1f}, "
                  f"sys {r['sys_s']:.1f}), wall {r['wall_s']:6.1f} s, peak {r['rss_mb']:5.0f} MiB, "
                  f"in {r['in_mib']:.0f} MiB, out {r['out_mib']:.0f} MiB, load {r['load'][0]:.1f} -> "
                  f"{r['load'][1]:.1f}", flush=True)
            if not args.keep:
                dst.unlink()
        npz = args.dir / f"{kind}_{args.rows}.npz"
        if npz.exists():
            print(f"{name:8s} C work alone: {c_work(name, npz):.1f} s CPU")
    print("\n| command | format | CPU (user + sys) | wall | peak memory | in / out | load |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['command']} | {r['fmt']} | {r['user_s'] + r['sys_s']:.1f} s ({r['user_s']:.1f} + "
              f"{r['sys_s']:.1f}) | {r['wall_s']:.1f} s | {r['rss_mb']:.0f} MiB | "
              f"{r['in_mib']:.0f} / {r['out_mib']:.0f} MiB | {r['load'][0]:.1f} -> {r['load'][1]:.1f} |")
    if shutil.which("taskset") is None and args.one_core:
        print("(taskset not found: --one-core did not pin)")


if __name__ == "__main__":
    main()
