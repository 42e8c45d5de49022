"""The ``gfins`` command's handling of what a user types and of the records it reads
(issue 15, items 3 and 4), run in-process through ``gfins_fmi.cli.main`` on small
inputs: options are checked when parsed, with messages in the command's own terms,
before anything runs; time columns are checked (finite, increasing, gaps reported) and
the interval is taken from them or checked against ``--dt``; solutions are written at
full precision."""
from __future__ import annotations

import numpy as np
import pytest

import gfins_fmi as gf
from gfins_fmi.sim import trajectory as tj
from gfins_fmi.cli import main
from support.commands import navigate_init_args
from support.truth import W0, numpy_outputs, paper_layout, smooth_motion

L, DT = 0.1, 0.01


def refused(capsys, *argv) -> str:
    """Run ``gfins argv`` expecting argparse to refuse it (exit 2); returns stderr."""
    with pytest.raises(SystemExit) as exc:
        main(list(argv))
    assert exc.value.code == 2
    return capsys.readouterr().err


# ---- options (item 4) -------------------------------------------------------------

NAV = ["--lat0", "30", "--lon0", "114"]
OPTION_CASES = {
    "demo duration 0": (["demo", "--duration", "0"], "argument --duration: must be finite and > 0 s"),
    "demo dt 0": (["demo", "--dt", "0"], "argument --dt: must be finite and > 0 s"),
    "demo dt negative": (["demo", "--dt", "-0.01"], "argument --dt: must be finite and > 0 s"),
    "demo dt nan": (["demo", "--dt", "nan"], "argument --dt: must be finite and > 0 s"),
    "demo noise negative": (["demo", "--noise", "-1"], "argument --noise: must be finite and >= 0 m/s^2"),
    "demo lever arm": (["demo", "--lever-arm", "1e-7"], "argument --lever-arm: must be finite and >= 1e-06 m"),
    "demo one sample": (["demo", "--duration", "0.01", "--dt", "0.01"],
                        "--duration 0.01 s at --dt 0.01 s gives 1 sample"),
    "reproduce runs 0": (["reproduce", "qin", "--runs", "0"], "argument --runs: must be an integer >= 1"),
    "reproduce runs text": (["reproduce", "qin", "--runs", "ten"], "argument --runs: must be an integer >= 1"),
    "reproduce gravity": (["reproduce", "qin", "--gravity", "-9.8"], "argument --gravity: must be finite and >= 0"),
    "reproduce seed": (["reproduce", "qin", "--seed", "-1"], "argument --seed: must be an integer >= 0"),
    "analyze runs 1": (["analyze", "--runs", "1"], "argument --runs: must be an integer >= 2"),
    "cosim seconds 0": (["cosim", "--seconds", "0"], "argument --seconds: must be finite and > 0 s"),
    "cosim step 0": (["cosim", "--step", "0"], "argument --step: must be finite and > 0 s"),
    "cosim align 0": (["cosim", "--align", "0"], "argument --align: must be finite and > 0 s"),
    "cosim below a step": (["cosim", "--seconds", "0.005"], "--seconds 0.005 s is shorter than one --step"),
    "gfnav lat nan": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1", "--lat0", "nan",
                       "--lon0", "114"], r"argument --lat0: must be finite and in (-90, 90) deg"),
    "gfnav lat pole": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1", "--lat0", "90",
                        "--lon0", "114"], r"argument --lat0: must be finite and in (-90, 90) deg"),
    "gfnav v0 short": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1", "--v0", "1,2", *NAV],
                       "argument --v0: expected 3 comma-separated finite numbers (E,N,U in m/s); got '1,2'"),
    "gfnav omega text": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1",
                          "--omega-init", "1,2,x", *NAV],
                         "argument --omega-init: expected 3 comma-separated finite numbers (x,y,z in rad/s)"),
    "gfnav noise 0": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "0.1", "--accel-noise",
                       "0", *NAV], "argument --accel-noise: must be finite and in (0, 1000] m/s^2"),
    "gfnav lever arm": (["gfnav", "a.csv", "o.csv", "--layout", "qin9", "--lever-arm", "-0.1", *NAV],
                        "argument --lever-arm: must be finite and >= 1e-06 m"),
    "navigate v0 nan": (["navigate", "a.csv", "o.csv", "--v0", "0,nan,0", *NAV],
                        "argument --v0: expected 3 comma-separated finite numbers (E,N,U in m/s); got '0,nan,0'"),
    "navigate baro tau": (["navigate", "a.csv", "o.csv", "--baro-tau", "0", *NAV],
                          "argument --baro-tau: must be finite and > 0 s"),
    "navigate h0": (["navigate", "a.csv", "o.csv", "--h0", "inf", *NAV], "argument --h0: must be finite"),
    "navigate heading": (["navigate", "a.csv", "o.csv", "--heading0", "nan", *NAV],
                         "argument --heading0: must be finite"),
    "solve9 dt 0": (["solve9", "a.csv", "o.csv", "--dt", "0", "--lever-arm", "0.1"],
                    "argument --dt: must be finite and > 0 s"),
}


@pytest.mark.parametrize("case", sorted(OPTION_CASES))
def test_options_are_refused_at_parse_time_in_the_commands_terms(case, capsys, tmp_path,
                                                                  monkeypatch):
    """Before: tracebacks after part of the work (demo --duration 0, --dt 0|-0.01,
    reproduce --runs 0, cosim --seconds 0), a half-run demo (--noise -1), a C-core
    message (--lat0 nan: 'an input sample is not finite'), garbage (--v0 1,2)."""
    monkeypatch.chdir(tmp_path)               # any output folder would appear here
    argv, message = OPTION_CASES[case]
    err = refused(capsys, *argv)
    assert message in err, err
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == []     # nothing ran, nothing written


# ---- time columns and output precision (item 3) -----------------------------------

@pytest.fixture
def record9():
    n = 60
    u, th = paper_layout(L)
    t, f, w, wd = smooth_motion(n, DT)
    return 100.0 + t, numpy_outputs(u, th, f, w, wd)


def _csv(path, *cols):
    np.savetxt(path, np.column_stack(cols), delimiter=",", fmt="%.17g")
    return str(path)


def _solve9(tmp_path, t, A, *extra):
    src = _csv(tmp_path / "a.csv", t, A) if t is not None else _csv(tmp_path / "a.csv", A)
    dst = tmp_path / "o.csv"
    return main(["solve9", src, str(dst), "--lever-arm", str(L), *extra]), dst


def test_solve9_takes_the_interval_and_the_times_from_the_column(tmp_path, record9):
    """Before: the time column was dropped, times restarted at 0 and were written with
    6 decimals."""
    t, A = record9
    status, dst = _solve9(tmp_path, t, A, "--omega-init", ",".join(map(str, W0)))
    assert status == 0
    out = np.loadtxt(dst, delimiter=",", skiprows=1)
    assert np.array_equal(out[:, 0], t)                      # the record's times, all digits
    ref = gf.solve_accel9(A, DT, L, W0)
    # the interval from the column (median of its differences) is DT to a few ulp of t
    np.testing.assert_allclose(out[:, 4:7], ref.omega_rad_s, rtol=1e-12, atol=1e-12)
    assert np.array_equal(out[:, 1:4], ref.f_m_s2)            # f does not depend on dt


def test_solve9_checks_dt_against_the_column(tmp_path, record9, capsys):
    t, A = record9
    status, _ = _solve9(tmp_path, t, A, "--dt", "0.02")
    assert status == 2
    assert "--dt 0.02 s disagrees with the time column (interval 0.01 s)" in capsys.readouterr().err
    status, _ = _solve9(tmp_path, t, A, "--dt", "0.01")
    assert status == 0


def test_solve9_without_a_time_column_needs_dt(tmp_path, record9, capsys):
    _, A = record9
    status, _ = _solve9(tmp_path, None, A)
    assert status == 2 and "has no time column: give --dt" in capsys.readouterr().err
    status, dst = _solve9(tmp_path, None, A, "--dt", "0.01")
    assert status == 0
    out = np.loadtxt(dst, delimiter=",", skiprows=1)
    assert np.array_equal(out[:, 0], np.arange(len(A)) * 0.01)


BAD_TIMES = {
    "constant": (lambda t: np.full_like(t, 5.0), "row 1: time 5 s does not increase (previous 5 s)"),
    "nan": (lambda t: np.where(np.arange(t.size) == 7, np.nan, t), "row 7: time nan s is not finite"),
    "decreasing": (lambda t: t[::-1], "does not increase"),
    "gap": (lambda t: np.where(np.arange(t.size) >= 20, t + 0.5, t),
            "1 gap in the time column: row 20 (t = 100.19 -> 100.7 s, 51 intervals of 0.01 s)"),
    "jitter": (lambda t: t + np.where(np.arange(t.size) == 30, 0.003, 0.0),
               "the time column is not uniform"),
}


@pytest.mark.parametrize("case", sorted(BAD_TIMES))
def test_solve9_refuses_bad_time_columns(case, tmp_path, record9, capsys):
    """Before: constant, NaN, decreasing or gapped times -> exit 0 with times from 0."""
    t, A = record9
    fix, message = BAD_TIMES[case]
    status, dst = _solve9(tmp_path, fix(t), A, "--dt", "0.01")
    err = capsys.readouterr().err
    assert status == 2, err
    assert message in err, err
    if case == "gap":
        assert "a fixed-interval solver cannot bridge it" in err
    assert not dst.exists()


def test_solve9_refuses_samples_beyond_the_physical_limits(tmp_path, record9, capsys):
    """Before: 1e300 samples and dt = 1e300 (w = 1.6e150 rad/s) passed with exit 0. Now
    the solver refuses them as the navigators do; the solution before it is kept in
    sol.partial.csv."""
    t, A = record9
    A = A.copy()
    A[40] = 1e300
    status, dst = _solve9(tmp_path, t, A)
    err = capsys.readouterr().err
    assert status == 1
    assert "sample 40 is beyond the physical limits" in err and "50 rad/s" in err
    assert np.loadtxt(dst.with_name("o.partial.csv"), delimiter=",", skiprows=2).shape[0] == 40
    # dt = 1e300: where noise makes omega_x^2 < 0 (omega_x crosses 0 at t = 0) the rate is
    # the integral of omega_dot, ~1e298 rad/s
    noisy = record9[1] + np.random.default_rng(5).normal(0.0, 1e-3, record9[1].shape)
    status, dst = _solve9(tmp_path, None, noisy, "--dt", "1e300")
    assert status == 1 and "is beyond the physical limits" in capsys.readouterr().err
    assert np.loadtxt(dst.with_name("o.partial.csv"), delimiter=",", skiprows=2, ndmin=2).shape[0] >= 1


def _gfnav(tmp_path, t, A, *extra):
    src = _csv(tmp_path / "arr.csv", t, A)
    dst = tmp_path / "sol.csv"
    return main(["gfnav", src, str(dst), "--layout", "qin9", "--lever-arm", str(L),
                 *NAV, *extra]), dst


@pytest.mark.parametrize("case", ["nan", "constant", "gap"])
def test_gfnav_names_the_bad_row(case, tmp_path, record9, capsys):
    """Before: NaN or repeated times -> 'the time column is not uniform' or a C-core
    message about dt_s; now the row and the fault are named."""
    t, A = record9
    fix, message = BAD_TIMES[case]
    status, _ = _gfnav(tmp_path, fix(t), A)
    err = capsys.readouterr().err
    assert status == 2
    assert message in err, err


def test_navigate_checks_times_reports_gaps_and_writes_full_precision(tmp_path, capsys):
    tr = tj.sample(tj.Circle(), 2.0, DT)
    t = tr.t_s[1:].copy()
    init = navigate_init_args(tr)
    src, dst = tmp_path / "rec.csv", tmp_path / "sol.csv"

    def navigate(times):
        _csv(src, times, tr.dtheta_rad, tr.dv_m_s)
        return main(["navigate", str(src), str(dst), *init])
    assert navigate(t) == 0
    out = np.loadtxt(dst, delimiter=",", skiprows=1)
    ref = gf.Strapdown(gf.NavState.from_trajectory(tr, 0)).run(tr.dtheta_rad, tr.dv_m_s, t_s=t)
    # full precision: time and quaternion columns round-trip exactly (before: 12 digits)
    assert np.array_equal(out[:, 0], ref.t_s) and np.array_equal(out[:, 10:14], ref.q_bn)
    capsys.readouterr()
    bad = t.copy()
    bad[50] = np.nan
    assert navigate(bad) == 2
    assert "row 50: time nan s is not finite" in capsys.readouterr().err
    bad = t.copy()
    bad[80:] += 1.0                       # 100 samples missing: navigated, and reported
    assert navigate(bad) == 0
    assert "note: 1 gap in the time column: row 80" in capsys.readouterr().err
