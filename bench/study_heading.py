"""UKF where it matters (issue 11): the filter started with a 30 deg heading error (and a
30 deg heading sigma) on a moving vehicle, tactical IMU, 1 Hz GNSS position + velocity.
For each seed: the time after which the heading stays within 1 sigma of the EKF started
with the true heading (sigma 1 deg) on the same data -- it has reached that filter's
accuracy -- for the UKF and for the EKF.

    python bench/study_heading.py [--seeds 20] [--seconds 300] [--out docs/figures]
"""
from __future__ import annotations

import argparse

import numpy as np

from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.evaluation import navigation_errors
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.nav.strapdown import NavState
from gfins_fmi.nav.earth import quat_multiply
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle


def rotated(nav: NavState, heading_err_rad: float) -> NavState:
    """The same state with the heading increased by heading_err (a rotation about up by
    -heading_err: heading is clockwise)."""
    a = -heading_err_rad
    q = np.array([np.cos(a / 2), 0.0, 0.0, np.sin(a / 2)])
    return NavState(quat_multiply(q, nav.q_bn), nav.v_n_m_s.copy(), nav.lat_rad, nav.lon_rad, nav.h_m, nav.t_s)


def settle_time(t, err, bound):
    """First time after which |err| <= bound for good (NaN if never)."""
    bad = np.flatnonzero(np.abs(err) > bound)
    if bad.size == 0:
        return t[0]
    return np.nan if bad[-1] == len(t) - 1 else t[bad[-1] + 1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--seconds", type=float, default=300.0)
    ap.add_argument("--error-deg", type=float, default=30.0)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    T = a.seconds
    profile = town_drive(T, speed0_m_s=10.0)        # moving from the start
    truth = simulate_vehicle(profile, T, 0.01)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.5, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1))
    err0 = np.radians(a.error_deg)
    rows = []
    curves = {}
    for seed in range(a.seeds):
        d = simulate_drive(profile, T, 0.01, imu=TACTICAL, gnss=rx, seed=seed, truth=truth)
        res = {}
        for name, filt, e0, sd in (("ekf_true", "ekf", 0.0, np.radians(1.0)), ("ekf", "ekf", err0, err0),
                                   ("ukf", "ukf", err0, err0)):
            cfg = FilterConfig(imu=TACTICAL, filter=filt, gate_probability=None)
            init = InitialState(rotated(d.initial, e0), position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                                attitude_std_rad=(0.005, 0.005, sd))
            sol = IntegratedNavigator(cfg, init).run(d.imu, d.gnss)
            er = navigation_errors(sol, d.truth)
            res[name] = (sol.t_s, er.heading_rad, sol.std[:, 8])
        t, h_true, sd_true = res["ekf_true"]
        # same data: the difference to the true-heading EKF against that filter's sigma
        ts = {k: settle_time(t, (res[k][1] - h_true + np.pi) % (2 * np.pi) - np.pi, sd_true)
              for k in ("ukf", "ekf")}
        rows.append((ts["ukf"], ts["ekf"], abs(res["ukf"][1][-1]), abs(res["ekf"][1][-1]),
                     abs(res["ekf_true"][1][-1])))
        if seed == 0:
            curves = res
        print(f"seed {seed}: within 1 sigma of the true-heading EKF after: UKF {ts['ukf']:.1f} s, "
              f"EKF {ts['ekf']:.1f} s; final |heading error| UKF {np.degrees(rows[-1][2]):.3f} deg, "
              f"EKF {np.degrees(rows[-1][3]):.3f} deg, true-heading EKF {np.degrees(rows[-1][4]):.3f} deg")
    r = np.array(rows)
    print(f"UKF settled within 120 s in {np.sum(r[:, 0] <= 120)}/{len(r)} seeds (median {np.nanmedian(r[:, 0]):.1f} s, "
          f"max {np.nanmax(r[:, 0]):.1f} s); EKF within 120 s in {np.sum(r[:, 1] <= 120)}/{len(r)} "
          f"(median {np.nanmedian(r[:, 1]):.1f} s)")
    if a.out:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
        t = curves["ekf_true"][0] - curves["ekf_true"][0][0]
        for k, lab in (("ekf_true", "EKF, true heading"), ("ekf", f"EKF, {a.error_deg:g} deg error"),
                       ("ukf", f"UKF, {a.error_deg:g} deg error")):
            ax[0].plot(t, np.degrees(curves[k][1]), lw=0.8, label=lab)
            ax[1].semilogy(t, np.maximum(np.abs(np.degrees(curves[k][1])), 1e-4), lw=0.8, label=lab)
        ax[1].semilogy(t, np.degrees(curves["ekf_true"][2]), "k--", lw=0.6, label="1 sigma, true-heading EKF")
        ax[0].set_ylabel("heading error (deg)")
        ax[1].set_ylabel("|heading error| (deg)")
        ax[1].set_xlabel("time after start of motion (s)")
        ax[0].legend(fontsize=8)
        ax[1].legend(fontsize=8)
        for x in ax:
            x.grid(True, lw=0.3)
        fig.tight_layout()
        p = f"{a.out}/heading_{a.error_deg:g}deg_ukf_ekf.png"
        fig.savefig(p, dpi=110)
        print("figure:", p)


if __name__ == "__main__":
    main()
