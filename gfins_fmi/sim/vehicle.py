"""A rigid ground vehicle and the exact outputs of the sensors riding it, from the C core
(gf_vehicle: the truth source of the vehicle FMU ``gfins_vehicle``).

The vehicle is level, at constant height, and follows a profile of segments; each
segment changes the speed, the heading rate and the heading by C2 smooth steps (so
acceleration and yaw acceleration are continuous). See csrc/sim/gf_vehicle.h for the
equations. ``VehicleProfile.seed001`` is the vehicle test of seed 001 (alignment, a
start to 15 m/s, two 180 deg turns) and equals ``trajectory.VehicleRun``;
``VehicleProfile.circle`` is the circle of seed 000 (level).

Aiding sensors (C gf_aiding_sim, the same code as the vehicle FMU's): a
:class:`GnssReceiver` (antenna lever arm, white and Gauss-Markov errors, rate and time
offset, latency, scheduled outages, reported stds), a :class:`Barometer` (bias: constant,
random walk, Gauss-Markov; white noise) and an :class:`Odometer` (wheel lever arm,
scale-factor error, white noise). ``simulate_vehicle(..., gnss=, baro=, odometer=,
seed=)`` returns their measurements and truth with the IMU record; the vehicle FMU with
the sensors' ``fmu_parameters()`` and ``noise_seed = seed`` delivers the same bits.
Geometry and error definitions: csrc/sim/gf_aiding.h and docs/cosim.md.
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (GfinsError, as_scalar, as_vector3, check_status, ffi, lib, ptr,
                            struct_columns as _columns, struct_doubles as _doubles)
from gfins_fmi.gyrofree.array import forward_model
from gfins_fmi.nav.earth import deg
from gfins_fmi.sim.trajectory import Trajectory

__all__ = ["Segment", "VehicleProfile", "VehicleRecord", "simulate_vehicle", "MAX_SEGMENTS",
           "GnssReceiver", "Barometer", "Odometer", "GnssMeasurements", "BaroMeasurements",
           "OdometerMeasurements", "AidingTruth", "MAX_OUTAGES"]

MAX_SEGMENTS = int(lib.GF_VEHICLE_MAX_SEGMENTS)
MAX_OUTAGES = int(lib.GF_AIDING_MAX_OUTAGES)
_MAX_RATE_HZ = 1000.0       # GF_AIDING_MAX_RATE_HZ
_QUEUE = int(lib.GF_GNSS_QUEUE)


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


def _real(owner: str, name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"{owner}.{name} must be a real number; got {value!r}")
    return float(value)


def _integer(owner: str, name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, np.integer)):
        raise TypeError(f"{owner}.{name} must be an integer; got {value!r}")
    return int(value)


class _Sensor:
    """Shared by the sensor dataclasses: ``_SPEC`` lists (attribute = field of the C
    struct, FMU parameter, kind) with kind "r" real, "v" 3-vector, "i" integer; the C
    struct is the gf_aiding_params member ``_C``, also the FMU's on/off parameter."""

    def _values(self) -> dict:
        owner = type(self).__name__
        conv = {"r": lambda n, v: _real(owner, n, v),
                "v": lambda n, v: as_vector3(f"{owner}.{n}", v, "SI").tolist(),
                "i": lambda n, v: _integer(owner, n, v)}
        return {a: conv[kind](a, getattr(self, a)) for a, _, kind in self._SPEC}

    def _to_c(self, params) -> None:
        c = getattr(params, self._C)
        c.enabled = 1
        for attr, value in self._values().items():
            if isinstance(value, list):
                getattr(c, attr)[0:3] = value
            else:
                setattr(c, attr, value)

    def fmu_parameters(self) -> dict:
        """The sensor as start values of the vehicle FMU (FMI 3.0 names), switched on."""
        values = self._values()
        return {self._C: 1, **{fmu: values[a] for a, fmu, _ in self._SPEC}}


@dataclass(frozen=True)
class GnssReceiver(_Sensor):
    """A GNSS receiver on the vehicle (csrc/sim/gf_aiding.h, docs/cosim.md).

    Epoch k is valid at ``start + offset_s + k / rate_hz`` (epochs need not fall on IMU
    samples) and delivered ``latency_s`` later; epochs valid in an outage are not
    delivered. The antenna sits at ``lever_arm_m`` from the IMU; its position carries a
    white error and a first-order Gauss-Markov error, its velocity a white error (ENU).
    The receiver reports per epoch pos_std = sqrt(pos_std_m^2 + pos_gm_std_m^2),
    vel_std_m_s and ``quality``.

    Attributes
    ----------
    rate_hz : float
        Epochs per second, 0 < rate <= 1000 (receivers: 1 .. 20 Hz).
    offset_s : float
        First epoch after the start time, >= 0.
    latency_s : float
        Delivery delay, >= 0, latency_s * rate_hz <= 14.
    lever_arm_m : 3 floats
        IMU -> antenna phase centre, body right-front-up, m.
    pos_std_m, vel_std_m_s : 3 floats
        White position (m) and velocity (m/s) error stds, east, north, up.
    pos_gm_std_m : 3 floats
        Gauss-Markov position error, stationary std east, north, up, m.
    pos_gm_tau_s : float
        Its correlation time, > 0 where pos_gm_std_m > 0.
    quality : int
        RTKLIB Q reported: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP, 0 unknown.
    outages_s : sequence of (start, end)
        Outage intervals [start, end) in absolute time (the record's time scale), at most
        ``MAX_OUTAGES``.
    outage_first_s, outage_period_s, outage_duration_s : float
        Periodic outages: one of ``outage_duration_s`` every ``outage_period_s`` from
        ``outage_first_s`` (the "outage of T s every P s" protocol); duration 0: none.
    """
    rate_hz: float = 1.0
    offset_s: float = 0.0
    latency_s: float = 0.0
    lever_arm_m: tuple = (0.0, 0.0, 0.0)
    pos_std_m: tuple = (1.0, 1.0, 2.0)
    vel_std_m_s: tuple = (0.05, 0.05, 0.1)
    pos_gm_std_m: tuple = (0.0, 0.0, 0.0)
    pos_gm_tau_s: float = 100.0
    quality: int = 5
    outages_s: tuple = ()
    outage_first_s: float = 0.0
    outage_period_s: float = 0.0
    outage_duration_s: float = 0.0

    _C = "gnss"
    _SPEC = (("rate_hz", "gnss_rate", "r"), ("offset_s", "gnss_offset", "r"),
             ("latency_s", "gnss_latency", "r"),
             ("lever_arm_m", "gnss_lever_arm", "v"),
             ("pos_std_m", "gnss_pos_std", "v"),
             ("vel_std_m_s", "gnss_vel_std", "v"),
             ("pos_gm_std_m", "gnss_pos_gm_std", "v"),
             ("pos_gm_tau_s", "gnss_pos_gm_tau", "r"),
             ("quality", "gnss_q", "i"),
             ("outage_first_s", "gnss_outage_first", "r"),
             ("outage_period_s", "gnss_outage_period", "r"),
             ("outage_duration_s", "gnss_outage_duration", "r"))

    def _outages(self) -> np.ndarray:
        o = np.asarray(self.outages_s, dtype=float).reshape(-1, 2) if len(self.outages_s) else np.zeros((0, 2))
        if len(o) > MAX_OUTAGES:
            raise ValueError(f"GnssReceiver.outages_s: at most {MAX_OUTAGES} intervals; got "
                             f"{len(o)} (use the periodic rule for regular outages)")
        return o

    def _to_c(self, params) -> None:
        super()._to_c(params)
        o = self._outages()
        params.gnss.n_outages = len(o)
        params.gnss.outage_start_s[0:len(o)] = o[:, 0].tolist()
        params.gnss.outage_end_s[0:len(o)] = o[:, 1].tolist()

    def fmu_parameters(self) -> dict:
        o = self._outages()
        pad = [0.0] * (MAX_OUTAGES - len(o))
        return {**super().fmu_parameters(), "gnss_n_outages": len(o),
                "gnss_outage_start": o[:, 0].tolist() + pad, "gnss_outage_end": o[:, 1].tolist() + pad}


@dataclass(frozen=True)
class Barometer(_Sensor):
    """A barometric altimeter at the IMU: h + b + white noise, b = bias0_m + random walk
    + Gauss-Markov, sampled at ``start + offset_s + k / rate_hz``.

    Attributes
    ----------
    rate_hz, offset_s : float
        As :class:`GnssReceiver`.
    std_m : float
        White noise std (the reported std), m.
    bias0_m : float
        Constant part of the bias, m.
    bias_rw_m_sqrt_s : float
        Random walk of the bias, m/sqrt(s) (steps K sqrt(1/rate); 0 at the first sample).
    bias_gm_std_m, bias_gm_tau_s : float
        Gauss-Markov part of the bias: stationary std (m), correlation time (s).
    """
    rate_hz: float = 10.0
    offset_s: float = 0.0
    std_m: float = 0.5
    bias0_m: float = 0.0
    bias_rw_m_sqrt_s: float = 0.0
    bias_gm_std_m: float = 0.0
    bias_gm_tau_s: float = 100.0

    _C = "baro"
    _SPEC = (("rate_hz", "baro_rate", "r"), ("offset_s", "baro_offset", "r"),
             ("std_m", "baro_std", "r"), ("bias0_m", "baro_bias0", "r"),
             ("bias_rw_m_sqrt_s", "baro_bias_rw", "r"),
             ("bias_gm_std_m", "baro_bias_gm_std", "r"),
             ("bias_gm_tau_s", "baro_bias_gm_tau", "r"))


@dataclass(frozen=True)
class Odometer(_Sensor):
    """An odometer: the forward (body y) speed of the wheel point at ``lever_arm_m``,
    (1 + scale_error) u + white noise, sampled at ``start + offset_s + k / rate_hz``.

    Attributes
    ----------
    rate_hz, offset_s : float
        As :class:`GnssReceiver`.
    lever_arm_m : 3 floats
        IMU -> wheel contact point, body right-front-up, m.
    scale_error : float
        Scale-factor error k_odo (dimensionless), |k| < 0.5.
    std_m_s : float
        White noise std (the reported std), m/s.
    """
    rate_hz: float = 10.0
    offset_s: float = 0.0
    lever_arm_m: tuple = (0.0, 0.0, 0.0)
    scale_error: float = 0.0
    std_m_s: float = 0.05

    _C = "odo"
    _SPEC = (("rate_hz", "odo_rate", "r"), ("offset_s", "odo_offset", "r"),
             ("lever_arm_m", "odo_lever_arm", "v"),
             ("scale_error", "odo_scale_error", "r"),
             ("std_m_s", "odo_std", "r"))


@dataclass(frozen=True)
class GnssMeasurements:
    """GNSS epochs (the fields of the GnssRecord convention): time of validity ``t_s``
    (m,), antenna ``lat_rad``, ``lon_rad``, ``h_m`` (m,), ``pos_std_m`` (m, 3) ENU,
    ``vel_enu_m_s`` (m, 3), ``vel_std_m_s`` (m, 3), ``quality`` (m,) int8 (RTKLIB Q)."""
    t_s: np.ndarray
    lat_rad: np.ndarray
    lon_rad: np.ndarray
    h_m: np.ndarray
    pos_std_m: np.ndarray
    vel_enu_m_s: np.ndarray
    vel_std_m_s: np.ndarray
    quality: np.ndarray


@dataclass(frozen=True)
class BaroMeasurements:
    """Barometer samples (BaroRecord convention): ``t_s``, ``h_m``, ``std_m``, (k,)."""
    t_s: np.ndarray
    h_m: np.ndarray
    std_m: np.ndarray


@dataclass(frozen=True)
class OdometerMeasurements:
    """Odometer samples (OdometerRecord convention): ``t_s``, ``speed_m_s``,
    ``std_m_s``, (j,)."""
    t_s: np.ndarray
    speed_m_s: np.ndarray
    std_m_s: np.ndarray


@dataclass(frozen=True)
class AidingTruth:
    """Noise-free values at the same epochs as the measurements: the antenna's true
    position and velocity (``gnss``, the reported stds kept), the true height (``baro``)
    and the true forward wheel speed without scale error (``odometer``); the GNSS
    delivery times and the barometer's true bias (m)."""
    gnss: GnssMeasurements | None
    gnss_delivered_s: np.ndarray | None
    baro: BaroMeasurements | None
    baro_bias_m: np.ndarray | None
    odometer: OdometerMeasurements | None


#: gf_aiding_init's refusal codes -> the attribute refused
_BAD_AIDING = {
    int(lib.GF_AIDING_BAD_GNSS_RATE): "GnssReceiver.rate_hz",
    int(lib.GF_AIDING_BAD_GNSS_OFFSET): "GnssReceiver.offset_s",
    int(lib.GF_AIDING_BAD_GNSS_LATENCY): "GnssReceiver.latency_s",
    int(lib.GF_AIDING_BAD_GNSS_LEVER_ARM): "GnssReceiver.lever_arm_m",
    int(lib.GF_AIDING_BAD_GNSS_POS_STD): "GnssReceiver.pos_std_m",
    int(lib.GF_AIDING_BAD_GNSS_VEL_STD): "GnssReceiver.vel_std_m_s",
    int(lib.GF_AIDING_BAD_GNSS_GM_STD): "GnssReceiver.pos_gm_std_m",
    int(lib.GF_AIDING_BAD_GNSS_GM_TAU): "GnssReceiver.pos_gm_tau_s",
    int(lib.GF_AIDING_BAD_GNSS_QUALITY): "GnssReceiver.quality",
    int(lib.GF_AIDING_BAD_GNSS_PERIODIC): "GnssReceiver.outage_first_s/outage_period_s/outage_duration_s",
    int(lib.GF_AIDING_BAD_BARO_RATE): "Barometer.rate_hz",
    int(lib.GF_AIDING_BAD_BARO_OFFSET): "Barometer.offset_s",
    int(lib.GF_AIDING_BAD_BARO_STD): "Barometer.std_m",
    int(lib.GF_AIDING_BAD_BARO_BIAS0): "Barometer.bias0_m",
    int(lib.GF_AIDING_BAD_BARO_RW): "Barometer.bias_rw_m_sqrt_s",
    int(lib.GF_AIDING_BAD_BARO_GM_STD): "Barometer.bias_gm_std_m",
    int(lib.GF_AIDING_BAD_BARO_GM_TAU): "Barometer.bias_gm_tau_s",
    int(lib.GF_AIDING_BAD_ODO_RATE): "Odometer.rate_hz",
    int(lib.GF_AIDING_BAD_ODO_OFFSET): "Odometer.offset_s",
    int(lib.GF_AIDING_BAD_ODO_LEVER_ARM): "Odometer.lever_arm_m",
    int(lib.GF_AIDING_BAD_ODO_SCALE): "Odometer.scale_error",
    int(lib.GF_AIDING_BAD_ODO_STD): "Odometer.std_m_s",
}


def _describe_bad_aiding(bad: int) -> str:
    why = ffi.string(lib.gf_aiding_bad_string(bad)).decode()
    if bad >= lib.GF_AIDING_BAD_GNSS_OUTAGE:
        return f"GnssReceiver.outages_s[{bad - lib.GF_AIDING_BAD_GNSS_OUTAGE}] {why}"
    return f"{_BAD_AIDING.get(bad, 'an aiding sensor parameter')} {why}"


class _AidingRun:
    """The aiding sensors of one simulate_vehicle call: gf_aiding_init on the vehicle at
    its start, then gf_aiding_run to the last sample (one C call)."""

    def __init__(self, vehicle, gnss, baro, odometer, seed):
        for name, value, cls in (("gnss", gnss, GnssReceiver), ("baro", baro, Barometer),
                                 ("odometer", odometer, Odometer)):
            if value is not None and not isinstance(value, cls):
                raise TypeError(f"{name} must be a {cls.__name__} or None; got {type(value).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, (numbers.Integral, np.integer)) \
                or not 0 <= int(seed) < 2 ** 64:
            raise ValueError(f"seed must be an integer in [0, 2**64); got {seed!r}")
        self.sensors = {"gnss": gnss, "baro": baro, "odo": odometer}
        params = ffi.new("gf_aiding_params *")
        for s in self.sensors.values():
            if s is not None:
                s._to_c(params)
        self.params = params
        self.t0_s = float(vehicle.time_s)
        self.sim = ffi.new("gf_aiding_sim *")
        bad = ffi.new("int *")
        st = lib.gf_aiding_init(self.sim, params, vehicle, int(seed), ffi.NULL, bad)
        if st == lib.GF_ERR_BAD_PARAMETER:
            raise ValueError(f"aiding sensor rejected: {_describe_bad_aiding(bad[0])}")
        check_status(st, "gf_aiding_init")

    def _capacity(self, sensor, t_end_s: float) -> int:
        if sensor is None:
            return 0
        return max(0, int(np.floor((t_end_s - self.t0_s - sensor.offset_s) * sensor.rate_hz))) + 2

    def run(self, t_end_s: float) -> dict:
        caps = {k: self._capacity(s, t_end_s) for k, s in self.sensors.items()}
        bufs = {k: np.zeros((caps[k], _doubles(f"gf_{k}_epoch"))) for k in caps}
        ptrs = {k: ffi.cast(f"gf_{k}_epoch *", ptr(b, b.size)) if caps[k] else ffi.NULL
                for k, b in bufs.items()}
        n = {k: ffi.new("size_t *") for k in caps}
        st = lib.gf_aiding_run(self.sim, t_end_s, ptrs["gnss"], caps["gnss"], n["gnss"],
                               ptrs["baro"], caps["baro"], n["baro"], ptrs["odo"], caps["odo"], n["odo"])
        check_status(st, f"gf_aiding_run (GNSS, barometer, odometer epochs done: "
                         f"{n['gnss'][0]}, {n['baro'][0]}, {n['odo'][0]})")
        c = {k: _columns(bufs[k][:n[k][0]], f"gf_{k}_epoch") for k in caps}
        out, truth = {}, dict(gnss=None, gnss_delivered_s=None, baro=None, baro_bias_m=None,
                              odometer=None)
        if self.sensors["gnss"] is not None:
            g = c["gnss"]
            q = g["quality"].astype(np.int8)
            out["gnss"] = GnssMeasurements(g["t_s"], g["lat_rad"], g["lon_rad"], g["h_m"], g["pos_std_m"],
                                           g["vel_enu_m_s"], g["vel_std_m_s"], q)
            truth["gnss"] = GnssMeasurements(g["t_s"], g["true_lat_rad"], g["true_lon_rad"], g["true_h_m"],
                                             g["pos_std_m"], g["true_vel_enu_m_s"], g["vel_std_m_s"], q)
            truth["gnss_delivered_s"] = g["t_delivered_s"]
        if self.sensors["baro"] is not None:
            b = c["baro"]
            out["baro"] = BaroMeasurements(b["t_s"], b["h_m"], b["std_m"])
            truth["baro"] = BaroMeasurements(b["t_s"], b["true_h_m"], b["std_m"])
            truth["baro_bias_m"] = b["bias_m"]
        if self.sensors["odo"] is not None:
            o = c["odo"]
            out["odometer"] = OdometerMeasurements(o["t_s"], o["speed_m_s"], o["std_m_s"])
            truth["odometer"] = OdometerMeasurements(o["t_s"], o["true_speed_m_s"], o["std_m_s"])
        return {**out, "aiding_truth": AidingTruth(**truth)}


_BAD = {1: "lat0_rad: |latitude| must be < 89 deg", 2: "h0_m must be in [-1000, 1e5] m",
        3: "speed0_m_s must be >= 0"}


def describe_bad_profile(bad: int) -> str:
    if bad >= 100:
        return (f"segment {bad - 100}: duration_s must be > 0 and the speed must stay >= 0 "
                "(the sum of dspeed_m_s so far is negative)")
    return _BAD.get(bad, "a parameter is out of range")


@dataclass
class VehicleRecord(Trajectory):
    """A sampled vehicle run (a :class:`~gfins_fmi.sim.trajectory.Trajectory` plus the
    angular acceleration, displacement, speed and heading rate, all from the C core), and
    the aiding sensors' measurements when simulated (``gnss``, ``baro``, ``odometer``;
    their noise-free values in ``aiding_truth``)."""
    gyro_dot_rad_s2: np.ndarray = None
    euler_rad: np.ndarray = None
    east_m: np.ndarray = None
    north_m: np.ndarray = None
    speed_m_s: np.ndarray = None
    heading_rate_rad_s: np.ndarray = None
    gnss: "GnssMeasurements | None" = None
    baro: "BaroMeasurements | None" = None
    odometer: "OdometerMeasurements | None" = None
    aiding_truth: "AidingTruth | None" = None

    def array_outputs(self, geometry) -> np.ndarray:
        """Outputs (n, N) of an accelerometer array of any geometry at the samples."""
        return forward_model(geometry, self.accel_m_s2, self.gyro_rad_s, self.gyro_dot_rad_s2)


def simulate_vehicle(profile: VehicleProfile, duration_s: float, dt_s: float,
                     start_time_s: float = 0.0, *, gnss: "GnssReceiver | None" = None,
                     baro: "Barometer | None" = None, odometer: "Odometer | None" = None,
                     seed: int = 0) -> VehicleRecord:
    """Run the vehicle for ``duration_s`` and sample it every ``dt_s`` (n = duration/dt + 1
    samples, the first at ``start_time_s``), in one C call; with aiding sensors, their
    epochs up to the last sample in one more.

    Parameters
    ----------
    profile : VehicleProfile
    duration_s, dt_s : float
        Length of the run and IMU sampling interval, s.
    start_time_s : float
        Time of the first sample; the aiding sensors' epochs count from it.
    gnss, baro, odometer : GnssReceiver, Barometer, Odometer, optional
        Aiding sensors to simulate (None: not simulated).
    seed : int
        Seed of the aiding sensors' generators, 0 <= seed < 2**64 (each sensor has its own
        stream). The vehicle FMU draws the same numbers with ``noise_seed = seed`` for
        seed < 2**31.

    Returns
    -------
    VehicleRecord
        The IMU record and truth; ``gnss``, ``baro``, ``odometer`` hold the epochs
        delivered by the last sample (time of validity + latency <= end), in time order,
        and ``aiding_truth`` their noise-free values.

    Raises
    ------
    ValueError
        A profile or sensor parameter is out of range (the message names it), or bad
        durations.
    GfinsError
        The motion left the domain (latitude beyond 89 deg).
    """
    if not (dt_s > 0 and np.isfinite(dt_s)) or not (duration_s >= 0 and np.isfinite(duration_s)):
        raise ValueError(f"dt_s must be > 0 and duration_s >= 0 (s); got {dt_s}, {duration_s}")
    start_time_s = as_scalar("start_time_s", start_time_s, "s")
    n = int(round(duration_s / dt_s)) + 1
    state = ffi.new("gf_vehicle_state *")
    buf = np.zeros((n, _doubles("gf_vehicle_sample")))
    samples = ffi.cast("gf_vehicle_sample *", ptr(buf, buf.size))
    bad = ffi.new("int *")
    st = lib.gf_vehicle_init(state, profile.to_c(), start_time_s, samples, bad)
    if st == lib.GF_ERR_BAD_PARAMETER:
        raise ValueError(f"vehicle profile rejected: {describe_bad_profile(bad[0])}")
    check_status(st, "gf_vehicle_init")
    sensors = _AidingRun(state, gnss, baro, odometer, seed) if (gnss or baro or odometer) else None
    done = ffi.new("size_t *")
    st = lib.gf_vehicle_run(state, n - 1, float(dt_s), samples + 1, done)
    check_status(st, f"gf_vehicle_run (stopped at sample {done[0] + 1} of {n})")
    cols = _columns(buf, "gf_vehicle_sample")
    aiding = sensors.run(float(cols["time_s"][-1])) if sensors else {}
    return VehicleRecord(
        t_s=cols["time_s"], lat_rad=cols["lat_rad"], lon_rad=cols["lon_rad"], h_m=cols["h_m"],
        v_n_m_s=cols["v_n_m_s"], q_bn=cols["q_bn"], gyro_rad_s=cols["gyro_rad_s"],
        accel_m_s2=cols["accel_m_s2"], dtheta_rad=cols["dtheta_rad"][1:],
        dv_m_s=cols["dv_m_s"][1:], motion=None, gyro_dot_rad_s2=cols["gyro_dot_rad_s2"],
        euler_rad=cols["euler_rad"], east_m=cols["east_m"], north_m=cols["north_m"],
        speed_m_s=cols["speed_m_s"], heading_rate_rad_s=cols["heading_rate_rad_s"], **aiding)
