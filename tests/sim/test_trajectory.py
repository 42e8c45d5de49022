"""The closed-form motions (gfins_fmi.sim.trajectory): the body rate is the attitude's
derivative, the vehicle run's profile, the airdrop's velocity is its position's derivative,
an array's outputs riding a motion.
"""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.nav import earth
from support.truth import numpy_outputs


def test_generator_body_rate_is_the_attitude_derivative():
    """w_nb^b of the generator against the complex-step derivative of its attitude
    (exact to round-off for analytic functions; independent of the rate formula)."""
    m = tj.SineVelocity()
    t = np.linspace(0, 100, 37)
    h = 1e-30
    (psi, th, ga), _ = m.euler(t + 1j * h)
    qc = earth.euler_to_quat(psi, th, ga)                  # complex quaternion
    dq = qc.imag / h
    q, w = m.attitude(t)
    conj = q * np.array([1, -1, -1, -1])
    w_ref = 2 * earth.quat_multiply(conj, dq)[:, 1:]
    np.testing.assert_allclose(w, w_ref, atol=1e-16)


def test_vehicle_run_profile():
    """Seed 001's run: still during alignment, then 15 m/s, heading turned by 180 deg
    twice, ending on the starting heading."""
    m = tj.VehicleRun()
    tr = tj.sample(m, 600.0 + 20.0 + 700.0, 0.1)
    speed = np.linalg.norm(tr.v_n_m_s, axis=1)
    assert np.all(speed[tr.t_s < 600.0] < 1e-9)
    cruise = (tr.t_s > 630.0)
    # displacements map to latitude/longitude with the reference point's radii, so the
    # east speed scales with cos(L0)/cos(L): tan(L0) dL ~ 3e-4 after 3.6 km of northing
    assert np.allclose(speed[cruise], 15.0, rtol=1e-3, atol=0)
    psi = gf.quat_to_euler(tr.q_bn)[:, 0]
    at = lambda t: psi[np.argmin(np.abs(tr.t_s - t))]   # noqa: E731
    assert at(700.0) == pytest.approx(0.0, abs=1e-9) or at(700.0) == pytest.approx(2 * np.pi, abs=1e-9)
    assert at(1000.0) == pytest.approx(np.pi, abs=1e-9)
    assert min(at(1300.0), 2 * np.pi - at(1300.0)) == pytest.approx(0.0, abs=1e-9)


def test_airdrop_velocity_is_the_position_derivative():
    """Complex-step derivative of the generator's closed-form position equals its
    velocity formula (exact to round-off; no finite differences involved)."""
    m = tj.Airdrop()
    t = np.linspace(0.0, 60.0, 25)
    (L, lam, h), (dL, dlam, dh), _ = m.position(t)
    (Lc, lamc, hc), _, _ = m.position(t + 1e-30j)
    np.testing.assert_allclose(np.imag(Lc) / 1e-30, dL, rtol=1e-13, atol=1e-20)
    np.testing.assert_allclose(np.imag(hc) / 1e-30, dh, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("motion", [tj.SineVelocity(), tj.Circle(), tj.Airdrop(), tj.Coning()],
                         ids=["sine", "circle", "airdrop", "coning"])
def test_generator_array_outputs(motion):
    """Accelerometer-array outputs of a trajectory: the 9-accelerometer solver gives back
    the trajectory's own w_ib^b and f^b (round-off, as in test_accel9), and the angular
    acceleration (complex step) agrees with a central difference of the rates to that
    difference's truncation error, (W dt)^2/6 relative at the highest frequency W."""
    dt = 0.01
    tr = tj.sample(motion, 30.0, dt)
    wd = motion.gyro_dot(tr.t_s)
    cd = (tr.gyro_rad_s[2:] - tr.gyro_rad_s[:-2]) / (2 * dt)
    # highest angular frequency in the rates: coning 5 Hz; airdrop swing 2 pi/6 s rad/s
    # (x1.5 margin covers the other motions' slower terms)
    W = 2 * np.pi * 5.0 if isinstance(motion, tj.Coning) else 2 * np.pi / 6.0 * 1.5
    assert np.abs(wd[1:-1] - cd).max() <= 2 * (W * dt) ** 2 / 6 * np.abs(wd).max()
    g = gf.accel9_geometry(0.1)
    A = tr.array_outputs(g)
    # the trajectory's array outputs = the independent numpy forward model
    A_ref = numpy_outputs(g.u_m, g.theta, tr.accel_m_s2, tr.gyro_rad_s, wd)
    assert np.abs(A - A_ref).max() <= 64 * np.finfo(float).eps * np.abs(A_ref).max()
    sol = gf.solve_accel9(A, dt, 0.1, tr.gyro_rad_s[0])
    S = np.abs(A).max()
    eps = np.finfo(float).eps
    assert np.abs(sol.f_m_s2 - tr.accel_m_s2).max() <= 64 * eps * S
    assert np.abs(sol.omega_dot_rad_s2 - wd).max() <= 64 * eps * S / 0.1
    big = np.abs(tr.gyro_rad_s) > 1e-3
    tol = 64 * eps * S / 0.1 / (2 * np.maximum(np.abs(tr.gyro_rad_s), 1e-3))
    assert np.all((np.abs(sol.omega_rad_s - tr.gyro_rad_s) <= tol)[big])
