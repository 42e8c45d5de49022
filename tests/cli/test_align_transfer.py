"""``gfins align transfer SLAVE_IMU MASTER_NAV``: a simulated scenario written by
--simulate and aligned (velocity+attitude: converged, exit 0, the estimates over time
and the figure written, the truth's errors printed), the same master as a KF-GINS .nav
file without rates (velocity only: the mounting derived, not converged: exit 1, outputs
written all the same), and bad input (no master, a master that does not cover the
slave: exit 2 with what to do). Truth: the simulator's installation and biases
(tests/estimation/test_transfer.py checks the filter against it in detail).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from gfins_fmi.io.columns import TRANSFER_COLUMNS
from gfins_fmi.io.navigation import read_navigation

ARCMIN = np.pi / 180 / 60


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """40 s simulated by the command itself (--simulate), aligned with attitude matching."""
    from gfins_fmi.cli import main
    d = tmp_path_factory.mktemp("transfer")
    slave, master = d / "slave.csv", d / "master.csv"
    rc = main(["align", "transfer", str(slave), str(master), "--simulate", "40", "--gyro-bias", "200",
               "--accel-bias", "3000", "--truth", str(d / "slave.csv.truth.csv"), "--truth-json",
               str(d / "slave.csv.truth.json"), "--master-att-bias", "0.0003,0.0167", "--tolerance", "2", "--output",
               str(d / "est.csv"), "--plot", str(d / "fig.png")])
    return d, rc


def test_simulated_scenario_aligns(simulated, capsys):
    """The mounting within 3 sigma of the truth at every row (the truth JSON's 20, -15, 25
    arcmin), exit 0 (its heading and roll 1-sigma below --tolerance 2' after 40 s: 0.16',
    1.3'; 1' takes ~100 s with these default master stds), the estimates over time with
    the TRANSFER_COLUMNS, the figure."""
    d, rc = simulated
    assert rc == 0
    truth = json.loads((d / "slave.csv.truth.json").read_text())
    assert truth["mount_deg"] == pytest.approx([20 / 60, -15 / 60, 25 / 60])
    names = (d / "est.csv").read_text().splitlines()[0].split(",")
    assert tuple(names) == TRANSFER_COLUMNS
    est = np.loadtxt(d / "est.csv", delimiter=",", skiprows=1)
    mount, std = est[:, 1:4], est[:, 4:7]
    assert np.all(np.abs(mount - truth["mount_deg"]) <= 3 * std)
    assert std[-1, 0] * 60 < 2.0 and std[-1, 2] * 60 < 2.0
    assert (d / "fig.png").stat().st_size > 10_000
    master, rates = read_navigation(d / "master.csv")
    assert rates is not None and len(master.t_s) == len(rates)


def test_kfgins_master_velocity_only(simulated, tmp_path, capsys):
    """The master as a KF-GINS .nav (no rate columns: its rate from its attitude) and
    velocity-only matching: the mounting derived from the attitudes, not converged in 40 s
    (1-sigma of arcminutes): exit 1, the estimates written all the same."""
    from gfins_fmi.cli import main
    d, _ = simulated
    m, _ = read_navigation(d / "master.csv")
    deg = 180 / np.pi
    nav = np.column_stack([np.zeros(len(m.t_s)), m.t_s, m.lat_rad * deg, m.lon_rad * deg, m.h_m,
                           m.v_enu_m_s[:, 1], m.v_enu_m_s[:, 0], -m.v_enu_m_s[:, 2],
                           m.euler_rad[:, 2] * deg, m.euler_rad[:, 1] * deg, m.euler_rad[:, 0] * deg])
    np.savetxt(tmp_path / "master.nav", nav, fmt="%.12f")
    capsys.readouterr()
    rc = main(["align", "transfer", str(d / "slave.csv"), str(tmp_path / "master.nav"), "--matching", "velocity",
               "--gyro-bias", "200", "--accel-bias", "3000", "--output", str(tmp_path / "est.csv")])
    cap = capsys.readouterr()
    assert rc == 1 and "not converged" in cap.err and (tmp_path / "est.csv").exists(), cap
    assert "taken from its attitude" in cap.out and "rotation between the slave's estimated attitude" in cap.out


def test_bad_input(simulated, tmp_path, capsys):
    from gfins_fmi.cli import main
    d, _ = simulated
    with pytest.raises(SystemExit):
        main(["align", "transfer", str(d / "slave.csv")])
    capsys.readouterr()
    m, r = read_navigation(d / "master.csv")
    from gfins_fmi.io.navigation import write_navigation
    late = type(m)(m.t_s[100:], m.lat_rad[100:], m.lon_rad[100:], m.h_m[100:], m.v_enu_m_s[100:], m.euler_rad[100:])
    write_navigation(tmp_path / "late.csv", late, r[100:])
    rc = main(["align", "transfer", str(d / "slave.csv"), str(tmp_path / "late.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "must cover the slave record's start" in err, err
    (tmp_path / "cols.csv").write_text("t_s,lat_deg\n0,1\n")
    rc = main(["align", "transfer", str(d / "slave.csv"), str(tmp_path / "cols.csv")])
    err = capsys.readouterr().err
    assert rc == 2 and "missing lon_deg" in err, err
    with pytest.raises(SystemExit):
        main(["align", "motion", str(d / "slave.csv"), str(d / "master.csv"), "--initial", "30,114,0,0,0,0",
              "--plot", str(tmp_path / "x.png")])
