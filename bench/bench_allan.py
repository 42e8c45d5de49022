"""Overlapping Allan deviation: gfins_fmi.analysis.allan (C sums, streamed) against
allantools' ``oadev`` on the same record and the same tau set, one core.

    python bench/bench_allan.py [--hours 10] [--rate 200] [--axes 6] [--per-decade 10] [--tau-max S]
                                [--repeat 3] [--no-allantools]

Prints the wall time of each (best of --repeat for ours), their ratio, the largest
relative difference of the deviations, and the peak memory each adds (tracemalloc: numpy
allocations) — ours fed from a generator in chunks of 2^18 rows as ``gfins noise`` reads
a file, so the record itself is never held; allantools given the whole (n, 6) array.
Needs ``pip install allantools``. Results: docs/benchmarks.md, "Allan deviation".
"""
from __future__ import annotations

import argparse
import os
import time
import tracemalloc

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from gfins_fmi.analysis.allan import AllanAccumulator, averaging_factors  # noqa: E402

CHUNK = 1 << 18


def chunks(n, axes, seed):
    """White noise plus a slow random walk, 6 axes, generated chunk by chunk."""
    rng = np.random.default_rng(seed)
    walk = np.zeros(axes)
    for start in range(0, n, CHUNK):
        k = min(CHUNK, n - start)
        rw = walk + np.cumsum(rng.normal(0.0, 1e-5, (k, axes)), axis=0)
        walk = rw[-1]
        yield rng.normal(0.0, 1e-3, (k, axes)) + rw + np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 9.8][:axes]


def ours(n, axes, dt, m, seed):
    acc = AllanAccumulator(dt, m, axes)
    for y in chunks(n, axes, seed):
        acc.add(y)
    return acc.result()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=10.0)
    ap.add_argument("--rate", type=float, default=200.0)
    ap.add_argument("--axes", type=int, default=6)
    ap.add_argument("--per-decade", type=int, default=10)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tau-max", type=float, default=None,
                    help="largest tau, s (default a quarter of the record); memory follows it")
    ap.add_argument("--no-allantools", action="store_true")
    a = ap.parse_args(argv)
    dt = 1.0 / a.rate
    n = int(round(a.hours * 3600 * a.rate))
    frac = 0.25 if a.tau_max is None else a.tau_max * a.rate / n
    m = averaging_factors(n, a.per_decade, frac)
    print(f"{a.hours:g} h at {a.rate:g} Hz: {n} samples x {a.axes} axes, {m.size} taus "
          f"({m[0] * dt:g} .. {m[-1] * dt:g} s)")
    best = np.inf
    for r in range(a.repeat):
        # generation timed alone and subtracted: the bench compares the Allan sums
        t0 = time.perf_counter()
        for _ in chunks(n, a.axes, 1):
            pass
        gen = time.perf_counter() - t0
        tracemalloc.start()
        t0 = time.perf_counter()
        res = ours(n, a.axes, dt, m, 1)
        el = time.perf_counter() - t0 - gen
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        best = min(best, el)
        print(f"  ours run {r + 1}: {el:.2f} s (generation {gen:.2f} s subtracted), peak numpy memory "
              f"{peak / 1e6:.0f} MB (the record is {n * a.axes * 8 / 1e6:.0f} MB)")
    if a.no_allantools:
        return
    import allantools
    y = np.concatenate(list(chunks(n, a.axes, 1)))
    tracemalloc.start()
    t0 = time.perf_counter()
    dev = np.empty((m.size, a.axes))
    for c in range(a.axes):
        t, d, _, ns = allantools.oadev(y[:, c], rate=a.rate, data_type="freq", taus=m * dt)
        dev[:, c] = d
    el = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.array_equal(np.round(t / dt), res.m), "the same tau set"
    rel = np.max(np.abs(dev / res.adev - 1.0))
    print(f"  allantools oadev: {el:.2f} s, peak numpy memory {peak / 1e6:.0f} MB beyond the "
          f"record's {y.nbytes / 1e6:.0f} MB")
    print(f"speed ratio (allantools / ours, best of {a.repeat}): {el / best:.1f}; largest relative "
          f"difference of the deviations: {rel:.2e}")


if __name__ == "__main__":
    main()
