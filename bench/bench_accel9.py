"""Throughput of the 9-accelerometer batch solve against the memory-bound limit.

    python bench/bench_accel9.py [--n 1000000] [--repeat 7]

Prints, for n samples (9 doubles in; 12 doubles + 1 flag byte out = 169 B/sample):
  * the C batch (gf9_solve through cffi, outputs preallocated),
  * the public API (solve_accel9: validation + output allocation + the same C call),
  * a plain numpy copy moving the same bytes: the input array copied into a
    preallocated buffer plus the output-sized array copied likewise (reads and writes
    at least what the solver reads and writes),
as best-of-repeat wall times, M samples/s, and the ratio solver / copy. One core: the
solver is single-threaded and numpy's copy is too.
"""
from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import gfins_fmi as gf
from gfins_fmi._lib import ffi, lib, ptr


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    n = args.n
    rng = np.random.default_rng(0)
    g = gf.accel9_geometry(0.1)
    # a realistic record: random rates/accelerations through the forward model
    A = gf.forward_model(g, rng.normal(0, 5, (n, 3)), rng.normal(0, 2, (n, 3)),
                         rng.normal(0, 5, (n, 3)))
    outs = [np.empty((n, 3)) for _ in range(4)]
    flags = np.empty(n, dtype=np.uint8)
    for o in outs:  # touch the pages once so that timing excludes first-touch faults
        o.fill(0.0)
    flags.fill(0)
    state = ffi.new("gf9_state *")
    done = ffi.new("size_t *")
    pA, po, pf = ptr(A), [ptr(o) for o in outs], ptr(flags, ctype="uint8_t")

    def c_batch():
        lib.gf9_init(state, 0.1, ffi.NULL)
        status = lib.gf9_solve(state, n, pA, 0.01, *po, pf, done)
        assert status == lib.GF_OK

    def api():
        gf.solve_accel9(A, 0.01, 0.1)

    out_bytes = np.empty(n * 12 * 8 + n, dtype=np.uint8)
    out_dst = np.empty_like(out_bytes)
    in_dst = np.empty_like(A)
    out_bytes.fill(1)
    out_dst.fill(0)
    in_dst.fill(0)

    def copy():
        np.copyto(in_dst, A)
        np.copyto(out_dst, out_bytes)

    t_c, t_api, t_copy = best(c_batch, args.repeat), best(api, args.repeat), best(copy, args.repeat)
    print(f"machine: {cpu_name()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}, "
          f"numpy {np.__version__}")
    print(f"n = {n} samples, best of {args.repeat}")
    for name, t in (("C batch gf9_solve (cffi, preallocated)", t_c),
                    ("public API solve_accel9", t_api),
                    ("numpy copy of the same bytes", t_copy)):
        print(f"  {name:40s} {t * 1e3:8.2f} ms  {n / t / 1e6:8.1f} M samples/s")
    print(f"  ratio C batch / copy: {t_c / t_copy:.2f}x   (goal: >= 20 M samples/s, within 3x of the copy)")


if __name__ == "__main__":
    main()
