"""In-motion alignment with a speed sensor and forward-backward processing (issue 13,
seed 003): the tachometer measurement, the reversed filter through the Python layer,
align_in_motion and its bad-input errors.

Truth: the vehicle simulator (gf_vehicle, independent of the filter) and closed-form
checks; the forward-backward driver's bits against the passes made one by one (two
independent paths through the C core: one call for all passes, and one call per pass
with the measurements split in Python). Seeds fixed; ~5 s CPU."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi._lib import lib
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.alignment import AlignmentError, coarse_align, coarse_align_inertial
from gfins_fmi.estimation.fine_alignment import align_in_motion
from gfins_fmi.estimation.evaluation import attitude_difference_rad
from gfins_fmi.io.records import BaroRecord, ImuRecord, OdometerRecord
from gfins_fmi.nav.strapdown import NavState, quat_to_euler
from gfins_fmi.sim import trajectory as tj
from support.auv import A_BIAS, DEG, DT, G_BIAS, NOISE, auv_truth, records
from support.motions import Mooring


@pytest.fixture(scope="module")
def auv():
    """The AUV-like run (support/auv.py)."""
    return auv_truth()


def config(**kw):
    return FilterConfig(imu=NOISE, gate_probability=0.9999, gate_reset_count=0, **kw)


def test_speed_measurement_levels_the_ins(auv):
    """Free inertial with a 0.2 deg tilt error drifts ~g 0.0035 t; with the tachometer
    speed and the turns the level errors are estimated: at 200 s they are far below the
    initial 0.2 deg (the seed-003 study measures a median 0.7' at 200 s for one forward
    pass; bound 3', a factor 4 above it and 4x below the initial error)."""
    imu, tach, depth, init = records(auv)
    sol = IntegratedNavigator(config(), init).run(imu, baro=depth, speed=tach)
    inn = sol.innovations_of("speed")
    assert len(inn) == len(tach.t_s) and np.all(inn["status"] == lib.GF_INS_ACCEPTED)
    a = attitude_difference_rad(sol.q_bn[-1], auv.q_bn[-1])[0]
    assert np.all(np.abs(a[:2]) < 3 / 60 * DEG), a / DEG * 60


def test_low_speed_refused_and_gross_speed_gated(auv):
    """At 0 m/s (a filter started at rest) the speed update is refused (direction of v_h
    undefined); a tachometer reading 3x the speed is rejected by the NIS gate."""
    imu, tach, depth, init = records(auv, t_end=20.0)
    nav0 = init.nav
    still = InitialState(NavState(nav0.q_bn, np.zeros(3), nav0.lat_rad, nav0.lon_rad, nav0.h_m, nav0.t_s),
                         velocity_std_m_s=0.01, gyro_bias_std_rad_s=G_BIAS, accel_bias_std_m_s2=A_BIAS)
    rest = ImuRecord(t_s=imu.t_s[:50], gyro=np.zeros((50, 3)),
                     accel=np.tile([0, 0, 9.7936 * DT], (50, 1)), kind="increments")
    z = OdometerRecord(t_s=np.array([0.5]), speed_m_s=np.array([0.0]), std_m_s=np.array([0.05]))
    sol = IntegratedNavigator(config(), still).run(rest, speed=z)
    assert list(sol.innovations["status"]) == [lib.GF_INS_REJECTED_LOW_SPEED]
    bad = OdometerRecord(t_s=tach.t_s, speed_m_s=3 * tach.speed_m_s, std_m_s=tach.std_m_s)
    sol = IntegratedNavigator(config(), init).run(imu, speed=bad)
    assert np.all(sol.innovations_of("speed")["status"] == lib.GF_INS_REJECTED_GATE)


def test_reverse_round_trip_python(auv):
    """Forward over 60 s then backward (reverse + run_backward) returns the nominal to its
    start within gf_sins' documented round trip (docs/sins.md: 1e-5 m, 2.3e-8 m/s,
    1.3e-11 rad over 10 min); rows report true-time velocity; reversing twice restores."""
    imu, tach, depth, init = records(auv, t_end=60.0)
    nav = IntegratedNavigator(config(), init)
    fwd = nav.run(imu)
    nav.reverse()
    assert nav.reversed
    with pytest.raises(ValueError, match="reversed"):
        nav.run(imu)
    back = nav.run_backward(imu, float(init.nav.t_s))
    assert abs(nav.t_s - init.nav.t_s) < 1e-9
    R = 6.37e6
    # row k of the backward walk is the state at t_(k-1) = forward row k-1
    dpos = np.abs(back.lat_rad[1:] - fwd.lat_rad[:-1]).max() * R
    dv = np.abs(back.v_n_m_s[1:] - fwd.v_n_m_s[:-1]).max()
    assert dpos < 1e-5 and dv < 2.3e-8, (dpos, dv)
    q_end = back.q_bn[0]
    assert np.linalg.norm(attitude_difference_rad(q_end, init.nav.q_bn)) < 1.3e-11
    P = nav.covariance
    nav.reverse()
    nav.reverse()
    assert np.array_equal(nav.covariance, P)


def test_reverse_round_trip_ukf(auv):
    """The UKF turns around too; its time update feeds back the mean of the propagated
    sigma points (a legitimate second-order move of the nominal, not reversible), so its
    free round trip is looser than the EKF's: measured 1.0e-5 m, 2.6e-4 m/s, 3e-10 rad
    over 60 s with velocity sigma 0.4 m/s; bounds 4x those."""
    imu, tach, depth, init = records(auv, t_end=60.0)
    nav = IntegratedNavigator(config(filter="ukf"), init)
    fwd = nav.run(imu)
    nav.reverse()
    back = nav.run_backward(imu, float(init.nav.t_s))
    assert np.abs(back.lat_rad[1:] - fwd.lat_rad[:-1]).max() * 6.37e6 < 4e-5
    assert np.abs(back.v_n_m_s[1:] - fwd.v_n_m_s[:-1]).max() < 1e-3
    assert np.linalg.norm(attitude_difference_rad(back.q_bn[0], init.nav.q_bn)) < 1.2e-9


def test_forward_backward_one_call_equals_passes(auv):
    """align_in_motion in one C call (gf_ins_forward_backward) and pass by pass
    (keep_rows: forward runs and backward walks, measurements split in Python) give the
    same bits; the pass table alternates direction and ends forward at the last sample."""
    imu, tach, depth, init = records(auv, t_end=60.0)
    a = align_in_motion(imu, tach, depth=depth, config=config(), initial=init, passes=2)
    b = align_in_motion(imu, tach, depth=depth, config=config(), initial=init, passes=2, keep_rows=True)
    assert np.array_equal(a.q_bn, b.q_bn) and np.array_equal(a.covariance, b.covariance)
    assert list(a.passes["direction"]) == [1, -1, 1, -1, 1]
    assert a.passes["t_s"][-1] == imu.t_s[-1] and abs(a.passes["t_s"][1] - init.nav.t_s) < 1e-9
    assert np.array_equal(a.passes["n_updates"], b.passes["n_updates"])
    assert len(b.rows) == 5 and len(b.rows[1]) == len(imu.t_s)
    # the navigator goes on forward from the end of the alignment period
    assert not a.navigator.reversed and a.navigator.t_s == imu.t_s[-1]


def test_forward_backward_improves_on_one_pass(auv):
    """Seed 003's finding on one run of 200 s: 4 forward-backward passes give smaller
    level errors than one forward pass over the same data (the study's medians over 50
    runs are in docs/reproductions/seed003_alignment.md)."""
    imu, tach, depth, init = records(auv, seed=11)
    k = len(imu.t_s)
    e = []
    for p in (0, 4):
        al = align_in_motion(imu, tach, depth=depth, config=config(), initial=init, passes=p)
        e.append(np.linalg.norm(attitude_difference_rad(al.q_bn, auv.q_bn[k])[0][:2]))
        assert al.converged, al.notes
    assert e[1] < e[0], np.array(e) / DEG * 60


def test_short_record_reported_not_converged(auv):
    """Seed 003's 30 s: the data do not hold the heading (first-pass heading sigma ~2.6 deg
    in the study); passes reuse them and settle with a small sigma on a wrong heading, so
    the verdict comes from the first pass: not converged, and said so in the notes."""
    imu, tach, depth, init = records(auv, t_end=30.0)
    al = align_in_motion(imu, tach, depth=depth, config=config(), initial=init, passes=3)
    assert not al.converged and any("NOT CONVERGED" in n for n in al.notes)
    assert al.passes["std9"][0, 8] > 0.5 * DEG


def test_align_in_motion_bad_input(auv):
    imu, tach, depth, init = records(auv, t_end=40.0)
    cfg = config()
    with pytest.raises(AlignmentError, match="shorter than min_duration_s"):
        align_in_motion(imu, tach, config=cfg, initial=init, passes=5, min_duration_s=60.0)
    with pytest.raises(AlignmentError, match="passes must be"):
        align_in_motion(imu, tach, config=cfg, initial=init, passes=-1)
    polar = InitialState(NavState(init.nav.q_bn, init.nav.v_n_m_s, 86 * DEG, 0.0, 0.0, 0.0),
                         gyro_bias_std_rad_s=G_BIAS, accel_bias_std_m_s2=A_BIAS)
    with pytest.raises(AlignmentError, match="85 deg"):
        align_in_motion(imu, tach, config=cfg, initial=polar)
    late = InitialState(NavState(init.nav.q_bn, init.nav.v_n_m_s, init.nav.lat_rad, init.nav.lon_rad,
                                 init.nav.h_m, 5.0), gyro_bias_std_rad_s=G_BIAS, accel_bias_std_m_s2=A_BIAS)
    with pytest.raises(AlignmentError, match="before its first sample"):
        align_in_motion(imu, tach, config=cfg, initial=late)
    wrong = OdometerRecord(t_s=tach.t_s, speed_m_s=2.5 * tach.speed_m_s, std_m_s=tach.std_m_s)
    with pytest.raises(AlignmentError, match="disagrees with the INS"):
        align_in_motion(imu, wrong, config=cfg, initial=init, passes=1)
    wide = InitialState(init.nav, attitude_std_rad=(0.01, 0.01, 30 * DEG), gyro_bias_std_rad_s=G_BIAS,
                        accel_bias_std_m_s2=A_BIAS)
    with pytest.raises(AlignmentError, match="coarse heading"):
        align_in_motion(imu, tach, config=cfg, initial=wide)
    far = OdometerRecord(t_s=tach.t_s + 1000.0, speed_m_s=tach.speed_m_s, std_m_s=tach.std_m_s)
    with pytest.raises(AlignmentError, match="no speed measurement inside"):
        align_in_motion(imu, far, config=cfg, initial=init)


def test_measurement_at_initial_time_is_applied(auv):
    """A GNSS-like height (baro) epoch exactly at the filter's initial time is applied
    there (it was logged stale before issue 13's fix)."""
    imu, tach, depth, init = records(auv, t_end=2.0)
    b = BaroRecord(t_s=np.array([init.nav.t_s]), h_m=np.array([init.nav.h_m + 0.3]), std_m=np.array([0.1]))
    sol = IntegratedNavigator(config(), init).run(imu, baro=b)
    assert list(sol.innovations["status"]) == [lib.GF_INS_ACCEPTED]
    assert sol.innovations["t_s"][0] == init.nav.t_s


def _record(motion, duration_s):
    tr = tj.sample(motion, duration_s, 0.01)
    return tr, ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad, accel=tr.dv_m_s, kind="increments",
                         source=type(motion).__name__)


def _euler_error(ca, tr, t_s):
    e = ca.euler_rad - quat_to_euler(tr.q_bn[int(round(t_s / 0.01))])
    return (e + np.pi) % (2 * np.pi) - np.pi


def test_inertial_frame_alignment_on_a_swaying_base():
    """Issue 13 item 1, the disturbed base: on a moored ship the mean rate is the sway's
    (gyrocompassing gives no heading) while the inertial-frame method finds the heading
    from the turn of gravity in inertial space. Perfect sensors, 300 s at 30 deg N:
    measured heading error 0.14 deg (the sway's velocity over the turn of the up axis:
    ~ 0.38 m/s / (g 300 s) / (W 300 s cos L) = 0.39 deg as a bound), tilt 0.002-0.003 deg.
    Allowed: 0.3 deg and 0.01 deg (about 2x and 3x the measured), and the reported
    1-sigma must cover the error (it is built from the fit's misfit: 0.37 deg here)."""
    m = Mooring()
    tr, rec = _record(m, 300.0)
    ca = coarse_align_inertial(rec, 0.0, 300.0, m.lat)
    err = _euler_error(ca, tr, 300.0)
    assert ca.heading_method == "inertial frame"
    assert abs(err[0]) < np.radians(0.3), np.degrees(err)
    assert np.all(np.abs(err[1:]) < np.radians(0.01)), np.degrees(err)
    assert ca.heading_std_rad >= abs(err[0]) and ca.tilt_std_rad >= np.abs(err[1:]).max()
    # the static method on the same record: refused (motion) or no heading
    try:
        cs = coarse_align(rec, 0.0, 300.0, m.lat, max_accel_std_m_s2=1.0, max_rate_rad_s=1.0)
        assert not np.isfinite(cs.euler_rad[0]) or abs(_euler_error(cs, tr, 300.0)[0]) > np.radians(5.0)
    except AlignmentError:
        pass


def test_inertial_frame_alignment_at_rest_is_exact():
    """At rest the integrated specific force is gravity's closed form: the attitude comes
    back to round-off (measured 2e-10 deg: 3e4 mechanization steps)."""
    st = tj.Stationary(heading=40 * DEG, pitch=2 * DEG, roll=-1 * DEG)
    tr, rec = _record(st, 60.0)
    err = _euler_error(coarse_align_inertial(rec, 0.0, 60.0, st.lat), tr, 60.0)
    assert np.all(np.abs(err) < np.radians(1e-8)), np.degrees(err)


def test_inertial_frame_alignment_refuses_what_it_cannot_do():
    st = tj.Stationary()
    _, rec = _record(st, 40.0)
    with pytest.raises(AlignmentError, match="shorter than 30"):
        coarse_align_inertial(rec, 0.0, 20.0, st.lat)
    with pytest.raises(AlignmentError, match="85 deg"):
        coarse_align_inertial(rec, 0.0, 40.0, np.radians(87.0))
    # a vehicle driving a circle: its accelerations do not integrate to a bounded velocity
    c = tj.Circle()
    _, rec_c = _record(c, 60.0)
    with pytest.raises(AlignmentError, match="base is moving"):
        coarse_align_inertial(rec_c, 0.0, 60.0, c.lat)
