"""``gfins noise`` and ``gfins integrate --noise-file``: a simulated static record of a
consumer MEMS IMU -> the command's noise block -> the filter configured from it on
simulated drives with the same IMU: the average NEES inside its chi-square band (issue
23's acceptance, reduced: 10 seeded runs), while a noise block that understates the
noise 3x is outside it (the check can fail). The command's outputs and refusals."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gfins_fmi.cli import main
from gfins_fmi.estimation import FilterConfig, InitialState, IntegratedNavigator
from gfins_fmi.estimation.evaluation import chi2_band, nees, state_errors
from gfins_fmi.estimation.noise_file import read_noise_file
from gfins_fmi.io import ImuRecord
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.nav.strapdown import quat_to_euler
from gfins_fmi.sim.scenarios import simulate_drive, town_drive
from gfins_fmi.sim.vehicle import GnssReceiver, simulate_vehicle

#: the IMU of the chain: a consumer MEMS (white noise, Gauss-Markov biases of 100 s)
IMU = ImuNoise(gyro_arw_deg_sqrt_h=0.3, gyro_bias_instability_deg_h=10.0, gyro_correlation_time_s=100.0,
               accel_vrw_ug_sqrt_hz=100.0, accel_bias_instability_ug=300.0, accel_correlation_time_s=100.0)


@pytest.fixture(scope="module")
def identified(tmp_path_factory):
    """2 hours at rest at 50 Hz (seed 5) through `gfins noise`."""
    d = tmp_path_factory.mktemp("noise")
    dt = 0.02
    n = int(2 * 3600 / dt)
    g, a = IMU.sample(n, dt, np.random.default_rng(5))
    t = np.arange(1, n + 1) * dt
    ImuRecord(t, g * dt, (a + [0.0, 0.0, 9.8]) * dt, "increments", "static, 2 h").to_csv(d / "static.csv")
    code = main(["noise", str(d / "static.csv"), "--output", str(d / "noise.toml"), "--table",
                 str(d / "adev.csv"), "--plot", str(d)])
    assert code == 0
    return d


def test_noise_command_writes_block_table_and_figure(identified, capsys):
    d = identified
    m = read_noise_file(d / "noise.toml")
    # the white terms within 3% of the simulated ones (2 h: 360000 samples; spread 0.2%)
    assert m.gyro_arw_deg_sqrt_h == pytest.approx(0.3, rel=0.03)
    assert m.accel_vrw_ug_sqrt_hz == pytest.approx(100.0, rel=0.03)
    assert (d / "allan.png").stat().st_size > 10000
    head = (d / "adev.csv").read_text().splitlines()[0]
    assert head.startswith("tau_s,n_terms,adev_gyro_x_rad_s")


def _runs(cfg, seeds, prof, T, rx, truth):
    acc = None
    for seed in seeds:
        d = simulate_drive(prof, T, 0.01, imu=IMU, gnss=rx, seed=300 + seed, truth=truth)
        init = InitialState(d.initial, position_std_m=(1.0, 1.0, 2.0), velocity_std_m_s=0.1,
                            attitude_std_rad=(0.005, 0.005, 0.02))
        sol = IntegratedNavigator(cfg, init).run(d.imu, d.gnss, smoother=True)   # keeps the epochs
        e = state_errors(sol.epochs, d.truth, d.gyro_bias_rad_s, d.accel_bias_m_s2)
        v = nees(sol.epochs, e)
        acc = v if acc is None else acc + v
    return acc / len(seeds), sol.epochs["t_s"]


def test_filter_from_the_identified_block_is_consistent(identified):
    """10 seeded 300 s drives (1 Hz GNSS, 1 m / 0.05 m/s), the filter configured from the
    file: the average NEES (15 states) inside its 95% chi-square band at >= 80% of the
    epochs after 60 s (the band is for 10 runs; the full study's criterion is 90% over
    100 runs: bench/study_consistency.py); with the noise understated 3x (the file's
    densities and bias stds / 3), fewer than 20% inside."""
    T = 300.0
    prof = town_drive(T)
    rx = GnssReceiver(rate_hz=1.0, offset_s=0.37, pos_std_m=(1.0, 1.0, 2.0), vel_std_m_s=(0.05, 0.05, 0.1))
    truth = simulate_vehicle(prof, T, 0.01)
    model = read_noise_file(identified / "noise.toml")
    lo, hi = chi2_band(15, 10)
    mean, t = _runs(FilterConfig(imu=model, gate_probability=None), range(10), prof, T, rx, truth)
    inside = np.mean((mean[t > 60] >= lo) & (mean[t > 60] <= hi))
    assert inside >= 0.8, (inside, np.median(mean[t > 60]), lo, hi)
    low = dataclasses.replace(model, gyro_arw_deg_sqrt_h=model.gyro_arw_deg_sqrt_h / 3,
                              accel_vrw_ug_sqrt_hz=model.accel_vrw_ug_sqrt_hz / 3,
                              gyro_bias_instability_deg_h=model.gyro_bias_instability_deg_h / 3,
                              accel_bias_instability_ug=model.accel_bias_instability_ug / 3)
    mean3, t = _runs(FilterConfig(imu=low, gate_probability=None), range(10), prof, T, rx, truth)
    assert np.mean((mean3[t > 60] >= lo) & (mean3[t > 60] <= hi)) < 0.2


def test_integrate_reads_the_noise_file(identified, tmp_path, capsys):
    """`gfins integrate --noise-file` runs a drive with the block (exit 0, the difference
    to GNSS printed); --noise with --noise-file is refused at parse time. (Not with
    --truth: `integrate --truth TRUTH.csv` stops after writing its outputs, a failure of
    the TruthRecord path of estimation.evaluation that the golden outputs record as exit
    2 -- reported, not this issue's.)"""
    T = 120.0
    d = simulate_drive(town_drive(T), T, 0.01, imu=IMU, gnss=GnssReceiver(rate_hz=1.0), seed=2)
    d.imu.to_csv(tmp_path / "imu.csv")
    d.gnss.to_csv(tmp_path / "gnss.csv")
    tr = d.truth
    e = [float(x) for x in np.degrees(quat_to_euler(tr.q_bn[0]))]
    p0 = [float(np.degrees(tr.lat_rad[0])), float(np.degrees(tr.lon_rad[0])), float(tr.h_m[0])]
    ini = f"--initial={p0[0]!r},{p0[1]!r},{p0[2]!r},{e[0]!r},{e[1]!r},{e[2]!r}"
    args = ["integrate", str(tmp_path / "imu.csv"), str(tmp_path / "gnss.csv"), str(tmp_path / "out.csv"),
            "--imu-format", "csv", "--gnss-format", "csv", ini, "--noise-file", str(identified / "noise.toml")]
    assert main(args) == 0
    assert "residuals to the GNSS fixes used" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(args + ["--noise", "0.3,100,10,300,100"])
    assert "--noise or --noise-file" in capsys.readouterr().err


def test_noise_command_refusals(tmp_path, capsys):
    t = np.arange(1, 101) * 0.01
    t[50:] += 0.5                                 # a gap
    ImuRecord(t, np.zeros((100, 3)), np.zeros((100, 3)), "rates").to_csv(tmp_path / "gap.csv")
    assert main(["noise", str(tmp_path / "gap.csv")]) == 2
    assert "uniform sampling" in capsys.readouterr().err
    (tmp_path / "other.csv").write_text("a,b\n1,2\n3,4\n")
    assert main(["noise", str(tmp_path / "other.csv")]) == 2
    assert "not an ImuRecord" in capsys.readouterr().err
