"""EKF and UKF of the integrated navigator on a linear problem: measurements that are
linear in the error state (GNSS position and velocity at the IMU, no lever arm; barometric
height) and errors small enough that the mechanization is linear over them (start errors
of centimetres and tenths of a milliradian, a quiet IMU, exact data). There the unscented
transform is exact for any spread whose weights are right, so

- the UKF run with three different spreads (alpha, beta, kappa) gives the same filter to
  the second-order terms of the mechanization over these errors: a weight or a spread
  slip (weights that no longer sum to one, outer weights that do not match the points'
  spread) changes the covariances by tens of per cent;
- the EKF agrees with the UKF at every update, within what the EKF linearises (its
  transition over each 10 ms step: I + F T, F at the step's end, against the UKF's
  mechanization of each point).

Truth: the closed-form truth of tests/support/drives.py (exact increments and GNSS), and
the two filters against each other; the tolerances are the measured differences with a
margin (figures in each test).
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.estimation import InitialState, IntegratedNavigator
from support.drives import Rec, drive, gnss_record, quiet_config

#: (ukf_alpha, ukf_beta, ukf_kappa): the default, a wide and a narrow spread
SPREADS = {"default": (0.5, 2.0, 0.0), "wide": (1.0, 0.0, 1.0), "narrow": (0.2, 2.0, 0.0)}


@pytest.fixture(scope="module")
def runs():
    tr, imu = drive(60.0)
    gnss = gnss_record(tr, np.arange(1003, len(tr.t_s), 1000), std=(0.02, 0.03, 0.05), vstd=0.01)
    kb = np.arange(1057, len(tr.t_s), 100)
    baro = Rec(t_s=tr.t_s[kb].copy(), h_m=tr.h_m[kb].copy(), std_m=np.full(len(kb), 0.05))
    init = InitialState(gf.NavState.from_trajectory(tr, 0), position_std_m=(0.02, 0.03, 0.04),
                        velocity_std_m_s=(0.01, 0.012, 0.014), attitude_std_rad=(2e-4, 3e-4, 1e-3))
    out = {"ekf": IntegratedNavigator(quiet_config(propagation_interval_s=0.0), init).run(imu, gnss, baro)}
    for name, (a, b, k) in SPREADS.items():
        cfg = quiet_config(propagation_interval_s=0.0, filter="ukf", ukf_alpha=a, ukf_beta=b,
                           ukf_kappa=k)
        out[name] = IntegratedNavigator(cfg, init).run(imu, gnss, baro)
    return out


def _compare(a, b):
    """Per update: |r_a - r_b| / s_std and |s_std_a / s_std_b - 1| over the rows each
    update uses, |NIS_a - NIS_b|; per IMU row: |std_a / std_b - 1| and the horizontal
    position difference in units of the north std."""
    ia, ib = a.innovations, b.innovations
    assert len(ia) == len(ib) > 100
    assert np.array_equal(ia["type"], ib["type"]) and np.array_equal(ia["status"], ib["status"])
    assert set(np.unique(ia["type"]).tolist()) == {1, 2, 3}       # GNSS position, velocity, baro
    used = np.arange(3)[None, :] < ia["m"][:, None]
    dr = np.abs(ia["r"][used] - ib["r"][used]) / ia["s_std"][used]
    ds = np.abs(ia["s_std"][used] / ib["s_std"][used] - 1)
    dn = np.abs(ia["nis"] - ib["nis"])
    dstd = np.abs(a.std / b.std - 1)
    dpos = np.abs(a.lat_rad - b.lat_rad) * 6.37e6 / a.std[:, 4]
    return dr.max(), ds.max(), dn.max(), dstd.max(), dpos.max()


@pytest.mark.parametrize("spread", ["wide", "narrow"])
def test_ukf_does_not_depend_on_its_spread(runs, spread):
    """Default spread against a wide (alpha 1, beta 0, kappa 1) and a narrow (alpha 0.2)
    one: measured, wide / narrow, residuals 7e-6 / 3.5e-5 sigma, innovation stds 3e-7 /
    9e-7, state stds 2e-6 / 4e-6 relative, positions 7e-6 / 2.7e-5 sigma (the points
    reach the mechanization's curvature in proportion to the spread). Bounds: 1e-4 sigma
    and 1e-5 relative, 3 to 30 times those; a weight slip moves the stds by > 10%."""
    dr, ds, dn, dstd, dpos = _compare(runs["default"], runs[spread])
    assert dr < 1e-4 and dpos < 1e-4, (dr, dpos)
    assert ds < 1e-5 and dstd < 1e-5, (ds, dstd)
    assert dn < 1e-4, dn


def test_ekf_agrees_with_the_ukf_at_every_update(runs):
    """EKF against the default UKF: measured residuals 2.2e-4 sigma, innovation stds 2.3e-4
    and state stds 2.6e-3 relative (the largest on the heading, which these measurements
    see only through the turns), NIS 4.4e-6, positions 3.2e-4 sigma: the EKF's first-order
    transition per 10 ms step (the second-order term T^2 F^2 / 2 is dropped up to 20 ms,
    gf_ins_gnss.h) against the UKF's mechanization of each point. Bounds: 1e-3 sigma, 1e-3
    and 1e-2 relative, 1e-4 on the NIS (4 to 20 times those)."""
    dr, ds, dn, dstd, dpos = _compare(runs["ekf"], runs["default"])
    assert dr < 1e-3 and dpos < 1e-3, (dr, dpos)
    assert ds < 1e-3, ds
    assert dstd < 1e-2, dstd
    assert dn < 1e-4, dn
