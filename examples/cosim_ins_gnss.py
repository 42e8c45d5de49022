"""Vehicle + integrated navigator co-simulation: the vehicle FMU drives seed 001's run
(60 s at rest, a start to 15 m/s, 180 deg turns at 300-330 s and 540-570 s; 600 s at
100 Hz) with a tactical-grade IMU and its aiding sensors — a GNSS receiver at 1 Hz, 0.37 s
off the IMU grid, 0.1 s latency, out from 300 s to 360 s; a barometer with a 2 m bias; an
odometer with a 0.5 % scale error — and feeds the integrated-navigator FMU (EKF with
barometer-bias and odometer-scale states, NHC) through the Python master on fmpy's slave
classes (integrated_example() has the whole set-up).

Prints the comparison with the batch API (IntegratedNavigator.run on the increments and
epochs the FMU received, each epoch with the sample it arrived with) and the navigation
errors against the vehicle's truth, and writes docs/figures/cosim_ins_gnss.png (errors with
the filter's +-3 sigma, the outage shaded).

    python examples/cosim_ins_gnss.py [--seconds 600] [--fmi 3] [--out docs/figures/cosim_ins_gnss.png]
"""
from __future__ import annotations

import argparse
import pathlib
import time
import types

import numpy as np

from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.reference import direct_navigation, integrated_recording
from gfins_fmi.fmi.system import integrated_example, vehicle_integrated_navigation
from gfins_fmi.estimation.evaluation import navigation_errors, plot_errors
from gfins_fmi.sim.vehicle import VehicleProfile


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=600.0)
    ap.add_argument("--fmi", type=int, choices=[2, 3], default=3)
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/figures/cosim_ins_gnss.png"))
    args = ap.parse_args()
    options = integrated_example()
    system = vehicle_integrated_navigation(VehicleProfile.seed001(align_s=60.0),
                                                 stop_s=args.seconds, **options)
    t0 = time.perf_counter()
    with CoSimulation(system, fmi_version=args.fmi) as m:
        m.initialize()
        r = m.run(progress=True)
    wall = time.perf_counter() - t0
    steps = len(r["time"]) - 1
    print(f"co-simulation, FMI {args.fmi}.0, {args.seconds:g} s at {1 / system.step_s:g} Hz: "
          f"{wall:.1f} s ({1e6 * wall / steps:.0f} us a step)")

    # the batch API on what the FMU received
    rec = integrated_recording(system, r)
    sol = rec["solution"]
    t0 = time.perf_counter()
    ref = direct_navigation(system, rec)
    batch_wall = time.perf_counter() - t0
    fields = ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors")
    same = all(np.array_equal(getattr(sol, f), getattr(ref, f)) for f in fields) and all(
        np.array_equal(sol.innovations[f], ref.innovations[f], equal_nan=True)
        for f in ("t_s", "type", "status", "nis"))
    plain = direct_navigation(system, rec, initial=system.sources["initial"])
    print(f"batch API ({batch_wall:.2f} s), P0 as the FMU makes it: "
          f"{'bit for bit equal' if same else 'DIFFERENT'} ({len(sol)} rows, "
          f"{len(sol.innovations)} updates); with InitialState's own P0: max |dh| "
          f"{np.max(np.abs(plain.h_m - sol.h_m)):.2g} m, |dv| "
          f"{np.max(np.abs(plain.v_n_m_s - sol.v_n_m_s)):.2g} m/s, |dq| "
          f"{np.max(np.abs(plain.q_bn - sol.q_bn)):.2g}")
    g = rec["gnss"]
    inn = sol.innovations
    print(f"epochs received: GNSS {len(g.t_s)} (each {np.median(rec['t_s'][rec['gnss_sample']] - g.t_s):.2f} s "
          f"after its time of validity), barometer {len(rec['baro'].t_s)}, odometer "
          f"{len(rec['odometer'].t_s)}; updates accepted {np.sum(inn['status'] == 0)}, "
          f"gated {np.sum(inn['status'] == 1)}, stale {np.sum(inn['status'] == 3)}")

    # errors against the vehicle's truth: the navigator's row j took the vehicle's row j - 1
    rows = slice(int(np.flatnonzero(r["navigator.n_imu"][:, 0] == 1)[0]) - 1, None)
    truth = types.SimpleNamespace(
        t_s=sol.t_s, lat_rad=r["vehicle.lat"][rows, 0][:len(sol)],
        lon_rad=r["vehicle.lon"][rows, 0][:len(sol)], h_m=r["vehicle.h"][rows, 0][:len(sol)],
        v_n_m_s=r["vehicle.v"][rows][:len(sol)], q_bn=r["vehicle.q"][rows][:len(sol)])
    e = navigation_errors(sol, truth)
    err = np.c_[e.vel_enu_m_s, e.pos_enu_m, e.att_rad]
    z = np.abs(err) / sol.std
    outages = np.array(options["gnss"].outages_s, float)
    t = sol.t_s
    print("| interval | max horizontal error (m) | max velocity error (m/s) | max attitude error (deg) "
          "| share of errors within 3 sigma |")
    print("|---|---|---|---|---|")
    spans = [(t[0], outages[0, 0]), tuple(outages[0]), (outages[0, 1], t[-1] + 1e-9), (t[0], t[-1] + 1e-9)]
    for a, b in spans:
        sel = (t >= a) & (t < b)
        if not np.any(sel):
            continue
        print(f"| {a:.0f}-{min(b, t[-1]):.0f} s{' (GNSS out)' if (a, b) == tuple(outages[0]) else ''} | "
              f"{e.horizontal_m[sel].max():.3g} | {np.linalg.norm(e.vel_enu_m_s[sel], axis=1).max():.3g} | "
              f"{np.degrees(np.linalg.norm(e.att_rad[sel], axis=1).max()):.3g} | "
              f"{100 * np.mean(z[sel] < 3):.1f}% |")
    print(f"sensor estimates at the end: barometer bias {sol.sensors[-1, 12]:.3f} m (2 m + a random "
          f"walk), odometer scale {sol.sensors[-1, 13]:.5f} (0.005)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    plot_errors(e, args.out, std=sol.std, windows=outages[outages[:, 0] < t[-1]],
                title=f"vehicle FMU -> integrated navigator FMU (fmpy, FMI {args.fmi}.0): "
                      "errors, ±3σ dashed, GNSS outage grey")
    print(f"figure: {args.out}")


if __name__ == "__main__":
    main()
