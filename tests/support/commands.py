"""Command-line helpers of the tests."""
from __future__ import annotations

import numpy as np

import gfins_fmi as gf


def navigate_init_args(tr) -> list:
    """`gfins navigate` options giving the initial state of a trajectory's first sample
    (degrees, full precision)."""
    e = np.degrees(gf.quat_to_euler(tr.q_bn[0]))
    return ["--lat0", repr(float(np.degrees(tr.lat_rad[0]))), "--lon0",
            repr(float(np.degrees(tr.lon_rad[0]))), "--h0", repr(float(tr.h_m[0])),
            "--heading0", repr(float(e[0])), "--pitch0", repr(float(e[1])), "--roll0",
            repr(float(e[2])), "--v0=" + ",".join(repr(float(x)) for x in tr.v_n_m_s[0])]
