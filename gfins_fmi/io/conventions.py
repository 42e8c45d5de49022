"""Other tools' frames, angles and time scales, mapped once onto ours.

Ours (``csrc/nav/gf_sins.h``): body right-front-up (RFU), navigation East-North-Up (ENU),
Euler [heading, pitch, roll] with C_b^n = Rz(-heading) Rx(pitch) Ry(roll).
Many tools (KF-GINS, RTKLIB-based fusion code, most INS manuals) use body
forward-right-down (FRD), navigation North-East-Down (NED) and roll, pitch, yaw with
C_b^n = Rz(yaw) Ry(pitch) Rx(roll).

Both axis changes are the same permutation with a sign,
``P = [[0, 1, 0], [1, 0, 0], [0, 0, -1]]`` (swap the first two axes, negate the third):
v_RFU = P v_FRD and v_ENU = P v_NED, and P is its own inverse. Hence
C_RFU^ENU = P C_FRD^NED P, and the angles carry over unchanged: heading = yaw (both
clockwise from north), pitch = pitch (nose up +), roll = roll (right wing down +) —
tests/io/test_kfgins.py checks this with direction cosine matrices built both ways from
random angles.

Time: GPS time counts seconds since the GPS epoch 1980-01-06 00:00:00 GPST without
leap seconds; ``week * 604800 + seconds_of_week`` on that scale.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["P_SWAP", "frd_to_rfu", "ned_to_enu", "rpy_frd_ned_to_euler_rfu_enu",
           "SECONDS_PER_WEEK", "GPS_EPOCH_FROM_1970_S", "gps_seconds_from_calendar"]

#: v_RFU = P_SWAP @ v_FRD and v_ENU = P_SWAP @ v_NED (P_SWAP is its own inverse)
P_SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
P_SWAP.flags.writeable = False

#: seconds in a GPS week
SECONDS_PER_WEEK = 604800
#: 1970-01-01 to 1980-01-06 on a calendar without leap seconds: 3657 days (s)
GPS_EPOCH_FROM_1970_S = 3657 * 86400


def frd_to_rfu(v) -> np.ndarray:
    """Vectors (n, 3) from forward-right-down to right-front-up axes: (R, F, -D).
    The same operation maps north-east-down to east-north-up; see :func:`ned_to_enu`."""
    v = np.asarray(v, dtype=np.float64)
    return np.ascontiguousarray(np.stack([v[..., 1], v[..., 0], -v[..., 2]], axis=-1))


def ned_to_enu(v) -> np.ndarray:
    """Vectors (n, 3) from north-east-down to east-north-up: (E, N, -D)."""
    return frd_to_rfu(v)


def rpy_frd_ned_to_euler_rfu_enu(roll_rad, pitch_rad, yaw_rad) -> np.ndarray:
    """Attitude as roll, pitch, yaw of an FRD body in NED (C_b^n = Rz(yaw) Ry(pitch)
    Rx(roll)) -> ours, [heading, pitch, roll] of the RFU body in ENU (C_b^n =
    Rz(-heading) Rx(pitch) Ry(roll)): the same angles, heading wrapped to [0, 2 pi).

    Returns
    -------
    ndarray (n, 3), rad
    """
    roll = np.asarray(roll_rad, dtype=np.float64)
    pitch = np.asarray(pitch_rad, dtype=np.float64)
    heading = np.mod(np.asarray(yaw_rad, dtype=np.float64), 2.0 * math.pi)
    heading = np.where(heading >= 2.0 * math.pi, 0.0, heading)    # mod of -tiny gives 2 pi
    return np.ascontiguousarray(np.stack([heading, pitch, roll], axis=-1))


def gps_seconds_from_calendar(year, month, day, hour, minute, second) -> np.ndarray:
    """GPS seconds since 1980-01-06 00:00:00 of times given on the GPST calendar
    (arrays of equal shape; ``second`` may have a fraction). No leap seconds enter: the
    calendar is already GPS time. Resolution of the result: one float64 ulp, 2.4e-7 s at
    1.4e9 s (the years around 2025)."""
    y = np.asarray(year, dtype=np.int64)
    mo = np.asarray(month, dtype=np.int64)
    d = np.asarray(day, dtype=np.int64)
    h = np.asarray(hour, dtype=np.int64)
    mi = np.asarray(minute, dtype=np.int64)
    s = np.asarray(second, dtype=np.float64)
    months = ((y - 1970) * 12 + (mo - 1)).astype("datetime64[M]")
    date = months.astype("datetime64[D]") + (d - 1).astype("timedelta64[D]")
    bad = ((mo < 1) | (mo > 12) | (d < 1) | (date.astype("datetime64[M]") != months)
           | (h < 0) | (h > 23) | (mi < 0) | (mi > 59) | ~(s >= 0) | ~(s < 61))
    if np.any(bad):
        k = np.argwhere(bad)[0]
        raise ValueError(f"not a calendar time: {y[tuple(k)]}/{mo[tuple(k)]}/{d[tuple(k)]} "
                         f"{h[tuple(k)]}:{mi[tuple(k)]}:{s[tuple(k)]} (at index {k.tolist()})")
    days = (date - np.datetime64("1980-01-06", "D")).astype(np.int64)
    return (days * 86400 + h * 3600 + mi * 60) + s
