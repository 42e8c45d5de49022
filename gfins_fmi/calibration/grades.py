"""Default settings of the system-level calibration by IMU grade (navigation, tactical,
industrial MEMS): the prior of every parameter block, the white noise the filter
assumes, the zero-velocity measurement std; and the grade read from a record's first
static interval when the user names none.

Why grades: a prior is a statement about the IMU. Seed 001's (0.01 deg/h gyro biases)
describes its laser gyros; on a 0.1-0.3 deg/h IMU it pulls weakly observed estimates
towards zero while the reported sigma stays small. The grades' priors are the spread of
*uncalibrated* parameters of that class (what a calibration starts from), wide enough
that the record, not the prior, decides every parameter the path observes; the run then
checks every estimate against its prior (:mod:`gfins_fmi.calibration.diagnostics`).
The white noise is that of :data:`gfins_fmi.sim.scenarios.GRADES` (the project's one set
of grade figures; the consumer grade stands for industrial MEMS).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gfins_fmi.calibration.syscal_filter import Prior, SyscalConfig, core_gravity_m_s2
from gfins_fmi.nav.earth import WGS84
from gfins_fmi.sim.scenarios import GRADES as NOISE_GRADES

__all__ = ["Grade", "GRADES", "grade", "detect_grade", "measured_noise", "config_for_grade"]


@dataclass(frozen=True)
class Grade:
    """Defaults of one IMU grade: ``prior`` (:class:`Prior`), the white noise the filter
    assumes (``gyro_arw_deg_sqrt_h``, ``accel_vrw_ug_sqrt_hz``), ``vel_std_m_s`` (the
    zero-velocity measurement: a turntable's base sway), and the limits
    :func:`detect_grade` compares a static interval with (the largest white noise and the
    largest |bias| lower bound of the class)."""
    name: str
    description: str
    prior: Prior
    gyro_arw_deg_sqrt_h: float
    accel_vrw_ug_sqrt_hz: float
    vel_std_m_s: float
    max_arw_deg_sqrt_h: float
    max_gyro_bias_deg_h: float
    max_accel_bias_ug: float


def _noise(name: str) -> tuple:
    n = NOISE_GRADES[name]
    return n.gyro_arw_deg_sqrt_h, n.accel_vrw_ug_sqrt_hz


#: the grades (``calibrate(grade=...)``, ``gfins calibrate --grade``)
GRADES = {
    "navigation": Grade(
        "navigation", "ring-laser / fibre-optic gyros of 0.001-0.5 deg/h, quartz or silicon "
        "servo accelerometers of 10-1000 ug",
        Prior(attitude_deg=0.5, gyro_scale_ppm=1000.0, gyro_misalignment_arcsec=600.0,
              gyro_bias_deg_h=1.0, accel_scale_ppm=1000.0, accel_misalignment_arcsec=600.0,
              accel_bias_ug=3000.0, accel_k2_ug_g2=300.0, lever_arm_cm=20.0, accel_delay_ms=10.0),
        *_noise("navigation"), vel_std_m_s=1e-5,
        max_arw_deg_sqrt_h=0.02, max_gyro_bias_deg_h=2.0, max_accel_bias_ug=3000.0),
    "tactical": Grade(
        "tactical", "fibre-optic or good MEMS gyros of 0.5-20 deg/h, accelerometers of "
        "0.1-5 mg",
        Prior(attitude_deg=1.0, gyro_scale_ppm=1000.0, gyro_misalignment_arcsec=600.0,
              gyro_bias_deg_h=20.0, accel_scale_ppm=1000.0, accel_misalignment_arcsec=600.0,
              accel_bias_ug=5000.0, accel_k2_ug_g2=300.0, lever_arm_cm=10.0, accel_delay_ms=10.0),
        *_noise("tactical"), vel_std_m_s=1e-5,
        max_arw_deg_sqrt_h=0.3, max_gyro_bias_deg_h=60.0, max_accel_bias_ug=15000.0),
    "mems": Grade(
        "mems", "industrial MEMS: gyros of 20-1000 deg/h, accelerometers of 1-50 mg",
        Prior(attitude_deg=3.0, gyro_scale_ppm=5000.0, gyro_misalignment_arcsec=3600.0,
              gyro_bias_deg_h=500.0, accel_scale_ppm=5000.0, accel_misalignment_arcsec=3600.0,
              accel_bias_ug=30000.0, accel_k2_ug_g2=300.0, lever_arm_cm=10.0, accel_delay_ms=10.0),
        *_noise("consumer"), vel_std_m_s=1e-5,
        max_arw_deg_sqrt_h=np.inf, max_gyro_bias_deg_h=np.inf, max_accel_bias_ug=np.inf),
}


def grade(name: str) -> Grade:
    """The grade of that name (navigation, tactical, mems; ``industrial`` is mems)."""
    key = "mems" if name == "industrial" else name
    if key not in GRADES:
        raise ValueError(f"unknown IMU grade {name!r}; one of {', '.join(GRADES)} (or industrial)")
    return GRADES[key]


def detect_grade(dtheta_rad, dv_m_s, dt_s, lat_rad: float, h_m: float,
                 gravity_m_s2: float | None = None) -> tuple:
    """The finest grade a static interval's samples fit (increments over intervals dt_s):
    the white gyro noise (from the differences of consecutive rates, which cancel any
    constant or slow part: std(diff(w)) / sqrt(2) x sqrt(dt) = ARW), a lower bound of the
    gyro bias (| |mean rate| - Earth rate |: the bias can only add that much to a rate of
    known magnitude) and of the accelerometer bias (| |mean f| - g |); also the white
    accelerometer noise (the same differences). Returns ``(grade, figures)``: the figures
    measured (deg/sqrt(h), ug/sqrt(Hz), deg/h, ug)."""
    dt = np.broadcast_to(np.asarray(dt_s, float), (np.shape(dtheta_rad)[0],))
    w = np.asarray(dtheta_rad) / dt[:, None]
    f = np.asarray(dv_m_s) / dt[:, None]
    many = w.shape[0] > 2
    h = np.sqrt(np.median(dt))
    arw = float(np.max(np.std(np.diff(w, axis=0), axis=0)) / np.sqrt(2.0) * h) if many else 0.0
    arw_deg_sqrt_h = arw * 180.0 / np.pi * 60.0
    # ImuNoise's one-sided ASD A: per-sample std A / sqrt(2 dt), so A = std(diff f) sqrt(dt)
    vrw_ug = float(np.max(np.std(np.diff(f, axis=0), axis=0)) * h / 9.80665e-6) if many else 0.0
    gb = abs(np.linalg.norm(w.mean(axis=0)) - WGS84.omega_ie) * 180.0 / np.pi * 3600.0
    g = core_gravity_m_s2(lat_rad, h_m) if gravity_m_s2 is None else gravity_m_s2
    ab = abs(np.linalg.norm(f.mean(axis=0)) - g) / 9.80665e-6
    figures = {"arw_deg_sqrt_h": arw_deg_sqrt_h, "vrw_ug_sqrt_hz": vrw_ug, "gyro_bias_bound_deg_h": gb,
               "accel_bias_bound_ug": ab}
    for gr in GRADES.values():
        if arw_deg_sqrt_h <= gr.max_arw_deg_sqrt_h and gb <= gr.max_gyro_bias_deg_h and \
                ab <= gr.max_accel_bias_ug:
            return gr, figures
    return GRADES["mems"], figures


def measured_noise(g: Grade, figures: dict) -> dict:
    """The white noise a static interval showed, as SyscalConfig fields, floored at 1% of
    the grade's (a noise-free simulation shows none; the filter keeps some); and a
    zero-velocity std of at most a twentieth of one second's velocity noise (at most the
    grade's): the measurement's R enters the predicted innovation twice (R and the
    velocity's variance after the previous update), so an R near the noise's own share
    makes the NIS read low (10 ug/sqrt(Hz) with 1e-5 m/s: 4%). Give the base's real sway
    (--vel-std) when it moves more."""
    vrw = max(figures["vrw_ug_sqrt_hz"], 0.01 * g.accel_vrw_ug_sqrt_hz)
    sigma_1s = vrw * 9.80665e-6 / np.sqrt(2.0)        # m/s after 1 s of white noise
    return {"gyro_arw_deg_sqrt_h": max(figures["arw_deg_sqrt_h"], 0.01 * g.gyro_arw_deg_sqrt_h),
            "accel_vrw_ug_sqrt_hz": vrw, "vel_std_m_s": max(min(g.vel_std_m_s, 0.05 * sigma_1s), 1e-7)}


def config_for_grade(g: Grade, **changes) -> SyscalConfig:
    """The filter settings of a grade (the full model with the delay), with ``changes``
    to any :class:`SyscalConfig` field."""
    base = SyscalConfig(vel_std_m_s=g.vel_std_m_s, gyro_arw_deg_sqrt_h=g.gyro_arw_deg_sqrt_h,
                        accel_vrw_ug_sqrt_hz=g.accel_vrw_ug_sqrt_hz, prior=g.prior)
    return dataclasses.replace(base, **changes)
