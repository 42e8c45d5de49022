"""The batch API's checks before a run and its messages (issue 21): a measurement record
with no epoch inside the IMU record (two time scales) raises or warns as the caller
chooses; absurd standard deviations and rates name the argument and the limit; IMU
records whose specific force is far from gravity are warned about; no numpy scalar repr
reaches a message.

Truth: records of a simulated drive shifted by known offsets; the messages' text.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi import io
from gfins_fmi.estimation import (FilterConfig, FilterError, InitialState, IntegratedNavigator,
                                  UnusableMeasurementError, UnusableMeasurementWarning)
from gfins_fmi.estimation.alignment import coarse_align
from gfins_fmi.estimation.fine_alignment import fine_align
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, Odometer


@pytest.fixture(scope="module")
def drive():
    return simulate_drive(town_drive(20.0, lat0_rad=0.6, lon0_rad=2.0, h0_m=30.0), 20.0, 0.01,
                          imu=TACTICAL, gnss=GnssReceiver(), odometer=Odometer(), seed=5)


def _nav(d):
    return IntegratedNavigator(FilterConfig(imu=TACTICAL), InitialState(d.initial))


def test_a_record_outside_the_imu_record_raises_or_warns(drive):
    """Before: GNSS times entirely outside the IMU record — the API returned the unaided
    solution without a word. Now an exception by default, a warning or nothing on
    request (checks='warn' for a piece of a longer record that falls in an outage)."""
    late = dataclasses.replace(drive.gnss, t_s=drive.gnss.t_s + 1000.0)
    with pytest.raises(UnusableMeasurementError, match=r"no GNSS epoch falls inside the IMU record "
                       r"\(0 to 20 s\): its 21 epochs cover 1000 to 1020 s, so the run would be "
                       r"unaided; they are \+1000 s apart"):
        _nav(drive).run(drive.imu, late)
    with pytest.warns(UnusableMeasurementWarning, match="no odometer epoch falls inside .* they are 1 "
                      "GPS week apart: seconds of week against a continuous time"):
        odo = dataclasses.replace(drive.odometer, t_s=drive.odometer.t_s + 604800.0)
        sol = _nav(drive).run(drive.imu, drive.gnss, odometer=odo, checks="warn")
    assert len(sol) == len(drive.imu.t_s)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _nav(drive).run(drive.imu, late, checks="off")
    with pytest.raises(ValueError, match="checks must be one of 'raise', 'warn', 'off'"):
        _nav(drive).run(drive.imu, drive.gnss, checks="never")


def test_specific_force_far_from_gravity_is_warned(drive):
    """An IMU record whose accelerations are in g (|f| = 1 where 9.8 m/s^2 is expected):
    finite and within every limit, so the filter ran and diverged quietly. Warned."""
    rec = io.ImuRecord(t_s=drive.imu.t_s, gyro=drive.imu.gyro, accel=drive.imu.accel / 9.80665,
                       kind=drive.imu.kind)
    with pytest.warns(gf.PlausibilityWarning, match=r"the IMU record: the median specific force \|f\| "
                      r"is [\d.]+ m/s\^2 \(0\.10\d g\).* likely cause: accelerations in g where m/s\^2 "
                      r"are expected"):
        try:
            _nav(drive).run(rec, drive.gnss)
        except FilterError:        # diverging on it is fine: the warning came first
            pass


@pytest.mark.parametrize("field, value, message", [
    ("position_std_m", 1e200, r"InitialState.position_std_m = 1e\+200 m is above 1e\+07 m \(more than "
                              r"the Earth's radius\): give the 1-sigma of the error at the start"),
    ("velocity_std_m_s", 1e300, r"InitialState.velocity_std_m_s = 1e\+300 m/s is above 10000 m/s"),
    ("attitude_std_rad", (0.1, 0.1, 7.0), r"InitialState.attitude_std_rad = .* is above 3.14159 rad"),
])
def test_initial_stds_name_their_limit(drive, field, value, message):
    """Before: InitialState(position_std_m=1e200) -> "gf_ins_init: an input sample is not
    finite (NaN or Inf)" (its variance overflowed in C)."""
    with pytest.raises(ValueError, match=message):
        IntegratedNavigator(FilterConfig(imu=TACTICAL), InitialState(drive.initial, **{field: value}))


def test_measurement_std_names_its_limit(drive):
    """Before: an odometer std of 1e300 -> "IMU sample 0 holds NaN or Inf"."""
    odo = dataclasses.replace(drive.odometer, std_m_s=np.full(len(drive.odometer.t_s), 1e300))
    with pytest.raises(ValueError, match=r"odometer at t = .* s has a standard deviation of \[1e\+300\] "
                       r".* above 1e\+100 its variance overflows"):
        _nav(drive).run(drive.imu, drive.gnss, odometer=odo)


def _static(lat_deg=34.0, seconds=30.0, dt=0.01):
    """A level IMU at rest facing north: gravity up, the Earth rate (0, cos L, sin L)."""
    lat = np.radians(lat_deg)
    n = int(seconds / dt)
    w = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])
    f = np.array([0.0, 0.0, 9.7966])
    return io.ImuRecord(t_s=np.arange(1, n + 1) * dt, gyro=np.tile(w * dt, (n, 1)),
                        accel=np.tile(f * dt, (n, 1)), kind="increments")


@pytest.mark.parametrize("rate_hz, message", [
    (0.0, r"rate_hz must be finite and > 0 Hz; got 0\.0"),
    (1e9, r"rate_hz = 1e\+09 Hz is above the IMU's sampling rate \(100 Hz\): a zero-velocity update "
          r"comes at most once per IMU sample"),
])
def test_fine_align_rate_names_its_limit(rate_hz, message):
    """Before: rate_hz=0 a bare ZeroDivisionError; rate_hz=1e9 a 447 GiB MemoryError."""
    imu = _static()
    co = coarse_align(imu, 0.0, 10.0, np.radians(34.0), gyro_bias_std_rad_s=1e-8)
    with pytest.raises(ValueError, match=message):
        fine_align(imu, np.radians(34.0), 0.0, 80.0, config=FilterConfig(imu=TACTICAL), coarse=co,
                   rate_hz=rate_hz)


def test_coarse_align_latitude_check_raises_or_warns():
    """The latitude given against the Earth rate measured at rest (gyros good enough to
    say: a bias 1-sigma given)."""
    imu = _static(34.0)
    with pytest.raises(gf.estimation.alignment.AlignmentError,
                       match=r"the latitude given, -34\.0000 deg, is 68 deg from the one the gyros "
                             r"measure at rest, 34\.0000 deg"):
        coarse_align(imu, 0.0, 10.0, np.radians(-34.0), gyro_bias_std_rad_s=1e-8)
    with pytest.warns(gf.PlausibilityWarning, match="is 68 deg from"):
        coarse_align(imu, 0.0, 10.0, np.radians(-34.0), gyro_bias_std_rad_s=1e-8, checks="warn")
    coarse_align(imu, 0.0, 10.0, np.radians(34.0), gyro_bias_std_rad_s=1e-8)     # the right one


def test_no_numpy_scalar_repr_in_messages(drive):
    """Before: times printed as np.float64(...) (numpy 2's scalar repr) in the filter's
    messages. The IMU times here are numpy arrays, as records hold them."""
    t = drive.imu.t_s.copy()
    t[100] = t[99]
    rec = io.ImuRecord.__new__(io.ImuRecord)           # a record object past its own checks
    object.__setattr__(rec, "t_s", t)
    for name in ("gyro", "accel", "kind", "source"):
        object.__setattr__(rec, name, getattr(drive.imu, name))
    with pytest.raises(FilterError) as ei:
        _nav(drive).run(rec, drive.gnss)
    assert "IMU sample 100 at t = 1.0 s" in str(ei.value) or "IMU sample 100 at t = " in str(ei.value)
    assert "np." not in str(ei.value) and "float64" not in str(ei.value), str(ei.value)
    imu = _static()
    with pytest.raises(Exception) as ei:
        fine_align(imu, np.radians(34.0), 0.0, 80.0, config=FilterConfig(imu=TACTICAL),
                   coarse=coarse_align(imu, 0.0, 10.0, np.radians(34.0)), t0_s=np.float64(50.0),
                   t1_s=np.float64(60.0))
    assert "np." not in str(ei.value) and "(50, 60] s" in str(ei.value), str(ei.value)
