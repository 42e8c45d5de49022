"""The initial navigation state from command options, one way for every command: the
position and attitude in degrees (``--lat0 --lon0 --h0 --heading0 --pitch0 --roll0 --v0``
of ``navigate`` and ``gfnav``, or ``--initial LAT,LON,H,HEADING,PITCH,ROLL`` of
``integrate`` and ``align motion``), the velocity and the time of the state."""
from __future__ import annotations

import numpy as np

from gfins_fmi.nav.earth import deg
from gfins_fmi.nav.strapdown import NavState, euler_to_quat

__all__ = ["nav_state", "from_state_options", "from_initial_option", "record_start_s"]


def nav_state(lat_deg: float, lon_deg: float, h_m: float, heading_deg: float, pitch_deg: float,
              roll_deg: float, v_enu_m_s=(0.0, 0.0, 0.0), t_s: float = 0.0) -> NavState:
    """A NavState of a position and attitude given in degrees (heading clockwise from
    north), a velocity east, north, up (m/s) and a time (s)."""
    q = euler_to_quat(np.array([heading_deg, pitch_deg, roll_deg]) * deg)
    return NavState(q, np.asarray(v_enu_m_s, float), lat_deg * deg, lon_deg * deg, h_m, t_s)


def from_state_options(args, t_s: float) -> NavState:
    """The state of ``--lat0 --lon0 --h0 --heading0 --pitch0 --roll0 --v0`` at ``t_s``."""
    return nav_state(args.lat0, args.lon0, args.h0, args.heading0, args.pitch0, args.roll0,
                     args.v0, t_s)


def from_initial_option(values, t_s: float, v_enu_m_s=(0.0, 0.0, 0.0)) -> NavState:
    """The state of ``--initial LAT,LON,H,HEADING,PITCH,ROLL`` at ``t_s``."""
    lat, lon, h, heading, pitch, roll = values
    return nav_state(lat, lon, h, heading, pitch, roll, v_enu_m_s, t_s)


def record_start_s(imu) -> float:
    """Where a filter run over a whole IMU record starts: its first sample (rates), or
    one interval (the median of the first 100) before it (increments: the first covers
    the interval that ends there)."""
    t = imu.t_s
    return float(t[0]) if imu.kind == "rates" else float(t[0] - np.median(np.diff(t[:100])))
