"""Interrupts and concurrent runs (issue 21, acceptance): ``gfins integrate`` interrupted
by SIGINT or SIGTERM at random points of its reading, filtering, smoothing and writing,
and pairs of runs started together on the same outputs, leave in the folder either the
previous set of outputs or the new one, each whole (sha256 of every file), and no
temporary.

Before: Ctrl-C while integrate wrote its innovation log exited 130 saying "OUT left as it
was" while OUT was already the new solution beside the previous run's log, and
OUT.innovations.csv.part stayed behind; two staggered runs on one output corrupted the
log in 2 of 24 pairs (a fixed temporary name).

The study runs in a process of its own (tests/support/interrupts.py: the signals go to
it, not to pytest), once on the path every run takes (in chunks: here chunks of 1200
samples, reading, filtering, smoothing and writing interleaved) and once on the
whole-record path (--plot's; its phases one after the other); the pairs run on the
first. The default run interrupts 16 points (4 per phase or quarter) and runs 3 pairs
(~1 min on the 2-core machine); GFINS_INTERRUPT_POINTS=64 GFINS_INTERRUPT_PAIRS=24 is the
acceptance study (its figures: docs/io.md, "A run's outputs").
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from support.paths import ROOT

POINTS = int(os.environ.get("GFINS_INTERRUPT_POINTS", "16"))
PAIRS = int(os.environ.get("GFINS_INTERRUPT_PAIRS", "3"))


@pytest.mark.parametrize("mode", ["chunks", "whole"])
def test_interrupts_and_concurrent_runs_leave_one_whole_set(tmp_path, mode):
    import gfins_fmi as gf
    from gfins_fmi.sim.scenarios import TACTICAL, simulate_drive, town_drive
    from gfins_fmi.sim.vehicle import GnssReceiver
    d = simulate_drive(town_drive(60.0, lat0_rad=0.6, lon0_rad=2.0, h0_m=30.0), 60.0, 0.01,
                       imu=TACTICAL, gnss=GnssReceiver(), seed=4)
    d.imu.to_csv(tmp_path / "imu.csv")
    d.gnss.to_csv(tmp_path / "gnss.csv")
    tr = d.truth
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    init = "--initial=" + ",".join(repr(float(x)) for x in
                                   (np.degrees(tr.lat_rad[0]), np.degrees(tr.lon_rad[0]), tr.h_m[0], *e))
    env = dict(os.environ, PYTHONPATH=str(ROOT / "tests"), MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(ROOT / "tests" / "support" / "interrupts.py"), str(tmp_path),
                           str(tmp_path / "imu.csv"), str(tmp_path / "gnss.csv"), init, str(POINTS),
                           str(PAIRS if mode == "chunks" else 0), "21", mode], capture_output=True, text=True, timeout=1800, env=env,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert res["failures"] == [], (res["failures"], res["points"], res["reference_events"])
    assert len(res["points"]) == POINTS and len(res["pairs"]) == (PAIRS if mode == "chunks" else 0)
    # every point aimed at one of the four phases (quarters of the run in chunks), and the
    # interrupted runs left the old set: the study reached the runs it meant to interrupt
    # (not only finished ones)
    aims = ({"read", "filter", "smoother", "write"} if mode == "whole" else
            {f"quarter {i}" for i in range(1, 5)})
    assert {p["aimed"] for p in res["points"]} == aims
    assert sum(p["set"] == "old" for p in res["points"]) >= POINTS // 2, res["points"]
