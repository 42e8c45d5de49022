"""``gfins align``: in motion with a speed and depth record (the pass table written), and
static on a swaying base (--disturbed).
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.strapdown import quat_to_euler
from gfins_fmi.sim import trajectory as tj
from support.auv import DEG, auv_truth, records
from support.motions import Mooring


@pytest.fixture(scope="module")
def auv():
    """The AUV-like run (support/auv.py)."""
    return auv_truth()


def test_cli_align(auv, tmp_path, capsys):
    """`gfins align motion` on CSV records: one line per pass, the pass table, exit 1 when
    not converged; static
    mode refuses motion in its window (a turn at 3 deg/s: mean |w| above its 0.05 rad/s
    limit); missing inputs are refused at parse time."""
    from gfins_fmi.cli import main
    imu, tach, depth, init = records(auv, t_end=60.0)
    imu.to_csv(tmp_path / "imu.csv")
    tach.to_csv(tmp_path / "speed.csv")
    depth.to_csv(tmp_path / "depth.csv")
    e = quat_to_euler(init.nav.q_bn) / DEG
    ini = f"30,114,-50,{e[0]},{e[1]},{e[2]}"
    out = tmp_path / "passes.csv"
    rc = main(["align", "motion", str(tmp_path / "imu.csv"), str(tmp_path / "speed.csv"), "--initial", ini,
               "--depth", str(tmp_path / "depth.csv"), "--passes", "1", "--output", str(out)])
    cap = capsys.readouterr()
    lines = [x for x in cap.out.splitlines() if x.startswith("pass ")]
    # 60 s of data: not converged (first-pass heading sigma ~1.4 deg): exit 1, table written
    assert rc == 1 and len(lines) == 3 and out.exists() and "not converged" in cap.err, cap
    rc = main(["align", "static", str(tmp_path / "imu.csv"), "--position", "30,114,-50", "--window", "20,50"])
    err = capsys.readouterr().err
    assert rc == 2 and "motion during the static alignment" in err, err
    with pytest.raises(SystemExit):
        main(["align", "motion", str(tmp_path / "imu.csv")])


def _record(motion, duration_s):
    tr = tj.sample(motion, duration_s, 0.01)
    return tr, ImuRecord(t_s=tr.t_s[1:], gyro=tr.dtheta_rad, accel=tr.dv_m_s, kind="increments",
                         source=type(motion).__name__)


def test_cli_align_disturbed(tmp_path, capsys):
    """`gfins align static --disturbed` prints the inertial-frame attitude of the window's
    end (the heading within the test above's 0.3 deg); --fine may follow it (before: refused)."""
    from gfins_fmi.cli import main
    m = Mooring()
    tr, rec = _record(m, 120.0)
    rec.to_csv(tmp_path / "imu.csv")
    rc = main(["align", "static", str(tmp_path / "imu.csv"), "--position", "30,114,100", "--disturbed",
               "--window", "0,120"])
    out = capsys.readouterr().out
    assert rc == 0 and "coarse (inertial frame)" in out, out
    heading = float(out.split("heading ")[1].split(" deg")[0])
    truth = np.degrees(quat_to_euler(tr.q_bn[-1])[0])
    assert abs((heading - truth + 180.0) % 360.0 - 180.0) < 0.5, (heading, truth)   # measured 0.30 deg
    # issue 20: --fine follows --disturbed (zero-velocity updates with a 0.1 m/s 1-sigma: the base sways)
    rc = main(["align", "static", str(tmp_path / "imu.csv"), "--position", "30,114,100", "--disturbed",
               "--window", "0,60", "--fine"])
    out = capsys.readouterr().out
    assert rc == 0 and "fine (60 to 120 s): heading" in out, out
