"""A rigid ground vehicle and the exact outputs of the sensors riding it, from the C core
(gf_vehicle: the truth source of the vehicle FMU ``gfins_vehicle``).

The vehicle is level, at constant height, and follows a profile of segments; each
segment changes the speed, the heading rate and the heading by C2 smooth steps (so
acceleration and yaw acceleration are continuous). See csrc/gf_vehicle.h for the
equations. ``VehicleProfile.seed001`` is the vehicle test of seed 001 (alignment, a
start to 15 m/s, two 180 deg turns) and equals ``trajectory.VehicleRun``;
``VehicleProfile.circle`` is the circle of seed 000 (level).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import GfinsError, as_scalar, check_status, ffi, lib, ptr
from gfins_fmi.trajectory import Trajectory, deg

__all__ = ["Segment", "VehicleProfile", "VehicleRecord", "simulate_vehicle", "MAX_SEGMENTS"]

MAX_SEGMENTS = int(lib.GF_VEHICLE_MAX_SEGMENTS)
_SAMPLE_DOUBLES = 33  # gf_vehicle_sample is 33 doubles, in the order of _FIELDS
_FIELDS = [("t_s", 1), ("q_bn", 4), ("euler_rad", 3), ("v_n_m_s", 3), ("lat_rad", 1),
           ("lon_rad", 1), ("h_m", 1), ("east_m", 1), ("north_m", 1), ("speed_m_s", 1),
           ("heading_rate_rad_s", 1), ("gyro_rad_s", 3), ("accel_m_s2", 3),
           ("gyro_dot_rad_s2", 3), ("dtheta_rad", 3), ("dv_m_s", 3)]


@dataclass
class Segment:
    """One profile segment: over ``duration_s`` the speed changes by ``dspeed_m_s``, the
    heading rate (clockwise positive) by ``dheading_rate_rad_s`` and the heading, on top
    of the rate, by ``dheading_rad`` (all by the smooth step S(s) = s - sin(2 pi s)/2pi)."""
    duration_s: float
    dspeed_m_s: float = 0.0
    dheading_rate_rad_s: float = 0.0
    dheading_rad: float = 0.0


@dataclass
class VehicleProfile:
    """Start state and segments; after the last segment the vehicle cruises (constant
    speed and heading rate)."""
    lat0_rad: float = 30 * deg
    lon0_rad: float = 114 * deg
    h0_m: float = 100.0
    heading0_rad: float = 0.0
    speed0_m_s: float = 0.0
    heading_rate0_rad_s: float = 0.0
    segments: list = field(default_factory=list)

    @classmethod
    def seed001(cls, align_s: float = 600.0, speed_m_s: float = 15.0, accel_s: float = 20.0,
                turn_times_s: tuple = (240.0, 480.0), turn_s: float = 30.0,
                heading_rad: float = 0.0, **start) -> "VehicleProfile":
        """Seed 001's vehicle test: at rest ``align_s``, a smooth start to ``speed_m_s``
        over ``accel_s``, 180 deg turns (clockwise) of ``turn_s`` starting
        ``turn_times_s`` after the start of motion. Same motion as
        ``trajectory.VehicleRun`` with the same arguments."""
        segs = [Segment(align_s), Segment(accel_s, dspeed_m_s=speed_m_s)]
        t = accel_s
        for t_turn in turn_times_s:
            if t_turn < t:
                raise ValueError(f"turn_times_s must be increasing and start after the "
                                 f"acceleration ({accel_s} s) and previous turns; got {turn_times_s}")
            if t_turn > t:
                segs.append(Segment(t_turn - t))
            segs.append(Segment(turn_s, dheading_rad=np.pi))
            t = t_turn + turn_s
        return cls(heading0_rad=heading_rad, segments=segs, **start)

    @classmethod
    def circle(cls, radius_m: float = 100.0, speed_m_s: float = 10.0, **start) -> "VehicleProfile":
        """Counter-clockwise circle (seen from above) of ``radius_m`` at ``speed_m_s``
        from the first sample on, level (seed 000's circle without its pitch and bank)."""
        if not (radius_m > 0 and speed_m_s > 0):
            raise ValueError(f"radius_m and speed_m_s must be > 0; got {radius_m}, {speed_m_s}")
        return cls(speed0_m_s=speed_m_s, heading_rate0_rad_s=-speed_m_s / radius_m, **start)

    def duration_s(self) -> float:
        """Total duration of the segments (the vehicle cruises after it)."""
        return float(sum(s.duration_s for s in self.segments))

    def to_c(self):
        """The profile as a ``gf_vehicle_profile`` (cffi)."""
        if len(self.segments) > MAX_SEGMENTS:
            raise ValueError(f"at most {MAX_SEGMENTS} segments; got {len(self.segments)}")
        p = ffi.new("gf_vehicle_profile *")
        for name in ("lat0_rad", "lon0_rad", "h0_m", "heading0_rad", "speed0_m_s",
                     "heading_rate0_rad_s"):
            setattr(p, name, float(getattr(self, name)))
        p.n_segments = len(self.segments)
        for k, s in enumerate(self.segments):
            p.segment[k].duration_s = float(s.duration_s)
            p.segment[k].dspeed_m_s = float(s.dspeed_m_s)
            p.segment[k].dheading_rate_rad_s = float(s.dheading_rate_rad_s)
            p.segment[k].dheading_rad = float(s.dheading_rad)
        return p

    def as_parameters(self) -> dict:
        """The profile as start values of the vehicle FMU (FMI 3.0 names; the segment
        arrays padded with zeros to MAX_SEGMENTS)."""
        def column(attr):
            vals = [float(getattr(s, attr)) for s in self.segments]
            return vals + [0.0] * (MAX_SEGMENTS - len(vals))
        if len(self.segments) > MAX_SEGMENTS:
            raise ValueError(f"at most {MAX_SEGMENTS} segments; got {len(self.segments)}")
        return {"lat0": self.lat0_rad, "lon0": self.lon0_rad, "h0": self.h0_m,
                "heading0": self.heading0_rad, "speed0": self.speed0_m_s,
                "heading_rate0": self.heading_rate0_rad_s, "n_segments": len(self.segments),
                "seg_duration": column("duration_s"), "seg_dspeed": column("dspeed_m_s"),
                "seg_dheading_rate": column("dheading_rate_rad_s"),
                "seg_dheading": column("dheading_rad")}


_BAD = {1: "lat0_rad: |latitude| must be < 89 deg", 2: "h0_m must be in [-1000, 1e5] m",
        3: "speed0_m_s must be >= 0"}


def _describe_bad(bad: int) -> str:
    if bad >= 100:
        return (f"segment {bad - 100}: duration_s must be > 0 and the speed must stay >= 0 "
                "(the sum of dspeed_m_s so far is negative)")
    return _BAD.get(bad, "a parameter is out of range")


@dataclass
class VehicleRecord(Trajectory):
    """A sampled vehicle run (a :class:`~gfins_fmi.trajectory.Trajectory` plus the
    angular acceleration, displacement, speed and heading rate, all from the C core)."""
    gyro_dot_rad_s2: np.ndarray = None
    euler_rad: np.ndarray = None
    east_m: np.ndarray = None
    north_m: np.ndarray = None
    speed_m_s: np.ndarray = None
    heading_rate_rad_s: np.ndarray = None

    def array_outputs(self, geometry) -> np.ndarray:
        """Outputs (n, N) of an accelerometer array of any geometry at the samples."""
        from gfins_fmi.accel_array import forward_model
        return forward_model(geometry, self.accel_m_s2, self.gyro_rad_s, self.gyro_dot_rad_s2)


def simulate_vehicle(profile: VehicleProfile, duration_s: float, dt_s: float,
                     start_time_s: float = 0.0) -> VehicleRecord:
    """Run the vehicle for ``duration_s`` and sample it every ``dt_s`` (n = duration/dt + 1
    samples, the first at ``start_time_s``), in one C call.

    Raises
    ------
    ValueError
        A profile parameter is out of range (the message names it), or bad durations.
    GfinsError
        The motion left the domain (latitude beyond 89 deg).
    """
    if ffi.sizeof("gf_vehicle_sample") != 8 * _SAMPLE_DOUBLES:  # pragma: no cover
        raise GfinsError("gf_vehicle_sample layout changed; update vehicle._FIELDS")
    if not (dt_s > 0 and np.isfinite(dt_s)) or not (duration_s >= 0 and np.isfinite(duration_s)):
        raise ValueError(f"dt_s must be > 0 and duration_s >= 0 (s); got {dt_s}, {duration_s}")
    start_time_s = as_scalar("start_time_s", start_time_s, "s")
    n = int(round(duration_s / dt_s)) + 1
    state = ffi.new("gf_vehicle_state *")
    buf = np.zeros((n, _SAMPLE_DOUBLES))
    samples = ffi.cast("gf_vehicle_sample *", ptr(buf, n * _SAMPLE_DOUBLES))
    bad = ffi.new("int *")
    st = lib.gf_vehicle_init(state, profile.to_c(), start_time_s, samples, bad)
    if st == lib.GF_ERR_BAD_PARAMETER:
        raise ValueError(f"vehicle profile rejected: {_describe_bad(bad[0])}")
    check_status(st, "gf_vehicle_init")
    done = ffi.new("size_t *")
    st = lib.gf_vehicle_run(state, n - 1, float(dt_s), samples + 1, done)
    check_status(st, f"gf_vehicle_run (stopped at sample {done[0] + 1} of {n})")
    cols, i = {}, 0
    for name, width in _FIELDS:
        cols[name] = buf[:, i] if width == 1 else buf[:, i:i + width]
        i += width
    return VehicleRecord(
        t_s=cols["t_s"], lat_rad=cols["lat_rad"], lon_rad=cols["lon_rad"], h_m=cols["h_m"],
        v_n_m_s=cols["v_n_m_s"], q_bn=cols["q_bn"], gyro_rad_s=cols["gyro_rad_s"],
        accel_m_s2=cols["accel_m_s2"], dtheta_rad=cols["dtheta_rad"][1:],
        dv_m_s=cols["dv_m_s"][1:], motion=None, gyro_dot_rad_s2=cols["gyro_dot_rad_s2"],
        euler_rad=cols["euler_rad"], east_m=cols["east_m"], north_m=cols["north_m"],
        speed_m_s=cols["speed_m_s"], heading_rate_rad_s=cols["heading_rate_rad_s"])
