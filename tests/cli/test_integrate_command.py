"""``gfins integrate`` on the rtk_walk recording: the solution, the innovation log and the
smoothed solution written, the summary printed.
"""
from __future__ import annotations


import numpy as np
import pytest
from support.paths import rtk_walk_dir

def _rtk_walk_dir():
    return rtk_walk_dir() or pytest.fail("the repository's copy of the rtk_walk recording "
                                         "(tests/data/rtk_walk) is missing")


def test_cli_integrate(tmp_path):
    from gfins_fmi.cli import main
    d = _rtk_walk_dir()
    out = tmp_path / "walk.csv"
    rc = main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out),
               "--imu-format", "rtk_walk", "--grade", "consumer", "--static", "9", "--zupt", "--smooth",
               "--outages", "15,20,25"])
    assert rc == 0
    sol = np.loadtxt(out, delimiter=",", skiprows=1)
    # 25 columns: no column of a disabled state (issue 20; --all-states: 35)
    assert sol.shape[1] == 25 and np.all(np.isfinite(sol))
    assert (tmp_path / "walk.innovations.csv").is_file() and (tmp_path / "walk.smoothed.csv").is_file()
    with pytest.raises(SystemExit) as ei:            # refused at parse time, in the CLI's terms
        main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out),
              "--imu-format", "rtk_walk", "--static", "9", "--lever-arm", "1,2"])
    assert ei.value.code == 2
    # two increments per navigation update: fewer rows, all finite (not half: this
    # receiver's IMU times are whole milliseconds, intervals of 6 to 9 ms, and only pairs
    # of equal intervals (within 1 %) are grouped; measured 15546 of 19052 rows)
    out2 = tmp_path / "walk2.csv"
    assert main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out2),
                 "--imu-format", "rtk_walk", "--grade", "consumer", "--static", "9",
                 "--subsamples", "2"]) == 0
    sol2 = np.loadtxt(out2, delimiter=",", skiprows=1)
    assert 0.5 * len(sol) < len(sol2) < 0.9 * len(sol) and np.all(np.isfinite(sol2))
    # --odometer-mount reaches the filter (two more states); with neither odometer nor NHC
    # nothing observes them: the boresight columns (the last two) stay exactly 0
    out3 = tmp_path / "walk3.csv"
    assert main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out3),
                 "--imu-format", "rtk_walk", "--grade", "consumer", "--static", "9",
                 "--subsamples", "2", "--odometer-mount"]) == 0
    with open(out3) as fh:
        assert fh.readline().strip().split(",")[-2:] == ["odo_pitch_rad", "odo_heading_rad"]
    sol3 = np.loadtxt(out3, delimiter=",", skiprows=1)
    assert sol3.shape == (len(sol2), sol2.shape[1] + 2) and np.all(sol3[:, -2:] == 0.0)
    out4 = tmp_path / "walk4.csv"
    assert main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out4),
                 "--imu-format", "rtk_walk", "--grade", "consumer", "--static", "9",
                 "--subsamples", "2", "--all-states"]) == 0
    sol4 = np.loadtxt(out4, delimiter=",", skiprows=1)
    assert sol4.shape == (len(sol2), 35) and np.all(sol4[:, :25] == sol2)
    with pytest.raises(SystemExit) as ei:
        main(["integrate", str(d / "imu_1730_sf.csv"), str(d / "gnss_1730_sf.pos"), str(out2),
              "--imu-format", "rtk_walk", "--subsamples", "5"])
    assert ei.value.code == 2
