"""Simulated drives (gfins_fmi.sim.scenarios): an IMU mounted off the vehicle's axes
against its closed-form truth.
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.nav import earth
from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle


@pytest.fixture(scope="module")
def drive():
    T = 420.0
    prof = town_drive(T)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1),
                      outages_s=((200.0, 260.0),))
    truth = simulate_vehicle(prof, T, 0.01)
    return prof, T, rx, truth


def test_imu_mount_in_the_simulation(drive):
    """simulate_drive(imu_mount_rad=(pitch, heading)): the IMU is mounted off the vehicle's
    axes. Truth in closed form: the vehicle rolls along its forward axis (its IMU point
    moves along its heading), whose direction in IMU axes is (sin h cos p, cos h cos p,
    sin p); the navigation-frame rate and velocity are those of the unrotated run."""
    prof, T, rx, truth = drive
    p, h = np.radians(1.0), np.radians(-1.5)
    d0 = simulate_drive(prof, T, 0.01, imu=TACTICAL, seed=1, truth=truth)
    d = simulate_drive(prof, T, 0.01, imu=TACTICAL, seed=1, truth=truth, imu_mount_rad=(p, h))
    C = earth.quat_to_dcm(d.truth.q_bn)                                  # C_b^n of the IMU
    C0 = earth.quat_to_dcm(d0.truth.q_bn)
    vb = np.einsum("kji,kj->ki", C, d.truth.v_n_m_s)
    moving = np.linalg.norm(vb, axis=1) > 1.0
    axis = np.array([np.sin(h) * np.cos(p), np.cos(h) * np.cos(p), np.sin(p)])
    u = vb[moving] / np.linalg.norm(vb[moving], axis=1)[:, None]
    # the vehicle's own axes: x (cos h, -sin h, 0), y = axis, z (-sin p sin h, -sin p cos h,
    # cos p) in IMU axes; its body velocity from the unrotated run, mapped: round-off
    C_mb = np.c_[[np.cos(h), -np.sin(h), 0.0], axis, [-np.sin(p) * np.sin(h), -np.sin(p) * np.cos(h), np.cos(p)]]
    u0 = np.einsum("kji,kj->ki", C0, d0.truth.v_n_m_s)[moving]
    u0 /= np.linalg.norm(u0, axis=1)[:, None]
    assert np.max(np.abs(u - u0 @ C_mb.T)) < 1e-12
    # and it rolls along its forward axis (measured 7e-5: the route's grade changes)
    assert np.max(np.linalg.norm(u - axis, axis=1)) < 2e-4
    # rates in the navigation frame unchanged (a fixed rotation of the body): round-off
    wn, wn0 = np.einsum("kij,kj->ki", C, d.truth.gyro_rad_s), np.einsum("kij,kj->ki", C0, d0.truth.gyro_rad_s)
    assert np.max(np.abs(wn - wn0)) < 1e-14
    assert np.array_equal(d.truth.v_n_m_s, d0.truth.v_n_m_s)
    # the increments are rotated the same way: |dtheta| and |dv| kept
    np.testing.assert_allclose(np.linalg.norm(d.truth.dv_m_s, axis=1),
                               np.linalg.norm(d0.truth.dv_m_s, axis=1), rtol=1e-13, atol=1e-15)
    with pytest.raises(ValueError, match="imu_mount_rad"):
        simulate_drive(prof, T, 0.01, truth=truth, imu_mount_rad=(0.0, 2.0))
