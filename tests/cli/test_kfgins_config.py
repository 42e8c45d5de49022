"""``gfins integrate --kfgins-config``: KF-GINS's std file complete, and every key of a
KF-GINS configuration either used or named (issue 20, "What to build" 1).

A simulated 40 s drive at 200 Hz (navigation-grade increments, 1 Hz GNSS) written as
KF-GINS's files, with a configuration whose initial sensor 1-sigma differ per axis so that
an axis or unit mix-up shows. Truths: KF-GINS's own writer (src/kf_gins.cpp ``writeSTD``:
sqrt of the covariance diagonal, deg/h, mGal, ppm, forward-right-down) computed here by
hand from the filter's covariance (IntegratedNavigator.covariance), never from the writer
under test.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from gfins_fmi.cli import main
from gfins_fmi.cli.kfgins_config import kfgins_config_text
from support.drives import kfgins_drive

LEVER = np.array([-0.3, 0.2, 1.2])      # body right, front, up, m
#: initial 1-sigma per axis as a KF-GINS user types them (forward, right, down)
BG_STD, BA_STD, SG_STD, SA_STD = (1.0, 2.0, 3.0), (40.0, 50.0, 60.0), (100.0, 200.0, 300.0), (400.0, 500.0, 600.0)
R2D = 180.0 / np.pi


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kfgins_drive")
    d = kfgins_drive(folder, 40.0, 11, LEVER)
    return folder, d


def _yaml(folder, d, out, noise=None, extra=""):
    """A KF-GINS configuration of the drive (KF-GINS's keys, frames and units): the true
    initial state, the demo configuration's noise (``noise`` replaces keys), the initial
    sensor 1-sigma per axis."""
    tr = d.truth
    n = dict(arw=[0.003] * 3, vrw=[0.03] * 3, gbstd=[0.027] * 3, abstd=[15.0] * 3, gsstd=[300.0] * 3,
             asstd=[300.0] * 3)
    n.update(noise or {})
    n["corrtime"] = 4.0
    return kfgins_config_text(folder / "imu.txt", folder / "gnss.txt", out, float(d.imu.t_s[0]) - 0.005,
                              tr.lat_rad[0], tr.lon_rad[0], tr.h_m[0], tr.v_n_m_s[0], tr.euler_rad[0], LEVER, n,
                              sensor_std={"initbgstd": BG_STD, "initbastd": BA_STD, "initsgstd": SG_STD,
                                          "initsastd": SA_STD}, extra=extra)


def _kfgins_std_by_hand(P) -> np.ndarray:
    """KF-GINS's writeSTD columns 10..21 from our covariance (states: dv ENU, dpos, phi ENU,
    bg xyz, ba xyz, sg xyz, sa xyz; body x right, y front, z up): sqrt of the diagonal,
    forward (our y), right (x), down (z), rad/s -> deg/h, m/s^2 -> mGal, 1 -> ppm."""
    s = np.sqrt(np.diag(P))
    frd = [1, 0, 2]
    return np.r_[s[9:12][frd] * R2D * 3600.0, s[12:15][frd] * 1e5, s[15:18][frd] * 1e6, s[18:21][frd] * 1e6]


def test_std_file_has_the_sensor_sigmas_in_kfgins_units_and_axes(drive, tmp_path, capsys):
    """Before: KF_GINS_STD.txt's 12 sensor columns were NaN. Now the filter's 1-sigma of
    the biases and scale factors, in KF-GINS's units and axis order: the first row is the
    configuration's initial 1-sigma per axis (as typed), the last equals the filter's
    covariance after the same run through the Python API, converted by hand; no NaN.
    The streamed run (chunks) and the whole record (--smooth) write the same file."""
    from gfins_fmi import io
    from gfins_fmi.cli.kfgins_config import initial_state, read_kfgins_config
    from gfins_fmi.estimation import FilterConfig, IntegratedNavigator
    from gfins_fmi.estimation.config import SENSOR_NAMES
    folder, d = drive
    files = {}
    for how, extra in (("chunks", []), ("whole", ["--smooth"])):
        out = tmp_path / how
        out.mkdir()
        cfg_path = tmp_path / f"{how}.yaml"
        cfg_path.write_text(_yaml(folder, d, out))
        assert main(["integrate", "--kfgins-config", str(cfg_path), *extra]) == 0
        capsys.readouterr()
        files[how] = (out / "KF_GINS_STD.txt").read_bytes()
    assert files["chunks"] == files["whole"]
    std = np.loadtxt(tmp_path / "chunks" / "KF_GINS_STD.txt")
    assert std.shape[1] == 22 and np.all(np.isfinite(std)), "a NaN or missing column in KF_GINS_STD.txt"
    # one 5 ms step after the start: the Gauss-Markov states' 1-sigma move by ~dt/tau (4 h) and
    # no GNSS fix has yet been used: the initial values to 1e-4 relative
    np.testing.assert_allclose(std[0, 10:], np.r_[BG_STD, BA_STD, SG_STD, SA_STD], rtol=1e-4)
    # the last row against the API's covariance after the same run (same reading, same filter)
    kf = read_kfgins_config(tmp_path / "chunks.yaml")
    imu = io.read_kfgins_imu(folder / "imu.txt")
    gnss = io.read_kfgins_gnss(folder / "gnss.txt")
    sel = imu.t_s > imu.t_s[0]
    rec = io.ImuRecord(t_s=imu.t_s[sel], gyro=imu.gyro[sel], accel=imu.accel[sel], kind="increments")
    cfg = FilterConfig(imu=kf.noise, input="increments", gnss_lever_arm_m=tuple(LEVER), scale_factors=True,
                       gyro_scale_std=300e-6, accel_scale_std=300e-6, gyro_scale_tau_s=4 * 3600.0,
                       accel_scale_tau_s=4 * 3600.0)
    nav = IntegratedNavigator(cfg, initial_state(kf, float(imu.t_s[0]), len(SENSOR_NAMES)))
    sol = nav.run(rec, gnss)
    assert float(sol.t_s[-1]) == pytest.approx(std[-1, 0], abs=1e-9)
    # 9 decimals in the file: at most 5e-10 of rounding, and the same C filter
    np.testing.assert_allclose(std[-1, 10:], _kfgins_std_by_hand(nav.covariance), rtol=0, atol=1e-9)
    # the GNSS fixes made the horizontal accelerometer biases observable: their 1-sigma fell
    assert np.all(std[-1, 13:15] < 0.9 * np.array(BA_STD[:2])), std[-1, 13:15]


def test_per_axis_noise_and_unused_keys_are_named(tmp_path):
    """Before: the largest axis of each imunoise value was taken silently, and keys KF-GINS
    forks add (odometer noise, lever arms) were ignored without a word. Now a warning names
    the key, its three values and the one used; another warning names every key that is
    not KF-GINS's (with the odometer options for odometer keys); the keys that map
    differently (initattstd, imudatarate) are stated in the notes."""
    from gfins_fmi.cli.kfgins_config import read_kfgins_config

    class _D:   # the few fields _yaml reads: a drive at rest
        class truth:
            euler_rad = np.array([[0.5, 0.01, -0.02]])
            v_n_m_s = np.zeros((1, 3))
            lat_rad, lon_rad, h_m = np.array([0.5]), np.array([2.0]), np.array([20.0])

        class imu:
            t_s = np.array([100.0])

    text = _yaml(tmp_path, _D, tmp_path, noise={"arw": [0.003, 0.004, 0.005]},
                 extra="odonoise: [ 0.1 ]\nodolever: [ 1.0, 0.5, 0.3 ]\n")
    text = text.replace("  corrtime: 4.0", "  corrtime: 4.0\n  rrw: [ 0.1, 0.1, 0.1 ]")
    (tmp_path / "k.yaml").write_text(text)
    with pytest.warns(UserWarning) as caught:
        run = read_kfgins_config(tmp_path / "k.yaml")
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2, messages
    per_axis = next(m for m in messages if "imunoise.arw" in m)
    assert "0.003, 0.004, 0.005 deg/sqrt(h)" in per_axis and "it uses the largest, 0.005 deg/sqrt(h)" in per_axis
    assert run.noise.gyro_arw_deg_sqrt_h == 0.005
    unused = next(m for m in messages if "not used" in m)
    assert "odonoise, odolever, imunoise.rrw" in unused and "--odometer ODO.csv" in unused, unused
    assert any(n.startswith("initattstd roll 0.003, pitch 0.003 deg") for n in run.notes), run.notes
    assert any(n.startswith("imudatarate 200 Hz: not needed") for n in run.notes), run.notes
    # the per-axis initial 1-sigma are kept per axis (forward, right, down -> right, front, up)
    assert run.sensor_std["gyro_scale_std"] == pytest.approx((200e-6, 100e-6, 300e-6))
    assert run.sensor_std["accel_bias_std_m_s2"] == pytest.approx((50e-5, 40e-5, 60e-5))
    # KF-GINS's own configuration, every key of dataset/kf-gins.yaml: not one warning
    (tmp_path / "clean.yaml").write_text(_yaml(tmp_path, _D, tmp_path))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_kfgins_config(tmp_path / "clean.yaml")


def test_the_command_prints_the_warnings_and_notes(drive, tmp_path, capsys):
    """Through the command: the warnings as `gfins integrate: warning:` lines, the notes
    on the standard output, and the run goes on (exit 0)."""
    folder, d = drive
    out = tmp_path / "out"
    out.mkdir()
    cfg = tmp_path / "k.yaml"
    cfg.write_text(_yaml(folder, d, out, noise={"vrw": [0.03, 0.03, 0.05]}, extra="odolever: [ 1, 0, 0 ]\n"))
    assert main(["integrate", "--kfgins-config", str(cfg)]) == 0
    cap = capsys.readouterr()
    assert "gfins integrate: warning: " in cap.err and "imunoise.vrw" in cap.err and "odolever" in cap.err, cap.err
    assert "KF-GINS configuration: initattstd roll 0.003, pitch 0.003 deg" in cap.out, cap.out


def test_the_run_records_how_the_keys_were_mapped(drive, tmp_path, capsys):
    """KF_GINS.config.json, what the run used, holds the mapping notes and the options'
    units, so a run's record says how KF-GINS's keys were read."""
    import json
    folder, d = drive
    out = tmp_path / "out"
    out.mkdir()
    cfg = tmp_path / "k.yaml"
    cfg.write_text(_yaml(folder, d, out))
    assert main(["integrate", "--kfgins-config", str(cfg)]) == 0
    capsys.readouterr()
    doc = json.loads((out / "KF_GINS.config.json").read_text())
    assert any(n.startswith("initattstd roll 0.003, pitch 0.003 deg") for n in doc["kfgins_notes"]), doc
    assert doc["units"]["propagation_interval"] == "s" and doc["inputs"]["imu"]["bytes"] > 0


def test_written_configuration_reads_back(tmp_path):
    """kfgins_config_text (the reader's inverse, used by the tests and the benchmark) and
    read_kfgins_config agree: the initial state, lever arm and noise read back as written
    (frames and units converted twice: to round-off, 1e-12 relative)."""
    from gfins_fmi.cli.kfgins_config import kfgins_noise_block, read_kfgins_config
    from gfins_fmi.sim.scenarios import NAVIGATION
    lat, lon, h, v, e = 0.52, 2.0, 31.5, (3.0, -4.0, 0.2), (2.5, 0.03, -0.02)
    (tmp_path / "out").mkdir()
    cfg = tmp_path / "kf.yaml"
    cfg.write_text(kfgins_config_text(tmp_path / "imu.txt", tmp_path / "gnss.txt", tmp_path / "out", 12.5, lat, lon,
                                      h, v, e, LEVER, kfgins_noise_block(NAVIGATION)))
    run = read_kfgins_config(cfg)
    lat2, lon2, h2, v2, e2 = run.nav0
    np.testing.assert_allclose([lat2, lon2, h2, *v2], [lat, lon, h, *v], rtol=1e-12)
    # heading 2.5 rad comes back as yaw in (-pi, pi]
    np.testing.assert_allclose(np.angle(np.exp(1j * np.asarray(e2))), np.angle(np.exp(1j * np.asarray(e))), rtol=1e-12)
    np.testing.assert_allclose(run.lever_arm_m, LEVER, rtol=1e-12)
    assert run.start_s == 12.5 and run.end_s is None
    for name in ("gyro_arw_deg_sqrt_h", "accel_vrw_ug_sqrt_hz", "gyro_bias_instability_deg_h",
                 "accel_bias_instability_ug", "gyro_correlation_time_s"):
        assert getattr(run.noise, name) == pytest.approx(getattr(NAVIGATION, name), rel=1e-12), name
