"""Every parameter of the FMUs other than the integrated navigator (SINS, the three
gyro-free navigators, the 9-accelerometer solver, the vehicle), enumerated from each model
description and seen: every parameter (every used element of a vector) takes a value
different from every other, and each one alone is perturbed: the outputs must change.

A parameter read into another's place leaves its own value unread, which this finds; the
FMU = cffi comparisons with distinct (random) values find two swapped ones
(tests/fmi/test_fmu.py: SINS with random ImuErrors and a low-pass, the gyro-free
navigators, the 9-accelerometer solver; tests/fmi/test_cosim.py: the vehicle with random
ImuErrors, array biases, noise and aiding sensors). What a run cannot see is listed with
the reason. The integrated navigator: tests/fmi/test_fmu_parameters.py.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description

import gfins_fmi as gf


def _nav_record(n=150, dt=0.01):
    """Exact rates, increments and a 9-accelerometer array of the drive of
    tests/support/drives.py, n samples from t = 5 s (moving, turning)."""
    from support.drives import drive
    tr, _ = drive(8.0, fine=dt, step=1)
    k0 = int(round(5.0 / dt))
    sl = slice(k0, k0 + n)
    geo = gf.accel9_geometry(0.11)
    A = gf.forward_model(geo, tr.accel_m_s2[sl], tr.gyro_rad_s[sl], tr.gyro_dot_rad_s2[sl])
    return tr, sl, A


def _perturbed(base: dict, skip=(), fixed=(), negate=(), whole=()):
    """(label, parameters) with one float element changed (x 1.1; a zero: a tenth of the
    largest element's size; the parameters in negate: the sign), for every
    element of every parameter not in skip (integers: + 1) whose label is not fixed."""
    for name, value in base.items():
        if name in skip:
            continue
        arr = np.atleast_1d(np.asarray(value, dtype=float))
        if name in whole:      # every element at once
            yield f"{name}[:]", {**base, name: (arr * 1.1).tolist()}
            continue
        for i in range(arr.size):
            if (f"{name}[{i}]" if np.ndim(value) else name) in fixed:
                continue
            new = arr.copy()
            scale = np.abs(arr).max() or 1e-3      # a zero: a tenth of its neighbours'
            new[i] = (new[i] + 1 if isinstance(value, int) else -new[i] if name in negate
                      else new[i] * 1.1 if new[i] != 0 else 0.1 * scale)
            v = int(new[0]) if isinstance(value, int) else (new.tolist() if np.ndim(value) else float(new[0]))
            yield (f"{name}[{i}]" if np.ndim(value) else name), {**base, name: v}


def _run(model, inputs, outputs, params, dt=0.01):
    from gfins_fmi.fmi.runner import run_fmu
    return run_fmu(model, inputs, outputs, dt, parameters=params, fmi_version=3)


def _check_every_parameter(model, inputs, outputs, base, inert, switches=(), alike=(), fixed=(),
                           negate=(), whole=()):
    """alike: parameters whose elements have equal values by their nature (a filter's
    symmetric numerator), left out of the distinctness check only; fixed: elements that
    must keep their value (a zero the FMU requires), not perturbed."""
    md = read_model_description(str(gf.fmu_path(model, 3)))
    params = {v.name for v in md.modelVariables if v.causality == "parameter"}
    assert params == set(base), (params - set(base), set(base) - params)
    where = {}
    for name, v in base.items():
        if name in switches or name in alike or isinstance(v, int):
            continue
        for i, x in enumerate(np.ravel(v)):
            if x != 0.0:        # zeros: unused elements, or a zero the FMU requires
                where.setdefault(float(x), []).append(f"{name}[{i}]")
    shared = {x: names for x, names in where.items() if len(names) > 1}
    assert not shared, f"parameters share a value: {shared}"
    ref = _run(model, inputs, outputs, base)
    seen_inert = []
    for label, params in _perturbed(base, skip=switches, fixed=fixed, negate=negate, whole=whole):
        out = _run(model, inputs, outputs, params)
        if all(np.array_equal(out[k], ref[k], equal_nan=True) for k in outputs):
            seen_inert.append(label)
    assert sorted(seen_inert) == sorted(inert), seen_inert


@pytest.mark.parametrize("vertical_mode", [1, 2], ids=["held", "baro"])
def test_sins_fmu_sees_every_parameter(vertical_mode):
    """SINS FMU with compensation, a low-pass and the vertical channel held (hold_height)
    or damped by the barometer (baro_tau)."""
    tr, sl, _ = _nav_record()
    rng = np.random.default_rng(25)
    e = gf.ImuErrors.random(rng, gyro_bias_deg_h=10, gyro_scale_ppm=1000, gyro_misalignment_arcsec=100,
                            accel_bias_ug=1000, accel_scale_ppm=1000, accel_misalignment_arcsec=100,
                            accel_k2_ug_g2=50, lever_arm_cm=3)
    from gfins_fmi.nav import signal_conditioning
    sos = signal_conditioning.design_cheby2(20.0, 100.0, order=4)
    q0 = gf.euler_to_quat(gf.quat_to_euler(tr.q_bn[sl][0]) + np.array([1e-3, 2e-3, -3e-3]))
    base = dict(input_mode=1, coning=1, vertical_mode=vertical_mode, hold_height=123.4, baro_tau=7.3,
                max_rate=43.0, max_specific_force=910.0, q0=q0.tolist(),
                v0=(tr.v_n_m_s[sl][0] + [0.011, -0.013, 0.017]).tolist(), lat0=float(tr.lat_rad[sl][0]),
                lon0=float(tr.lon_rad[sl][0]), h0=float(tr.h_m[sl][0]) + 0.37, skip_steps=0,
                imu_comp=1, **e.fmu_parameters(), lowpass_sections=2,
                lowpass_sos=np.r_[sos.ravel(), np.zeros(48 - sos.size)].tolist(), rotating=0)
    inputs = {"gyro_rate": tr.gyro_rad_s[sl], "specific_force": tr.accel_m_s2[sl],
              "dtheta": np.zeros((150, 3)), "dv": np.zeros((150, 3)),
              "h_ext": tr.h_m[sl] + 0.5, "gimbal": np.zeros((150, 2))}
    inert = ([{1: "baro_tau", 2: "hold_height"}[vertical_mode],       # the other mode's
              "max_rate", "max_specific_force"]                          # limits
             + [f"lowpass_sos[{i}]" for i in range(sos.size, 48)]        # sections past 2
             + (["h0", "v0[2]"] if vertical_mode == 1 else []))          # held: hold_height, 0
    # the misalignment matrices' diagonals must be zero (refused otherwise), the sections'
    # a0 one (gf_biquad_init refuses others)
    fixed = ([f"{s}_misalign[{i}]" for s in ("gyro", "accel") for i in (0, 4, 8)]
             + [f"lowpass_sos[{6 * k + 3}]" for k in range(len(sos))])
    _check_every_parameter("sins", inputs, ["q", "v", "lat", "lon", "h", "q_vehicle"], base,
                           inert, switches=("input_mode", "coning", "vertical_mode", "imu_comp",
                                            "lowpass_sections", "rotating", "skip_steps"),
                           alike=("lowpass_sos",), fixed=fixed)   # b0 = b2, a0 = 1 per section


@pytest.mark.parametrize("model, vertical_mode", [("gfnav_qin9", 1), ("gfnav_qin9", 2),
                                                  ("gfnav_cube6", 2), ("gfnav_12", 2)])
def test_gyro_free_navigator_fmus_see_every_parameter(model, vertical_mode):
    """The gyro-free navigators (one model source, three layouts) with the fused-EKF rate
    strategy (cube6: integration, it measures no squared rates) on WGS-84, the vertical
    channel held (hold_height) or damped by the barometer (baro_tau)."""
    tr, sl, _ = _nav_record()
    layout = model.split("_")[1]
    geo = gf.layout(layout, 0.11)
    A = gf.forward_model(geo, tr.accel_m_s2[sl], tr.gyro_rad_s[sl], tr.gyro_dot_rad_s2[sl])
    q0 = gf.euler_to_quat(gf.quat_to_euler(tr.q_bn[sl][0]) + np.array([1e-3, 2e-3, -3e-3]))
    strategy = 0 if layout == "cube6" else 3     # cube6 measures no squared rates
    base = dict(l=0.11, strategy=strategy, accel_noise=2.3e-4,
                omega_init=(tr.gyro_rad_s[sl][0] + [1.1e-3, -1.3e-3, 1.7e-3]).tolist(),
                earth=0, flat_gravity=9.7, vertical_mode=vertical_mode, hold_height=123.4, baro_tau=7.3,
                q0=q0.tolist(), v0=(tr.v_n_m_s[sl][0] + [0.011, -0.013, 0.017]).tolist(),
                lat0=float(tr.lat_rad[sl][0]), lon0=float(tr.lon_rad[sl][0]),
                h0=float(tr.h_m[sl][0]) + 0.37, skip_steps=0, pos0=[1.5, 2.5, 3.5])
    inert = ["flat_gravity", "pos0[0]", "pos0[1]", "pos0[2]",   # the flat Earth's (earth = 1)
             {1: "baro_tau", 2: "hold_height"}[vertical_mode]]  # the other vertical mode's
    if vertical_mode == 1:          # the height held at hold_height, its rate at 0
        inert += ["h0", "v0[2]"]
    if strategy == 0:
        inert.append("accel_noise")                              # the fused EKF's (strategy 3)
    # l is checked against the array the inputs were made for: changing it alone is a
    # different (wrong) geometry, which the run sees; kept in the loop
    _check_every_parameter(model, {"A": A, "h_ext": tr.h_m[sl] + 0.5},
                           ["q", "v", "lat", "lon", "h", "omega", "f"], base, inert,
                           switches=("strategy", "earth", "vertical_mode", "skip_steps"))


def test_accel9_fmu_sees_every_parameter():
    _, _, A = _nav_record()
    base = dict(l=0.11, omega_init=[0.011, -0.013, 0.017])
    # omega_init is the sign reference of the rates (seed 000): its elements act by their
    # signs, so those are flipped
    _check_every_parameter("accel9", {"A": A}, ["f", "omega", "omega_dot", "omega_sq"], base, [],
                           negate=("omega_init",))


def test_vehicle_fmu_sees_every_parameter():
    """The vehicle with IMU errors, noise, the rotating mechanism, the 12-accelerometer
    array and the three aiding sensors (GNSS with a lever arm, an outage, periodic outages
    and a Gauss-Markov error; barometer; odometer), 1.2 s at 100 Hz, through three profile
    segments and two turns of the mechanism. The elements past n_segments, rot_n and
    gnss_n_outages are unused by definition and not perturbed."""
    rng = np.random.default_rng(52)
    e = gf.ImuErrors.random(rng, gyro_bias_deg_h=10, gyro_scale_ppm=1000, gyro_misalignment_arcsec=100,
                            accel_bias_ug=1000, accel_scale_ppm=1000, accel_misalignment_arcsec=100,
                            accel_k2_ug_g2=50, lever_arm_cm=3)

    def padded(values, size, fill=0.0):
        return list(values) + [fill] * (size - len(values))
    base = dict(
        lat0=0.61, lon0=2.03, h0=87.0, heading0=0.37, speed0=4.3, heading_rate0=0.021,
        n_segments=3, seg_duration=padded([0.4, 0.45, 0.5], 32),
        seg_dspeed=padded([1.3, -0.7, 0.9], 32), seg_dheading_rate=padded([0.07, -0.05, 0.03], 32),
        seg_dheading=padded([0.11, -0.13, 0.17], 32), drive=0, command_time=1.9,
        imu_errors=1, **e.fmu_parameters(),
        rotation=1, rot_n=2, rot_repeat=0,
        rot_base_axis=padded([0, -1], 64, -1), rot_imu_axis=padded([-1, 2], 64, -1),
        rot_base_angle=padded([0.43, 0.0], 64), rot_imu_angle=padded([0.0, -0.57], 64),
        rot_move=padded([0.35, 0.31], 64), rot_ramp=padded([0.071, 0.06], 64),
        rot_dwell=padded([0.112, 0.131], 64),
        noise=1, noise_seed=7, gyro_arw=0.19, gyro_bias_instability=2.9, gyro_correlation_time=310.0,
        gyro_rrw=0.23, accel_vrw=49.0, accel_bias_instability=53.0, accel_correlation_time=290.0,
        accel_rrw=0.29, gyro_band=3.1, accel_band=37.0, band_hz=1.7,
        array_noise=2.7e-4, array_layout=2, l=0.097, array_bias=(rng.normal(0, 1e-3, 12)).tolist(),
        gnss=1, gnss_rate=10.0, gnss_offset=0.13, gnss_latency=0.073, gnss_lever_arm=[0.312, 1.27, 1.61],
        gnss_pos_std=[0.41, 0.44, 0.83], gnss_vel_std=[0.051, 0.053, 0.099],
        gnss_pos_gm_std=[0.21, 0.24, 0.39], gnss_pos_gm_tau=47.0, gnss_q=4, gnss_n_outages=1,
        gnss_outage_start=padded([0.309], 8), gnss_outage_end=padded([0.402], 8),
        gnss_outage_first=0.551, gnss_outage_period=0.471, gnss_outage_duration=0.172,
        baro=1, baro_rate=12.5, baro_offset=0.023, baro_std=0.351, baro_bias0=1.4, baro_bias_rw=0.017,
        baro_bias_gm_std=0.27, baro_bias_gm_tau=67.0,
        odo=1, odo_rate=20.0, odo_offset=0.041, odo_lever_arm=[-0.71, 0.2, -0.4],
        odo_scale_error=0.015, odo_std=0.043)
    unused = ([f"{s}[{i}]" for s in ("seg_duration", "seg_dspeed", "seg_dheading_rate", "seg_dheading")
               for i in range(3, 32)]
              + [f"rot_{s}[{i}]" for s in ("base_axis", "imu_axis", "base_angle", "imu_angle", "move",
                                          "ramp", "dwell") for i in range(2, 64)]
              + [f"gnss_outage_{s}[{i}]" for s in ("start", "end") for i in range(1, 8)]
              + [f"{s}_misalign[{i}]" for s in ("gyro", "accel") for i in (0, 4, 8)]   # zero diagonal
              # an axis or angle of no turn: the turn about the other axis (the mechanism's)
              + ["rot_base_axis[1]", "rot_imu_axis[0]", "rot_base_angle[1]", "rot_imu_angle[0]"])
    n = 120
    inputs = {"speed_cmd": np.zeros(n), "heading_rate_cmd": np.zeros(n)}
    outputs = ["q", "v", "lat", "lon", "h", "gyro_rate", "specific_force", "dtheta", "dv", "A",
               "gimbal", "gnss_time_s", "gnss_lat_rad", "gnss_lon_rad", "gnss_h_m", "gnss_vel_enu_m_s",
               "gnss_pos_std_m", "gnss_vel_std_m_s", "gnss_quality", "baro_time_s", "baro_h_m",
               "baro_std_m", "odo_time_s", "odo_speed_m_s", "odo_std_m_s"]
    inert = ["command_time",          # drive = 0: the profile, not the command inputs
             "rot_dwell[1]",          # the last turn's dwell: nothing follows it (no repeat)
             "odo_lever_arm[1]"]      # the forward speed (w x l)_y has no l_y
    _check_every_parameter("vehicle", inputs, outputs, base, inert,
                           switches=("n_segments", "drive", "imu_errors", "rotation", "rot_n",
                                     "rot_repeat", "noise", "array_layout", "gnss", "gnss_n_outages",
                                     "baro", "odo", "rot_base_axis", "rot_imu_axis", "gnss_q"),
                           alike=("array_bias",), fixed=unused,
                           # the IMU error blocks a block at a time (their elements one by one:
                           # the SINS FMU above, the same fmu_imu_errors_build)
                           whole=("gyro_bias", "gyro_scale", "gyro_misalign", "accel_bias",
                                  "accel_scale", "accel_misalign", "accel_k2", "lever_arm",
                                  "array_bias"))
