"""The transfer-alignment FMU (gfins_transfer_align, issue 24): equal to the batch API
(gfins_fmi.estimation.transfer.transfer_align) bit for bit in FMI 2.0 and 3.0, its
parameters refused by name, and a co-simulation of a host (vehicle FMU), its master INS
(SINS FMU) and a slave IMU (a second vehicle FMU) feeding it, under our Python master and
under OSP libcosim (equal bit for bit: two Jacobi masters on one clock, as
tests/fmi/test_osp.py), the mounting found.

Truth: the batch API on the same samples (the FMU makes the gf_ins_step calls gf_ins_run
makes); for the co-simulation, the mounting the slave's vehicle FMU was given."""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.estimation import FilterConfig
from gfins_fmi.estimation.transfer import MasterErrors, slave_initial_state, transfer_align
from gfins_fmi.fmi import osp
from gfins_fmi.fmi.master import CoSimulation
from gfins_fmi.fmi.paths import FmuRunError
from gfins_fmi.fmi.system import vehicle_transfer_alignment
from gfins_fmi.fmi.transfer import run_transfer_fmu
from gfins_fmi.sim.transfer import MEMS_SLAVE, SlaveInstallation, simulate_transfer

ARCMIN = np.pi / 180 / 60
ERRORS = MasterErrors((0.015, 0.015, 0.005), 2e-5, 1.0)


@pytest.fixture(scope="module")
def scenario():
    inst = SlaveInstallation((20 * ARCMIN, -15 * ARCMIN, 25 * ARCMIN), (0.1, 0.0, -0.05), 0.015,
                             flexure_std_rad=2e-4, flexure_tau_s=0.5)
    sc = simulate_transfer(8.0, installation=inst, seed=4)
    cfg = FilterConfig(imu=MEMS_SLAVE, master_mount=True, master_lever=True, master_time_offset=True,
                       flexure=True, flexure_std_rad=2e-4, flexure_tau_s=0.5)
    init = slave_initial_state(sc.master, sc.master_rate_rad_s, sc.slave_imu.t_s[0] - 0.01, cfg,
                               gyro_bias_std_rad_s=1e-3, accel_bias_std_m_s2=0.03)
    return sc, cfg, init


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("matching, position", [("velocity+attitude", True), ("velocity", False)])
def test_fmu_equals_the_batch_api_bit_for_bit(scenario, version, matching, position):
    sc, cfg, init = scenario
    ref = transfer_align(sc.slave_imu, sc.master, config=cfg, master_rate_rad_s=sc.master_rate_rad_s,
                         matching=matching, position=position, master_errors=ERRORS, initial=init)
    out = run_transfer_fmu(sc.slave_imu, sc.master, sc.master_rate_rad_s, config=cfg, initial=init,
                           matching=matching, position=position, master_errors=ERRORS, fmi_version=version)
    sol = ref.solution
    assert np.array_equal(out["q"], sol.q_bn) and np.array_equal(out["v"], sol.v_n_m_s)
    assert np.array_equal(out["lat"][:, 0], sol.lat_rad) and np.array_equal(out["std"], sol.std)
    assert np.array_equal(out["sensors"], sol.sensors)
    assert np.array_equal(out["lever"], ref.lever_arm_m) and np.array_equal(out["lever_std"], ref.lever_std_m)
    assert np.array_equal(out["time_offset"][:, 0], ref.time_offset_s)
    assert np.array_equal(out["time_offset_std"][:, 0], ref.time_offset_std_s)
    assert np.array_equal(out["flexure_angles"], sol.transfer[:, 7:10])
    if matching == "velocity+attitude":        # velocity only: the batch API derives the mounting
        assert np.array_equal(out["mount"], ref.mount_rad) and np.array_equal(out["mount_std"], ref.mount_std_rad)


def test_refusals(scenario):
    """A parameter the core refuses is named with its value, unit and bounds (the settings
    table's message); the master's stds must be > 0."""
    sc, cfg, init = scenario
    with pytest.raises(FmuRunError, match=r"parameter master_mount_rad = \[0, 2, 0\] rad refused: must be "
                                          r"finite, the pitch"):
        run_transfer_fmu(sc.slave_imu, sc.master, sc.master_rate_rad_s, config=cfg, initial=init,
                         parameters={"master_mount_rad": [0.0, 2.0, 0.0]})
    with pytest.raises(FmuRunError, match="master_vel_std, master_att_std and master_pos_std"):
        run_transfer_fmu(sc.slave_imu, sc.master, sc.master_rate_rad_s, config=cfg, initial=init,
                         parameters={"master_vel_std": [0.01, 0.0, 0.01]})


@pytest.fixture(scope="module")
def cosim():
    """30 s: host, master INS, slave IMU mounted 20, -15, 25 arcmin off, the slave's filter."""
    system = vehicle_transfer_alignment(stop_s=30.0)
    with CoSimulation(system, fmi_version=2) as m:
        m.initialize()
        ours = m.run(points=osp.communication_points(system.step_s, 3000))
    return system, ours


def test_cosimulation_finds_the_mounting(cosim):
    """Under the Python master the slave's FMU finds the mounting its vehicle FMU was
    given, within 3 sigma plus what the vehicle's first-order model of it (I + N, a
    cross-coupling, not a rotation) leaves: |a|^2 / 2 = 0.1'; every 10 Hz epoch used."""
    system, ours = cosim
    a = np.asarray(system.sources["mount_rad"])
    est, std = ours["slave.mount"][-1], ours["slave.mount_std"][-1]
    assert np.all(np.abs(est - a) <= 3 * std + 0.1 * ARCMIN), ((est - a) / ARCMIN, std / ARCMIN)
    assert std[0] < ARCMIN and std[2] < ARCMIN
    # the epoch at the start (velocity, attitude) comes with no increment: stale by design
    # epochs at 0.1 .. 29.9 s (the last step, 29.99 s, receives the one at 29.98 s: within 0.1 s)
    assert ours["slave.n_rejected"][-1, 0] == 2 and ours["slave.n_updates"][-1, 0] == 2 * 299


@pytest.mark.skipif(osp.available() is not None, reason=osp.available() or "")
def test_libcosim_equals_the_python_master_bit_for_bit(cosim):
    system, ours = cosim
    theirs = osp.run_libcosim(system)
    assert sorted(theirs) == sorted(ours)
    for key in ours:
        assert np.array_equal(theirs[key], ours[key], equal_nan=True), key
