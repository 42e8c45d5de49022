"""The gfins command as installed (the console script): help, demo, validate, solve9,
navigate and gfnav on small records and bad samples."""
from __future__ import annotations

import shutil
import subprocess

import numpy as np

import gfins_fmi as gf
from support.truth import W0, numpy_outputs, paper_layout, smooth_motion


def run(*args, check=True):
    exe = shutil.which("gfins")
    assert exe, "the console script 'gfins' is not installed"
    proc = subprocess.run([exe, *args], capture_output=True, text=True, timeout=600)
    if check:
        assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def test_help_lists_commands():
    out = run("--help").stdout
    for cmd in ("demo", "solve9", "validate", "info"):
        assert cmd in out


def test_demo_runs_and_writes_figure(tmp_path):
    proc = run("demo", "--duration", "5", "--out", str(tmp_path))
    assert "demo passed" in proc.stdout
    assert "fmpy validate: 0 problems" in proc.stdout
    png = tmp_path / "gfins_demo.png"
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_validate_command():
    assert "0 problems" in run("validate").stdout


def test_solve9_csv_roundtrip_and_bad_sample(tmp_path):
    l, dt, n = 0.1, 0.01, 300
    u, th = paper_layout(l)
    t, f, w, wd = smooth_motion(n, dt)
    A = numpy_outputs(u, th, f, w, wd)
    src, dst = tmp_path / "a.csv", tmp_path / "sol.csv"
    np.savetxt(src, np.c_[t, A], delimiter=",", header="t,A1,...,A9", fmt="%.17g")
    run("solve9", str(src), str(dst), "--dt", str(dt), "--lever-arm", str(l),
        "--omega-init", ",".join(map(str, W0)))
    sol = np.loadtxt(dst, delimiter=",", skiprows=1)
    ref = gf.solve_accel9(A, dt, l, W0)
    assert np.array_equal(sol[:, 4:7], ref.omega_rad_s)  # %.17g round-trips doubles
    A[120, 4] = np.nan
    np.savetxt(src, A, delimiter=",", fmt="%.17g")
    proc = run("solve9", str(src), str(dst), "--dt", str(dt), "--lever-arm", str(l), check=False)
    assert proc.returncode == 1 and "A_m_s2[120, 4]" in proc.stderr
    # nothing lost, nothing mistaken: the 120 rows before it in sol.partial.csv (its first
    # line says where and why), the complete solution of the first run left as it was
    assert np.loadtxt(tmp_path / "sol.partial.csv", delimiter=",", skiprows=2).shape[0] == 120
    assert np.loadtxt(dst, delimiter=",", skiprows=1).shape[0] == n


def test_solve9_bad_arguments(tmp_path):
    src = tmp_path / "a.csv"
    np.savetxt(src, np.zeros((3, 9)), delimiter=",")
    proc = run("solve9", str(src), str(tmp_path / "o.csv"), "--dt", "0", "--lever-arm", "0.1",
               check=False)
    assert proc.returncode == 2 and "argument --dt: must be finite and > 0 s" in proc.stderr


def test_navigate_csv_and_bad_sample(tmp_path):
    """gfins navigate on a CSV of increments reproduces Strapdown.run; a NaN row stops it
    with status 1 and the rows before it in sol.partial.csv."""
    from gfins_fmi.sim import trajectory as tj
    tr = tj.sample(tj.Circle(), 30.0, 0.01)
    src, dst = tmp_path / "rec.csv", tmp_path / "sol.csv"
    rec = np.c_[tr.t_s[1:], tr.dtheta_rad, tr.dv_m_s]
    np.savetxt(src, rec, delimiter=",", header="t,gx,gy,gz,ax,ay,az", fmt="%.17g")
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    args = ["navigate", str(src), str(dst), "--header",
            "--lat0", repr(float(np.degrees(tr.lat_rad[0]))), "--lon0", repr(float(np.degrees(tr.lon_rad[0]))),
            "--h0", repr(float(tr.h_m[0])), "--heading0", repr(float(e[0])), "--pitch0", repr(float(e[1])),
            "--roll0", repr(float(e[2])), "--v0=" + ",".join(repr(float(x)) for x in tr.v_n_m_s[0])]
    run(*args)
    sol = np.loadtxt(dst, delimiter=",", skiprows=1)
    assert sol.shape == (len(rec), 14)
    ref = gf.Strapdown(gf.NavState.from_trajectory(tr, 0)).run(tr.dtheta_rad, tr.dv_m_s, t_s=tr.t_s[1:])
    # the CSV keeps 12 significant digits of degrees: 1e-10 deg = 1.7e-12 rad (11 um),
    # and the initial state passes through decimal degrees too: allow 5e-12 rad
    np.testing.assert_allclose(np.radians(sol[:, 1]), ref.lat_rad, rtol=0, atol=5e-12)
    np.testing.assert_allclose(sol[:, 0], ref.t_s, atol=1e-9)
    rec[1000, 5] = np.nan
    np.savetxt(src, rec, delimiter=",", fmt="%.17g")
    proc = run(*[a for a in args if a != "--header"], check=False)
    assert proc.returncode == 1 and "accel[1000, 1]" in proc.stderr
    assert np.loadtxt(tmp_path / "sol.partial.csv", delimiter=",", skiprows=2).shape[0] == 1000
    assert np.loadtxt(dst, delimiter=",", skiprows=1).shape[0] == len(rec)   # the first run's


def test_gfnav_csv(tmp_path):
    """gfins gfnav on a CSV of qin9 outputs reproduces GyroFreeNavigator.run."""
    from gfins_fmi.sim import trajectory as tj
    tr = tj.sample(tj.Circle(), 20.0, 0.01)
    g = gf.layout("qin9", 0.1)
    A = tr.array_outputs(g)
    src, dst = tmp_path / "arr.csv", tmp_path / "sol.csv"
    np.savetxt(src, np.c_[tr.t_s, A], delimiter=",", fmt="%.17g")
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    run("gfnav", str(src), str(dst), "--layout", "qin9", "--lever-arm", "0.1", "--strategy", "sqrt",
        "--omega-init=" + ",".join(repr(float(x)) for x in tr.gyro_rad_s[0]),
        "--lat0", repr(float(np.degrees(tr.lat_rad[0]))), "--lon0", repr(float(np.degrees(tr.lon_rad[0]))),
        "--h0", repr(float(tr.h_m[0])), "--heading0", repr(float(e[0])), "--pitch0", repr(float(e[1])),
        "--roll0", repr(float(e[2])), "--v0=" + ",".join(repr(float(x)) for x in tr.v_n_m_s[0]))
    sol = np.loadtxt(dst, delimiter=",", skiprows=1)
    ref, _ = gf.GyroFreeNavigator(g, gf.NavState.from_trajectory(tr, 0), "sqrt",
                                  tr.gyro_rad_s[0]).run(A, 0.01)
    assert sol.shape == (len(A), 21)
    np.testing.assert_allclose(np.radians(sol[:, 1]), ref.lat_rad, rtol=0, atol=5e-12)
    # the output rows carry the record's own times, to the bit (a row joins its input on t)
    np.testing.assert_array_equal(sol[:, 0], np.loadtxt(src, delimiter=",", usecols=0))
    proc = run("gfnav", str(src), str(dst), "--layout", "cube6", "--lever-arm", "0.1",
               "--lat0", "30", "--lon0", "114", check=False)
    assert proc.returncode == 2 and "needs 7 or 8 columns" in proc.stderr
