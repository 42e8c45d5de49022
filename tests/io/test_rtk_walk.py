"""The rtk_walk recording's reader (gfins_fmi.io.rtk_walk): the mounting matrix in
right-front-up, units, axes and time of the IMU CSV, and checks of the real recording
(counts and times, gravity up at rest, the right axis from the turns, GNSS velocity in
east-north-up).
"""
from __future__ import annotations

import datetime
import math
import os
import pathlib

import numpy as np
import pytest

from support.paths import rtk_walk_dir
from gfins_fmi.io import FileFormatError, GnssRecord, load_rtk_walk, read_rtk_walk_imu, rtk_walk_mounting
from gfins_fmi.io.rtk_walk import mounting_from_rpy

GPS_EPOCH = datetime.datetime(1980, 1, 6)
DEG = math.pi / 180


# axes of FRD as seen from RFU, and of NED from ENU, typed in: R = F's y, F = F's x, U = -D
FRD_TO_RFU = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]], float)


def write(path: pathlib.Path, text: str) -> pathlib.Path:
    path.write_text(text, encoding="utf-8")
    return path


def gnss(n=6, dt=1.0, vel=True):
    t = 1000.0 + dt * np.arange(n)
    v = np.tile([1.0, 2.0, 0.1], (n, 1)) if vel else None
    return GnssRecord(t, np.full(n, 0.5), np.full(n, 2.0), np.full(n, 30.0),
                      np.tile([0.02, 0.03, 0.05], (n, 1)), v,
                      np.tile([0.1, 0.1, 0.2], (n, 1)) if vel else None,
                      np.array([1, 1, 2, 2, 5, 1][:n]), "test")


def gps_seconds(dt: datetime.datetime) -> float:
    return (dt - GPS_EPOCH).total_seconds()


def test_rtk_walk_mounting_is_the_sources_matrix_in_rfu():
    """The source (rtklibexplorer/GNSS_IMU) applies f_b = C f_s with Groves' Euler_to_CTM
    of rpy = (180, 0, -90) deg for a forward-right-down body; its matrix, typed in here,
    then FRD -> RFU: diag(-1, -1, 1) (the typed formula to 1e-15, as sin(pi) = 1.2e-16;
    the function's matrix exactly, its entries snapped)."""
    phi, theta, psi = math.pi, 0.0, -math.pi / 2
    sf, cf, st, ct, sp, cp = (math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta),
                              math.sin(psi), math.cos(psi))
    groves = np.array([[ct * cp, ct * sp, -st],
                       [-cf * sp + sf * st * cp, cf * cp + sf * st * sp, sf * ct],
                       [sf * sp + cf * st * cp, -sf * cp + cf * st * sp, cf * ct]])
    assert np.abs(FRD_TO_RFU @ groves - rtk_walk_mounting()).max() < 1e-15
    np.testing.assert_array_equal(rtk_walk_mounting(), np.diag([-1.0, -1.0, 1.0]))


def test_rtk_walk_imu_reader_units_axes_and_time(tmp_path):
    text = ("1756402240.9610000,0.1,-0.2,1.0,0.01,0.02,0.03,0,0,0,0\n"
            "1756402240.9670007,0.2,-0.1,1.1,0.04,0.05,0.06,0,0,0,0\n")
    r = read_rtk_walk_imu(write(tmp_path / "imu.csv", text), np.diag([-1.0, -1.0, 1.0]))
    g = 9.80665
    np.testing.assert_array_equal(r.accel, [[-0.1 * g, 0.2 * g, 1.0 * g], [-0.2 * g, 0.1 * g, 1.1 * g]])
    np.testing.assert_array_equal(r.gyro, [[-0.01, -0.02, 0.03], [-0.04, -0.05, 0.06]])
    # GPS seconds: 3657 days between 1970-01-01 and 1980-01-06, by datetime
    offset = (GPS_EPOCH - datetime.datetime(1970, 1, 1)).total_seconds()
    np.testing.assert_array_equal(r.t_s, [1756402240.961 - offset, 1756402240.9670007 - offset])
    with pytest.raises(ValueError, match="determinant of -1 swaps handedness"):
        read_rtk_walk_imu(tmp_path / "imu.csv", np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="about 9.8"):
        read_rtk_walk_imu(tmp_path / "imu.csv", np.eye(3), g_m_s2=1.0)
    with pytest.raises(FileFormatError, match="imu2.csv:2: 7 columns where a rtk_walk IMU CSV line has 11"):
        read_rtk_walk_imu(write(tmp_path / "imu2.csv", text.splitlines()[0] + "\n1,2,3,4,5,6,7\n"), np.eye(3))


@pytest.fixture(scope="module")
def rtk_walk():
    folder = rtk_walk_dir()
    if folder is None:
        message = ("rtk_walk data not found: shared/data/rtk_walk beside the repository, or set "
                   "GFINS_RTK_WALK_DIR")
        if os.environ.get("CI"):
            pytest.fail(message)                       # CI has shared/: a missing copy is a failure
        pytest.skip(message)
    return load_rtk_walk(folder)


def test_rtk_walk_counts_and_times(rtk_walk):
    """The README's counts; both records on one scale: the IMU's first sample
    (17:30:40.961 GPST) 1.2 s after the first GNSS epoch (17:30:39.749)."""
    imu, gnss = rtk_walk
    assert len(imu) == 20455 and imu.kind == "rates"
    assert len(gnss) == 536 and gnss.quality_counts() == {"fix": 349, "float": 187}
    assert gnss.has_velocity
    t_imu0 = gps_seconds(datetime.datetime(2025, 8, 28, 17, 30, 40, 961000))
    t_gnss0 = gps_seconds(datetime.datetime(2025, 8, 28, 17, 30, 39, 749000))
    assert abs(imu.t_s[0] - t_imu0) < 1e-6 and abs(gnss.t_s[0] - t_gnss0) < 1e-6
    overlap = min(imu.t_s[-1], gnss.t_s[-1]) - max(imu.t_s[0], gnss.t_s[0])
    assert overlap > 130.0                               # of 134 s
    st = imu.dt_stats()
    assert abs(st.median_s - 0.006) < 1e-5 and st.max_s < 0.0095 and st.gaps == ()
    assert abs(1 / st.mean_s - 152.3) < 0.5              # the README's average rate
    g_st = gnss.dt_stats()
    assert g_st.min_s > 0.2499 and g_st.max_s < 0.2501   # 4 Hz, no missing epoch


def test_rtk_walk_at_rest_gravity_points_up(rtk_walk):
    """First second, at rest (|w| < 0.01 rad/s): the specific force is gravity's
    reaction, up. Magnitude 9.92 m/s^2 measured (the README's 1.01 g; normal gravity
    there, 40.1 deg N and 1601 m, is 9.796): within 0.2 m/s^2 (2 %, a consumer MEMS
    accelerometer's scale and bias) — in g, unconverted, it would read 1.01. Tilt of
    the up axis 1.0 deg measured: below 5 deg for a handheld receiver held level."""
    imu, _ = rtk_walk
    rest = imu.t_s < imu.t_s[0] + 1.0
    assert np.abs(imu.gyro[rest]).max() < 0.01
    f = imu.accel[rest].mean(axis=0)
    assert abs(np.linalg.norm(f) - 9.796) < 0.2
    assert f[2] / np.linalg.norm(f) > math.cos(5 * DEG)


def _window_mean(t, x, centres, half):
    """Mean of the samples x(t) over [c - half, c + half] for each centre."""
    c = np.concatenate([[0.0], np.cumsum(x)])
    lo = np.searchsorted(t, centres - half)
    hi = np.searchsorted(t, centres + half)
    return (c[hi] - c[lo]) / np.maximum(hi - lo, 1)


def test_rtk_walk_right_axis_from_the_turns(rtk_walk):
    """Walking forward at speed v and turning left at rate w_up, the centripetal
    acceleration points to the left: f_right = -w_up v. Over 1 s windows while moving
    (v > 0.5 m/s) the correlation of f_right with w_up v is -0.54 measured: the right
    axis is right (with x and y unflipped, identity mounting, +0.54; the handheld device's tilt
    and step accelerations keep it from -1). Require < -0.3."""
    imu, gnss = rtk_walk
    v = np.hypot(gnss.vel_enu_m_s[:, 0], gnss.vel_enu_m_s[:, 1])
    ok = (v > 0.5) & (gnss.t_s > imu.t_s[0] + 1) & (gnss.t_s < imu.t_s[-1] - 1)
    w_up = _window_mean(imu.t_s, imu.gyro[:, 2], gnss.t_s[ok], 0.5)
    f_right = _window_mean(imu.t_s, imu.accel[:, 0], gnss.t_s[ok], 0.5)
    assert np.corrcoef(f_right, w_up * v[ok])[0, 1] < -0.3


def test_rtk_walk_gnss_velocity_is_east_north_up(rtk_walk):
    """The velocity columns agree with the position differences, axis by axis
    (correlation > 0.9 east and north; measured 0.99): ENU, not RTKLIB's NEU order."""
    _, gnss = rtk_walk
    a, e2 = 6378137.0, 6.69437999014e-3
    s = np.sin(gnss.lat_rad)
    rn = a / np.sqrt(1 - e2 * s * s)
    rm = rn * (1 - e2) / (1 - e2 * s * s)
    dt = np.diff(gnss.t_s)
    east = np.diff(gnss.lon_rad) * (rn[1:] + gnss.h_m[1:]) * np.cos(gnss.lat_rad[1:]) / dt
    north = np.diff(gnss.lat_rad) * (rm[1:] + gnss.h_m[1:]) / dt
    mid = 0.5 * (gnss.vel_enu_m_s[1:] + gnss.vel_enu_m_s[:-1])
    assert np.corrcoef(east, mid[:, 0])[0, 1] > 0.9
    assert np.corrcoef(north, mid[:, 1])[0, 1] > 0.9


def test_mounting_from_any_angles_is_grovess_matrix_in_rfu(rng):
    """Groves' Euler_to_CTM (C = (Rz(yaw) Ry(pitch) Rx(roll))^T, typed in here from its
    closed form) for random angles, then FRD -> RFU: mounting_from_rpy to 1e-15 (round-off;
    no entry near 0 or +-1 for these angles, so nothing is snapped)."""
    for _ in range(20):
        phi, theta, psi = rng.uniform(-3.0, 3.0), rng.uniform(-1.4, 1.4), rng.uniform(-3.0, 3.0)
        sf, cf, st, ct, sp, cp = (math.sin(phi), math.cos(phi), math.sin(theta), math.cos(theta),
                                  math.sin(psi), math.cos(psi))
        groves = np.array([[ct * cp, ct * sp, -st],
                           [-cf * sp + sf * st * cp, cf * cp + sf * st * sp, sf * ct],
                           [sf * sp + cf * st * cp, -sf * cp + cf * st * sp, cf * ct]])
        assert np.abs(FRD_TO_RFU @ groves - mounting_from_rpy(phi, theta, psi)).max() < 1e-15


def test_mounting_snaps_only_what_floating_point_cannot_give(tmp_path):
    """Entries within 1e-15 of -1, 0 or +1 become exact; a small angle's sine (2e-8) stays."""
    for yaw in (2e-8, math.pi - 2e-8):
        c = mounting_from_rpy(0.0, 0.0, yaw)
        s = math.sin(2e-8)
        assert set(np.round(np.abs(c[np.abs(c) > 0.5]), 20)) == {1.0}     # exactly +-1
        assert np.isclose(np.sort(np.abs(c[np.abs(c) < 0.5]))[-2:], s, rtol=1e-9).all()
    # half a turn: sin(pi) = 1.2e-16 snapped, a signed permutation of the axes
    assert set(mounting_from_rpy(math.pi, 0.0, 0.0).ravel()) <= {-1.0, 0.0, 1.0}


def test_rtk_walk_mounting_and_unit_refusals(tmp_path):
    path = write(tmp_path / "imu.csv", "1756402240.9610000,0.1,-0.2,1.0,0.01,0.02,0.03,0,0,0,0\n")
    for bad in (np.eye(4)[:3, :], np.eye(2), np.full((3, 3), np.nan)):
        with pytest.raises(ValueError, match="mounting must be a finite 3x3 rotation matrix"):
            read_rtk_walk_imu(path, bad)
    with pytest.raises(ValueError, match=r"mounting must be a rotation \(orthonormal"):
        read_rtk_walk_imu(path, 1.01 * np.eye(3))                 # |C C^T - I| = 0.02
    for g in (9.0, 9.7, 9.9, 9.95, 10.0):
        with pytest.raises(ValueError, match="about 9.8"):
            read_rtk_walk_imu(path, np.eye(3), g_m_s2=g)
    r = read_rtk_walk_imu(path, np.diag([-1.0, -1.0, 1.0]), g_m_s2=9.71)
    assert r.accel[0, 2] == 9.71 and "C_s^b = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]" in r.source
    # a reflection (determinant -1) is refused; a rotation typed with a little round-off
    # (|C C^T - I| = 2e-12, det = 1 - 3e-12 < 1) is accepted, as the tolerance 1e-9 says
    with pytest.raises(ValueError, match=r"determinant \+1\); got .*det = -1"):
        read_rtk_walk_imu(path, np.diag([1.0, 1.0, -1.0]))
    near = read_rtk_walk_imu(path, (1.0 - 1e-12) * mounting_from_rpy(0.5, 0.25, 1.5))
    assert np.isfinite(near.accel).all()
    # the source text shows the matrix without negative zeros (-I's off-diagonal -0.0)
    r = read_rtk_walk_imu(path, -np.diag([1.0, 1.0, -1.0]), g_m_s2=9.71)
    assert "-0.0" not in r.source and "[[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]" in r.source
