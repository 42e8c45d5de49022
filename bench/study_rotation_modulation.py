"""Rotation modulation (issue 12 item 2): an 8 h run of a 0.01 deg/h-class IMU on a
static base (a moored ship), navigated in the IMU frame with the height held, from the
true initial state, with the IMU fixed and turned by the indexing and continuous schemes
of gfins_fmi.sim.rotation. Three error sets:

  A. constant biases only (gyro 0.01 deg/h, accelerometer 10 ug per axis): what
     rotation removes; the residual is compared with the linear error model (python-
     control, error_models.sins_error_model) driven by the modulated biases C_m^n(t) b;
  B. scale factor (10 ppm) and misalignment (10 arcsec) only: what the turns themselves
     make of them (cancelled by the reversals of the symmetric schemes, not by a
     one-way continuous rotation);
  C. B on a vehicle that turns (10 m/s, a 180 deg turn every 30 min): rotation does not
     remove errors excited by the vehicle's own rates (seed 001's point).

B and C are also run one error block at a time (gyro scale, gyro misalignment,
accelerometer scale and misalignment) to say which error each residual comes from.

    python bench/study_rotation_modulation.py [--hours 8] [--dt 0.02] [--figure docs/figures/rotation_modulation.png]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from gfins_fmi.nav import rotating
from gfins_fmi.sim import rotation as rot
from gfins_fmi.nav.imu_errors import ImuErrors
from gfins_fmi.sim.vehicle import Segment, VehicleProfile

LAT, H = np.radians(40.0), 50.0
R_E = 6371e3


def schemes():
    return {"fixed IMU": rot.RotationSchedule(()),
            "8-position indexing": rot.indexing_scheme(8, dwell_s=10.0, rate_deg_s=10.0),
            "16-position indexing": rot.indexing_scheme(16, dwell_s=10.0, rate_deg_s=10.0),
            "continuous, reversing": rot.continuous_scheme(6.0, 3.0, 120.0, reverse=True),
            "continuous, one way": rot.continuous_scheme(6.0, 3.0, 120.0, reverse=False)}


B_BLOCKS = {
    "gyro scale": dict(gyro_scale_ppm=[10.0, -10.0, 10.0]),
    "gyro misalignment": dict(gyro_misalignment_arcsec=[[0, 0, 0], [-10.0, 0, 0], [10.0, -10.0, 0]]),
    "accelerometer scale + misalignment": dict(
        accel_scale_ppm=[10.0, -10.0, 10.0],
        accel_misalignment_arcsec=[[0, 10.0, -10.0], [-10.0, 0, 10.0], [10.0, -10.0, 0]]),
}
ERRORS = {
    "A": ImuErrors(gyro_bias_deg_h=[0.01, -0.01, 0.01], accel_bias_ug=[10.0, -10.0, 10.0]),
    "B": ImuErrors(**{k: v for b in B_BLOCKS.values() for k, v in b.items()}),
}


def horizontal_error(sol, lat, lon):
    dn = (sol.imu.lat_rad - lat) * R_E
    de = (sol.imu.lon_rad - lon) * R_E * np.cos(lat)
    return np.hypot(dn, de), dn, de


def linear_prediction(rec, errors: ImuErrors, step_s: float = 1.0):
    """North and east errors of the linear model driven by the modulated biases."""
    import control

    from gfins_fmi.analysis.strapdown_errors import sins_error_model
    from gfins_fmi.nav.imu_errors import DEG_H, UG
    sys = sins_error_model(LAT, [1.0, 0.0, 0.0, 0.0], H)     # body = n: inputs in n axes
    m = int(round(step_s / rec.dt_s))
    k = np.arange(m - 1, rec.t_s.size, m)          # t_s[k] = step, 2 step, ...
    q = rec.q_mn[k]
    a, b, c, d = q.T
    C = np.stack([np.stack([a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)], -1),
                  np.stack([2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)], -1),
                  np.stack([2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d], -1)], 1)
    bg = np.asarray(errors.gyro_bias_deg_h) * DEG_H
    ba = np.asarray(errors.accel_bias_ug) * UG
    u = np.c_[C @ bg, C @ ba].T
    t = np.r_[0.0, rec.t_s[k]]
    u = np.c_[u[:, :1], u]
    r = control.forced_response(sys, t, u)
    return t, r.outputs[5], r.outputs[6], u[:3].mean(axis=1) / DEG_H


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=8.0)
    ap.add_argument("--dt", type=float, default=0.02)
    ap.add_argument("--figure", default=None)
    a = ap.parse_args(argv)
    T = 3600.0 * a.hours
    res = {}
    print("| errors | scheme | max horizontal error (m) | at the end (m) | linear model at the end (m) |")
    print("|---|---|---|---|---|")
    for name, sched in schemes().items():
        t0 = time.perf_counter()
        rec = rot.simulate_static(sched, T, a.dt, LAT, H)
        ref, _, _ = horizontal_error(rotating.navigate(rec), LAT, rec.lon_rad)
        for ek in ("A", "B"):
            th, dv = ERRORS[ek].apply_increments(rec.dtheta_rad, rec.dv_m_s, rec.dt_s)
            err, dn, de = horizontal_error(rotating.navigate(rec, th, dv), LAT, rec.lon_rad)
            lin = ""
            if ek == "A":
                tl, ln, le, mb = linear_prediction(rec, ERRORS["A"])
                lin = f"{np.hypot(ln[-1], le[-1]):.4g} (mean C_m^n b_g: {mb[0]:.1e}, {mb[1]:.1e}, {mb[2]:.1e} deg/h)"
                res[name] = {"t": rec.t_s, "err": err, "lin_t": tl, "lin": np.hypot(ln, le)}
            print(f"| {ek} | {name} | {err.max():.4g} | {err[-1]:.4g} | {lin} |", flush=True)
        print(f"|   | {name}: error-free IMU (algorithm) | {ref.max():.3g} | {ref[-1]:.3g} | "
              f"({time.perf_counter() - t0:.0f} s) |", flush=True)
    fixed, idx = res["fixed IMU"]["err"][-1], res["16-position indexing"]["err"][-1]
    print(f"A: 8 h error fixed / 16-position indexing = {fixed / idx:.0f}x")
    # B block by block: which of the errors the schemes leave
    print("| B, one block at a time | scheme | max horizontal error (m) | at the end (m) |")
    print("|---|---|---|---|")
    for name in ("fixed IMU", "8-position indexing", "16-position indexing", "continuous, reversing"):
        rec = rot.simulate_static(schemes()[name], T, a.dt, LAT, H)
        for bk, kw in B_BLOCKS.items():
            th, dv = ImuErrors(**kw).apply_increments(rec.dtheta_rad, rec.dv_m_s, rec.dt_s)
            err, _, _ = horizontal_error(rotating.navigate(rec, th, dv), LAT, rec.lon_rad)
            print(f"| {bk} | {name} | {err.max():.4g} | {err[-1]:.4g} |", flush=True)
    # C: the vehicle turns
    segs = [Segment(60.0, dspeed_m_s=10.0)]
    while sum(s.duration_s for s in segs) < T - 1900.0:
        segs += [Segment(1800.0 - 60.0), Segment(60.0, dheading_rad=np.pi)]
    prof = VehicleProfile(lat0_rad=LAT, h0_m=H, segments=segs)
    print("| C (B on a turning vehicle) | scheme | max horizontal error (m) | at the end (m) | |")
    for name in ("fixed IMU", "16-position indexing"):
        sched = schemes()[name]
        rec = rot.simulate_on_vehicle(sched, prof, T, a.dt)
        v = rec.vehicle

        def err_on_vehicle(errors):
            th, dv = (rec.dtheta_rad, rec.dv_m_s) if errors is None else \
                errors.apply_increments(rec.dtheta_rad, rec.dv_m_s, rec.dt_s)
            sol = rotating.navigate(rec, th, dv)
            return np.hypot((sol.imu.lat_rad - v["lat_rad"]) * R_E,
                            (sol.imu.lon_rad - v["lon_rad"]) * R_E * np.cos(LAT))
        e, e0 = err_on_vehicle(ERRORS["B"]), err_on_vehicle(None)
        print(f"| C | {name} | {e.max():.4g} | {e[-1]:.4g} | error-free {e0.max():.3g} |", flush=True)
        for bk, kw in B_BLOCKS.items():
            e = err_on_vehicle(ImuErrors(**kw))
            print(f"| C, {bk} only | {name} | {e.max():.4g} | {e[-1]:.4g} | |", flush=True)
    if a.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(10, 5), constrained_layout=True)
        for k, (name, r) in enumerate(res.items()):
            ax.semilogy(r["t"] / 3600, r["err"] + 1e-3, f"C{k}", label=name)
            ax.semilogy(r["lin_t"] / 3600, r["lin"] + 1e-3, f"C{k}:", lw=1)
        ax.set(xlabel="time (h)", ylabel="horizontal position error (m)",
               title="constant biases 0.01 deg/h, 10 ug: simulation (solid) and linear model (dotted)")
        ax.legend(fontsize=8)
        fig.savefig(a.figure, dpi=90)


if __name__ == "__main__":
    main()
