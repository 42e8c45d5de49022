"""``gfins align``: in motion with a speed and depth record (the pass table written), and
static on a swaying base (--disturbed).
"""
from __future__ import annotations

import numpy as np
import pytest

from gfins_fmi.estimation import InitialState
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.io.records import BaroRecord, ImuRecord, OdometerRecord
from gfins_fmi.nav.strapdown import NavState, euler_to_quat, quat_to_euler
from gfins_fmi.sim.vehicle import Segment, VehicleProfile, simulate_vehicle
from gfins_fmi.sim import trajectory as tj
from support.motions import Mooring

DEG = np.pi / 180
DT = 0.02
NOISE = ImuNoise(gyro_arw_deg_sqrt_h=0.002, accel_vrw_ug_sqrt_hz=10.0)
G_BIAS, A_BIAS = 0.01 * DEG / 3600, 50 * 9.80665e-6


@pytest.fixture(scope="module")
def auv():
    """An AUV-like run: 4.5 m/s, 50 m deep, 90 deg turns and speed changes, 200 s at 50 Hz."""
    segs = [Segment(20.0), Segment(30.0, dheading_rad=np.pi / 2), Segment(20.0, dspeed_m_s=1.0),
            Segment(30.0, dheading_rad=-np.pi / 2), Segment(30.0, dspeed_m_s=-1.0)] * 2
    prof = VehicleProfile(lat0_rad=30 * DEG, lon0_rad=114 * DEG, h0_m=-50.0, heading0_rad=40 * DEG,
                          speed0_m_s=4.5, segments=segs)
    return simulate_vehicle(prof, 200.0, DT)


def records(truth, seed=7, t_end=200.0, tach_scale=1.0, heading_err=2 * DEG):
    rng = np.random.default_rng(seed)
    n = int(round(t_end / DT))
    bg, ba = rng.normal(0, G_BIAS, 3), rng.normal(0, A_BIAS, 3)
    wn, an = NOISE.sample(n, DT, rng)
    imu = ImuRecord(t_s=truth.t_s[1:n + 1], gyro=truth.dtheta_rad[:n] + (bg + wn) * DT,
                    accel=truth.dv_m_s[:n] + (ba + an) * DT, kind="increments")
    ks = np.arange(5, n + 1, 5)
    vh = np.hypot(truth.v_n_m_s[ks, 0], truth.v_n_m_s[ks, 1])
    tach = OdometerRecord(t_s=truth.t_s[ks], speed_m_s=tach_scale * vh + rng.normal(0, 0.05, len(ks)),
                          std_m_s=np.full(len(ks), 0.05))
    kd = np.arange(50, n + 1, 50)
    depth = BaroRecord(t_s=truth.t_s[kd], h_m=truth.h_m[kd] + rng.normal(0, 0.1, len(kd)),
                       std_m=np.full(len(kd), 0.1))
    e0 = quat_to_euler(truth.q_bn[0]) + np.array([heading_err, 0.2 * DEG, -0.2 * DEG])
    v0 = 4.5 * np.array([np.sin(e0[0]), np.cos(e0[0]), 0.0])
    nav = NavState(euler_to_quat(e0), v0, truth.lat_rad[0], truth.lon_rad[0], truth.h_m[0], truth.t_s[0])
    init = InitialState(nav, position_std_m=1.0, velocity_std_m_s=(0.4, 0.4, 0.05),
                        attitude_std_rad=(0.6 * DEG, 0.6 * DEG, 6 * DEG), gyro_bias_std_rad_s=G_BIAS,
                        accel_bias_std_m_s2=A_BIAS)
    return imu, tach, depth, init


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
