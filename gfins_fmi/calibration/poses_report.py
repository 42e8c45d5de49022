"""What a calibration at unknown poses says: the parameters with their 1-sigma in
datasheet units, the residual tables (per pose, per turn), the figure.
"""
from __future__ import annotations

import numpy as np

from gfins_fmi.calibration.poses import PoseCalibration
from gfins_fmi.nav.imu_errors import ARCSEC, DEG_H, PPM, UG

__all__ = ["parameter_table", "UNITS", "plot_pose_calibration", "pose_rows", "turn_rows"]

#: name prefix -> (unit, factor from SI)
UNITS = {"accel_scale": ("ppm", 1 / PPM), "accel_mis": ("arcsec", 1 / ARCSEC), "accel_bias": ("ug", 1 / UG),
         "accel_k2": ("ug/g^2", 9.80665 / 1e-6), "gyro_scale": ("ppm", 1 / PPM),
         "gyro_mis": ("arcsec", 1 / ARCSEC), "gyro_bias": ("deg/h", 1 / DEG_H)}
_FRIENDLY = {"accel_scale": ("%", 100.0), "accel_mis": ("deg", 180 / np.pi), "accel_bias": ("m/s^2", 1.0),
             "accel_k2": ("s^2/m", 1.0), "gyro_scale": ("%", 100.0), "gyro_mis": ("deg", 180 / np.pi),
             "gyro_bias": ("deg/s", 180 / np.pi)}


def _prefix(name: str) -> str:
    return name.rsplit("_", 1)[0]


def parameter_table(cal: PoseCalibration) -> str:
    """Every parameter, its 1-sigma, in ImuErrors' units and in everyday ones (markdown)."""
    lines = ["| parameter | estimate | 1-sigma | unit | estimate | unit |", "|---|---|---|---|---|---|"]
    for n, v, s in zip(cal.names, cal.values, cal.std):
        u, f = UNITS[_prefix(n)]
        u2, f2 = _FRIENDLY[_prefix(n)]
        lines.append(f"| {n} | {v * f:.6g} | {s * f:.3g} | {u} | {v * f2:.5g} | {u2} |")
    return "\n".join(lines)


def pose_rows(cal: PoseCalibration):
    """(names, columns) of the per-pose residual table."""
    p = cal.pose_table
    names = ["t0_s", "t1_s", "accel_x_m_s2", "accel_y_m_s2", "accel_z_m_s2", "norm_minus_g_nominal_m_s2",
             "norm_minus_g_m_s2", "sigma_m_s2"]
    cols = [p["t0_s"], p["t1_s"], *p["accel_mean_m_s2"].T, p["norm_minus_g_nominal_m_s2"],
            p["norm_minus_g_m_s2"], p["sigma_m_s2"]]
    return names, cols


def turn_rows(cal: PoseCalibration):
    """(names, columns) of the per-turn residual table (angles in degrees)."""
    t = cal.turn_table
    d = 180 / np.pi
    names = ["t0_s", "t1_s", "angle_deg", "residual_nominal_deg", "residual_deg", "sigma_deg"]
    cols = [t["t0_s"], t["t1_s"], t["angle_rad"] * d, t["residual_nominal_rad"] * d, t["residual_rad"] * d,
            t["sigma_rad"] * d]
    return names, cols


def plot_pose_calibration(cal: PoseCalibration, imu, path, title: str = ""):
    """Three panels: the still detector along the record (accelerometer variance against
    its threshold, the poses shaded); |f| - g per pose before and after with the noise of
    a pose mean; the gravity-direction residual per turn before and after with its noise."""
    import matplotlib   # lazy: matplotlib only when a figure is asked for
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    st = cal.still
    t = imu.t_s
    fig, ax = plt.subplots(3, 1, figsize=(10, 10))
    ax[0].semilogy(t, np.maximum(st.accel_stat, 1e-12), lw=0.5, label="accelerometer variance over the window")
    ax[0].axhline(st.accel_threshold, color="k", ls="--", lw=0.7, label="threshold")
    for s, e in st.ranges:
        ax[0].axvspan(t[s], t[e - 1], color="C2", alpha=0.2, lw=0)
    ax[0].set_xlabel("t, s")
    ax[0].set_ylabel("m^2/s^4")
    ax[0].set_title(f"{len(st.ranges)} still poses (shaded)", fontsize=9)
    ax[0].legend(fontsize=8)
    p = cal.pose_table
    k = np.arange(len(p["t0_s"]))
    ax[1].semilogy(k, np.abs(p["norm_minus_g_nominal_m_s2"]), "o", ms=3, label="nominal conversion")
    ax[1].semilogy(k, np.abs(p["norm_minus_g_m_s2"]), "o", ms=3, label="calibrated")
    ax[1].semilogy(k, p["sigma_m_s2"], "k_", ms=8, label="noise of the pose mean (1 sigma)")
    ax[1].set_xlabel("pose")
    ax[1].set_ylabel("| |f| - g |, m/s^2")
    ax[1].legend(fontsize=8)
    tt = cal.turn_table
    j = np.arange(len(tt["t0_s"]))
    d = 180 / np.pi
    ax[2].semilogy(j, tt["residual_nominal_rad"] * d, "o", ms=3, label="rates less the initial mean")
    ax[2].semilogy(j, tt["residual_rad"] * d, "o", ms=3, label="calibrated")
    ax[2].semilogy(j, np.sqrt(2) * tt["sigma_rad"] * d, "k_", ms=8, label="noise (1 sigma, both axes)")
    ax[2].set_xlabel("turn")
    ax[2].set_ylabel("gravity direction residual, deg")
    ax[2].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
