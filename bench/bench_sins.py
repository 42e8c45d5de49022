"""Throughput and accuracy of the strapdown mechanization, against pyins.

    python bench/bench_sins.py [--n 1000000] [--repeat 5]

A closed-form sine-velocity motion (gfins_fmi.sim.trajectory.SineVelocity, horizontal only,
100 Hz) gives exact increments; both navigators hold the height (the free vertical
channel diverges as e^(t/570 s) and would dominate any record longer than an hour). The same increments are navigated by
  * gfins_fmi: gf_sins_run through cffi (one C call; best of --repeat), and through the
    public API Strapdown.run;
  * pyins (PyPI package ``python-ins``, imported as ``pyins``; benchmark only, not a
    dependency): compute_increments_from_imu (its coning/sculling) + Integrator.integrate
    (numba), after a warm-up run so that JIT compilation is not timed.
Frames: pyins uses NED and body front-right-down; the record is converted (x_frd =
y_rfu, y_frd = x_rfu, z_frd = -z_rfu). Accuracy: maximum horizontal position error and
attitude error against the truth, for both.
"""
from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.nav import earth
from gfins_fmi._lib import ffi, lib, ptr


def best(fn, repeat):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def horizontal(lat, lon, tlat, tlon):
    R = 6371000.0
    return float(np.max(np.hypot((lat - tlat) * R, (lon - tlon) * R * np.cos(tlat))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    dt = 0.01
    t0 = time.perf_counter()
    tr = tj.sample(tj.SineVelocity(amplitude_m_s=(2.0, 3.0, 0.0)), args.n * dt, dt)
    print(f"truth: {args.n} increments ({args.n * dt:.0f} s at 100 Hz) generated in "
          f"{time.perf_counter() - t0:.1f} s")
    n = tr.dtheta_rad.shape[0]
    x0 = gf.NavState.from_trajectory(tr, 0)

    # --- gfins_fmi: raw C batch with preallocated outputs
    q = np.empty((n, 4)); v = np.empty((n, 3)); pos = np.empty((n, 3)); tt = np.empty(n)
    for a in (q, v, pos, tt):
        a.fill(0.0)
    cfg = gf.SinsConfig(vertical="hold", hold_height_m=float(tr.h_m[0]))
    state = ffi.new("gf_sins_state *")
    done = ffi.new("size_t *")
    q0, v0 = np.ascontiguousarray(x0.q_bn), np.ascontiguousarray(x0.v_n_m_s)
    pg, pa = ptr(tr.dtheta_rad), ptr(tr.dv_m_s)

    def c_run():
        lib.gf_sins_init(state, cfg._c(), ptr(q0), ptr(v0), x0.lat_rad, x0.lon_rad, x0.h_m, 0.0)
        st = lib.gf_sins_run(state, n, pg, pa, dt, ffi.NULL, ffi.NULL, 0, ptr(q), ptr(v), ptr(pos),
                             ptr(tt), done)
        assert st == lib.GF_OK

    def api_run():
        return gf.Strapdown(x0, cfg).run(tr.dtheta_rad, tr.dv_m_s, dt_s=dt)

    t_c = best(c_run, args.repeat)
    t_api = best(api_run, args.repeat)
    sol = api_run()
    err_g = horizontal(sol.lat_rad, sol.lon_rad, tr.lat_rad[1:], tr.lon_rad[1:])
    qe = sol.q_bn
    att_g = _att_err_deg(qe, tr.q_bn[1:])

    print(f"machine: {_cpu()}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}")
    print(f"gfins_fmi C batch (cffi, preallocated): {t_c * 1e3:8.1f} ms  {n / t_c / 1e6:6.2f} M samples/s")
    print(f"gfins_fmi Strapdown.run (public API):   {t_api * 1e3:8.1f} ms  {n / t_api / 1e6:6.2f} M samples/s")
    print(f"  accuracy: max horizontal error {err_g:.4g} m, max attitude error {att_g:.3g} deg")

    # --- pyins
    try:
        import pandas as pd
        import pyins
        from pyins.strapdown import Integrator, compute_increments_from_imu
    except ImportError:
        print("pyins not installed (pip install python-ins): comparison skipped")
        return

    def to_frd(x):
        return np.c_[x[:, 1], x[:, 0], -x[:, 2]]

    g_frd = np.r_[np.zeros((1, 3)), to_frd(tr.dtheta_rad)]
    a_frd = np.r_[np.zeros((1, 3)), to_frd(tr.dv_m_s)]
    imu = pd.DataFrame(np.c_[g_frd, a_frd], index=pd.Index(tr.t_s, name="time"),
                       columns=["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"])
    e0 = gf.quat_to_euler(x0.q_bn)
    pva = pd.Series({"lat": np.degrees(x0.lat_rad), "lon": np.degrees(x0.lon_rad), "alt": x0.h_m,
                     "VN": x0.v_n_m_s[1], "VE": x0.v_n_m_s[0], "VD": -x0.v_n_m_s[2],
                     "roll": np.degrees(e0[2]), "pitch": np.degrees(e0[1]),
                     "heading": np.degrees(e0[0])})

    def pyins_run():
        inc = compute_increments_from_imu(imu, "increment")
        return Integrator(pva, with_altitude=False).integrate(inc)

    Integrator(pva, with_altitude=False).integrate(
        compute_increments_from_imu(imu.iloc[:100], "increment"))  # JIT warm-up
    t_p = best(pyins_run, max(1, min(args.repeat, 3)))
    traj = pyins_run()
    lat = np.radians(traj["lat"].values[1:])
    lon = np.radians(traj["lon"].values[1:])
    err_p = horizontal(lat, lon, tr.lat_rad[1:], tr.lon_rad[1:])
    qp = earth.euler_to_quat(np.radians(traj["heading"].values[1:]), np.radians(traj["pitch"].values[1:]),
                          np.radians(traj["roll"].values[1:]))
    att_p = _att_err_deg(qp, tr.q_bn[1:])
    print(f"pyins {getattr(pyins, '__version__', '?')} (numba):              {t_p * 1e3:8.1f} ms  "
          f"{n / t_p / 1e6:6.2f} M samples/s")
    print(f"  accuracy: max horizontal error {err_p:.4g} m, max attitude error {att_p:.3g} deg")
    print(f"speed ratio gfins_fmi C batch / pyins: {t_p / t_c:.1f}x; public API / pyins: {t_p / t_api:.1f}x"
          "   (goal >= 20x at equal or better accuracy; >= 10 M samples/s)")


def _att_err_deg(qe, qt):
    w = np.sum(qe * qt, axis=1)
    v = qt[:, :1] * qe[:, 1:] - qe[:, :1] * qt[:, 1:] - np.cross(qe[:, 1:], qt[:, 1:])
    return float(np.degrees(np.max(2 * np.arctan2(np.linalg.norm(v, axis=1), np.abs(w)))))


def _cpu():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


if __name__ == "__main__":
    main()
