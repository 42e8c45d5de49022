"""Properties of the integrated navigator (hypothesis): IntegratedNavigator.run in pieces
equals one run over the record, bit for bit (EKF and UKF).
"""
from __future__ import annotations

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is in the test extra: pip install '.[test]'")
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import gfins_fmi as gf  # noqa: E402
from support.properties import FEW  # noqa: E402


@pytest.fixture(scope="module")
def short_drive():
    """20 s of a vehicle (truth at 1 kHz, increments at 100 Hz) with GNSS at 1 Hz."""
    from gfins_fmi.io import GnssRecord, ImuRecord
    from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle
    prof = VehicleProfile(lat0_rad=0.52, speed0_m_s=8.0, segments=[
        Segment(5), Segment(8, dspeed_m_s=3, dheading_rad=np.pi / 2), Segment(7)])
    tr = simulate_vehicle(prof, 20.0, 0.001)
    step = 10
    n = (len(tr.t_s) - 1) // step
    imu = ImuRecord(tr.t_s[step::step][:n].copy(), tr.dtheta_rad[:n * step].reshape(n, step, 3).sum(1),
                    tr.dv_m_s[:n * step].reshape(n, step, 3).sum(1), "increments", "short drive")
    k = np.arange(1000, len(tr.t_s), 1000)
    m = len(k)
    gnss = GnssRecord(tr.t_s[k], tr.lat_rad[k], tr.lon_rad[k], tr.h_m[k],
                      pos_std_m=np.tile([0.05, 0.05, 0.1], (m, 1)),
                      vel_enu_m_s=tr.v_n_m_s[k], vel_std_m_s=np.full((m, 3), 0.01))
    return tr, imu, gnss


@FEW
@given(cut_fraction=st.floats(0.01, 0.99), filt=st.sampled_from(["ekf", "ukf"]))
def test_integrated_navigator_in_pieces_equals_whole(short_drive, cut_fraction, filt):
    from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
    tr, imu, gnss = short_drive
    noise = gf.ImuNoise(gyro_arw_deg_sqrt_h=0.01, accel_vrw_ug_sqrt_hz=10,
                        gyro_bias_instability_deg_h=0.1, gyro_correlation_time_s=3600,
                        accel_bias_instability_ug=20, accel_correlation_time_s=3600)

    def navigator():
        return IntegratedNavigator(FilterConfig(imu=noise, filter=filt),
                                   InitialState(gf.NavState.from_trajectory(tr, 0)))
    whole = navigator().run(imu, gnss)
    cut = max(1, min(len(imu) - 1, int(cut_fraction * len(imu))))
    t_cut = imu.t_s[cut - 1]
    nav = navigator()
    # the GNSS epochs valid up to the first piece's last sample go with it
    t_next, t_end = imu.t_s[cut], imu.t_s[-1]

    def piece(rec, t0, t1):
        return rec.slice(t0, t1) if np.any((rec.t_s >= t0) & (rec.t_s <= t1)) else None
    a = nav.run(imu.slice(imu.t_s[0], t_cut), piece(gnss, imu.t_s[0], t_cut))
    b = nav.run(imu.slice(t_next, t_end), piece(gnss, np.nextafter(t_cut, np.inf), t_end))
    for name in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m"):
        np.testing.assert_array_equal(np.concatenate([getattr(a, name), getattr(b, name)]),
                                      getattr(whole, name), err_msg=f"cut at {cut}: {name}")
