"""Integrated navigation of a real recording (shared/data/rtk_walk): a handheld consumer
MEMS IMU (~166 Hz, rates) and a 4 Hz RTK receiver (fix, then float), walking tight turns.

What it does (docs/reproductions/rtk_walk.md):
1. reads the raw files (gfins_fmi.io.load_rtk_walk: g -> m/s^2, sensor -> body axes);
2. weights the GNSS epochs by their RTK quality (float x2, single x5, as the source did);
3. aligns: levelling over the first 9 s at rest; the consumer gyro cannot gyrocompass, so
   the heading comes from the GNSS velocity once above 1 m/s, carried back by the gyros;
4. runs the EKF (rates, zero-velocity updates at standstill) with all GNSS, then with
   simulated 15 s outages, and the RTS smoother;
5. scores the drift during each outage against the RTK positions (no independent truth
   exists), and writes figures.

    python examples/rtk_walk_integration.py [DATA_DIR] [--out docs/figures]
"""
from __future__ import annotations

import argparse
import pathlib

import numpy as np

from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.alignment import align_static_then_gnss
from gfins_fmi.estimation.evaluation import navigation_errors
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.io import load_rtk_walk

HERE = pathlib.Path(__file__).resolve().parent


def default_data_dir() -> pathlib.Path:
    """$GFINS_RTK_WALK_DIR, else the repository's copy (tests/data/rtk_walk), else
    shared/data/rtk_walk beside a parent of this checkout."""
    import os
    env = os.environ.get("GFINS_RTK_WALK_DIR")
    if env:
        return pathlib.Path(env)
    if (HERE.parent / "tests" / "data" / "rtk_walk").is_dir():
        return HERE.parent / "tests" / "data" / "rtk_walk"
    for parent in HERE.parents:
        cand = parent / "shared" / "data" / "rtk_walk"
        if cand.is_dir():
            return cand
    return HERE.parent.parent / "shared" / "data" / "rtk_walk"


DATA = default_data_dir()

#: the source's noise figures (its configuration file): gyro 0.0038 deg/s/sqrt(Hz) =
#: 0.228 deg/sqrt(h); accelerometer 70 ug/sqrt(Hz); bias random walks 3.8e-5 deg/s^2/sqrt(Hz)
#: (= 8.2 deg/h/sqrt(h)) and 7 ug/s/sqrt(Hz)
DATASHEET = ImuNoise(gyro_arw_deg_sqrt_h=0.0038 * 60, accel_vrw_ug_sqrt_hz=70.0,
                     gyro_rrw_deg_h_sqrt_h=3.8e-5 * 3600 * 60, accel_rrw_ug_sqrt_s=7.0,
                     gyro_correlation_time_s=300.0, accel_correlation_time_s=300.0)
#: what the filter uses: the white noises x10. The datasheet describes the sensor at
#: rest; walking with the device in hand adds vibration, hand motion and the source's
#: 10 Hz low-pass, and with the datasheet values the GNSS innovations are ~50x too large
#: (mean NIS 144 for 3 dof, measured); x10 brings the mean NIS to 3.6
IMU = ImuNoise(gyro_arw_deg_sqrt_h=10 * DATASHEET.gyro_arw_deg_sqrt_h,
               accel_vrw_ug_sqrt_hz=10 * DATASHEET.accel_vrw_ug_sqrt_hz,
               gyro_rrw_deg_h_sqrt_h=DATASHEET.gyro_rrw_deg_h_sqrt_h,
               accel_rrw_ug_sqrt_s=DATASHEET.accel_rrw_ug_sqrt_s,
               gyro_correlation_time_s=300.0, accel_correlation_time_s=300.0)
#: RTK position stds below this are raised to it: the receiver reports 1 cm, but the
#: antenna is in a walker's hand (innovations show centimetres)
RTK_STD_FLOOR_M = 0.03


def config(**kw) -> FilterConfig:
    base = dict(imu=IMU, input="rates", propagation_interval_s=0.05,
                # the source: IMU 0.05 m to the right of the antenna (its N, E, D = front, right, down)
                gnss_lever_arm_m=(-0.05, 0.0, 0.0), zupt=True, zupt_std_m_s=0.02,
                standstill_accel_std_m_s2=0.15, standstill_gyro_rad_s=0.03, standstill_window_s=1.0,
                gate_probability=0.9999, max_imu_gap_s=0.1)
    base.update(kw)
    return FilterConfig(**base)


def weighted(gnss, factors={2: 2.0, 5: 5.0}):
    """The record with position/velocity stds floored (RTK_STD_FLOOR_M) and multiplied per
    RTK quality."""
    from gfins_fmi.io import GnssRecord
    k = np.ones(len(gnss.t_s))
    for q, f in factors.items():
        k[gnss.quality == q] = f
    return GnssRecord(t_s=gnss.t_s, lat_rad=gnss.lat_rad, lon_rad=gnss.lon_rad, h_m=gnss.h_m,
                      pos_std_m=np.maximum(gnss.pos_std_m, RTK_STD_FLOOR_M) * k[:, None],
                      vel_enu_m_s=gnss.vel_enu_m_s,
                      vel_std_m_s=gnss.vel_std_m_s * k[:, None], quality=gnss.quality,
                      source=gnss.source + " (std x quality factor)")


def run(data_dir=DATA, outage_s=15.0, outage_starts_s=(25.0, 45.0, 65.0, 85.0, 105.0), filt="ekf"):
    imu, gnss = load_rtk_walk(data_dir)
    gnss = weighted(gnss)
    t0 = imu.t_s[0]
    sp = align_static_then_gnss(imu, gnss, (t0, t0 + 9.0), min_speed_m_s=1.0,
                                gyro_bias_std_rad_s=np.radians(0.1), accel_bias_std_m_s2=0.05)
    cfg = config(filter=filt)
    init = InitialState(sp.nav, position_std_m=(0.05, 0.05, 0.1), velocity_std_m_s=0.05,
                        attitude_std_rad=np.maximum(sp.attitude_std_rad, np.radians([2, 2, 5])),
                        gyro_bias_std_rad_s=np.radians(0.05), accel_bias_std_m_s2=0.05,
                        sensors=sp.sensors)
    sel = imu.t_s > sp.nav.t_s
    from gfins_fmi.io import ImuRecord
    rec = ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind="rates", source=imu.source)
    full = IntegratedNavigator(cfg, init).run(rec, gnss)
    win = np.array([(t0 + s, t0 + s + outage_s) for s in outage_starts_s])
    cut = gnss.with_outages([tuple(w) for w in win])
    sol = IntegratedNavigator(cfg, init).run(rec, cut, smoother=True)
    sm = sol.smooth()
    rows = []
    for name, s in (("filter", sol), ("smoother", sm)):
        e = navigation_errors(s, gnss)       # against every RTK epoch (fix and float)
        for w0, w1 in win:
            inside = (e.t_s >= w0) & (e.t_s < w1)
            hz = e.horizontal_m[inside]
            rows.append((name, w0 - t0, float(hz[-1]), float(np.sqrt(np.mean(hz ** 2))), float(hz.max())))
    return dict(imu=imu, gnss=gnss, start=sp, full=full, outage=sol, smoothed=sm, windows=win, rows=rows, t0=t0)


def figures(r, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    g, t0 = r["gnss"], r["t0"]
    lat0, lon0 = g.lat_rad[0], g.lon_rad[0]
    R = 6378137.0

    def en(lat, lon):
        return (np.asarray(lon) - lon0) * R * np.cos(lat0), (np.asarray(lat) - lat0) * R

    fig, ax = plt.subplots(1, 2, figsize=(11, 5))
    e, n = en(g.lat_rad, g.lon_rad)
    fix = g.quality == 1
    ax[0].plot(e[fix], n[fix], ".", ms=3, color="0.4", label="RTK fix")
    ax[0].plot(e[~fix], n[~fix], ".", ms=3, color="0.75", label="RTK float")
    for key, lab in (("outage", "EKF with 15 s outages"), ("smoothed", "RTS smoother")):
        s = r[key]
        x, y = en(s.lat_rad, s.lon_rad)
        ax[0].plot(x, y, lw=0.8, label=lab)
    for w0, w1 in r["windows"]:
        s = r["outage"]
        m = (s.t_s >= w0) & (s.t_s < w1)
        x, y = en(s.lat_rad[m], s.lon_rad[m])
        ax[0].plot(x, y, color="r", lw=1.6)
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("east (m)")
    ax[0].set_ylabel("north (m)")
    ax[0].legend(fontsize=7)
    ax[0].set_title("rtk_walk: GNSS, filter (red: outages), smoother")
    for key, lab in (("outage", "filter"), ("smoothed", "smoother")):
        er = navigation_errors(r[key], g)
        ax[1].plot(er.t_s - t0, er.horizontal_m, lw=0.8, label=lab)
    for w0, w1 in r["windows"]:
        ax[1].axvspan(w0 - t0, w1 - t0, color="0.9", zorder=0)
    ax[1].set_yscale("log")
    ax[1].set_ylim(bottom=1e-3)
    ax[1].set_xlabel("time (s)")
    ax[1].set_ylabel("horizontal difference to RTK (m)")
    ax[1].legend(fontsize=8)
    ax[1].grid(True, lw=0.3)
    fig.tight_layout()
    p = pathlib.Path(out) / "rtk_walk_integration.png"
    fig.savefig(p, dpi=110)
    return p


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("data", nargs="?", default=str(DATA))
    ap.add_argument("--out", default=None)
    ap.add_argument("--filter", default="ekf")
    a = ap.parse_args(argv)
    r = run(a.data, filt=a.filter)
    for note in r["start"].notes:
        print("alignment:", note)
    e = navigation_errors(r["full"], r["gnss"])
    print(f"all GNSS: horizontal difference to RTK: RMS {e.rms()['horizontal_m']:.3f} m; updates "
          f"{len(r['full'].innovations)}, rejected {len(r['full'].rejected())}, ZUPT "
          f"{len(r['full'].innovations_of('zupt'))}")
    print("15 s outages (drift scored against RTK):")
    print("  who       start   end-of-outage  RMS over outage  max")
    for name, s, end, rms, mx in r["rows"]:
        print(f"  {name:9s} {s:5.0f} s  {end:8.3f} m  {rms:10.3f} m  {mx:8.3f} m")
    for name in ("filter", "smoother"):
        ends = np.array([row[2] for row in r["rows"] if row[0] == name])
        print(f"  {name}: mean drift at outage end {ends.mean():.3f} m, RMS {np.sqrt(np.mean(ends ** 2)):.3f} m")
    if a.out:
        print("figure:", figures(r, a.out))


if __name__ == "__main__":
    main()
