"""Throughput of the gyro-free navigator: array outputs -> (w, f) -> strapdown solution.

    python bench/bench_gfnav.py [--n 1000000] [--repeat 5]

A noisy record of the Qin et al. scenario (fixed frame with gravity) is navigated by
GyroFreeNavigator (one C call) for each layout / rate strategy; best of --repeat.
"""
from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import gfins_fmi as gf
from gfins_fmi.experiments import qin as R
from gfins_fmi.gyrofree.array import forward_model


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    sc = R.QinScenario(duration_s=(args.n - 1) * 0.01, radius_m=10.0, rho_rad_s2=1e-5)
    tr = R.qin_truth(sc)
    n = tr["t"].size
    x0 = gf.NavState(tr["q"][0], tr["vel"][0], 0.0, 0.0, 0.0, 0.0, tr["pos"][0])
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo")
                if line.startswith("model name")), platform.processor())
    print(f"machine: {cpu}, {os.cpu_count()} logical CPUs; n = {n} samples, best of {args.repeat}")
    rng = np.random.default_rng(0)
    for lay, strategy in (("cube6", "integrate"), ("qin9", "sqrt"), ("qin9", "fused"),
                          ("12", "eigen")):
        g = gf.layout(lay, 0.1)
        A = forward_model(g, tr["f"], tr["w"], np.zeros_like(tr["w"]))
        A += rng.normal(0, 1.4e-5, A.shape)
        best = np.inf
        for _ in range(args.repeat):
            nav = gf.GyroFreeNavigator(g, x0, strategy, tr["w"][0], accel_noise_m_s2=1.4e-5,
                                       sins=gf.SinsConfig(earth="flat", flat_gravity_m_s2=9.8))
            t0 = time.perf_counter()
            nav.run(A, 0.01)
            best = min(best, time.perf_counter() - t0)
        print(f"  {lay:6s} {strategy:10s} {best * 1e3:8.1f} ms  {n / best / 1e6:6.2f} M samples/s"
              "   (goal >= 3 M samples/s)")


if __name__ == "__main__":
    main()
