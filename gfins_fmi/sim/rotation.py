"""Rotating IMU (C core ``gf_rotation``; seed 001): the two-axis indexing mechanism, rotation
schedules (seed 001's 18-position calibration path, turntable paths about the IMU's own
axes, indexing and continuous modulation schemes) and the exact outputs of an IMU riding
the mechanism on a static base or on a vehicle. Their navigation (rotation modulation, the
vehicle attitude from the gimbal angles) is :mod:`gfins_fmi.nav.rotating`.

Frames and the mechanism (csrc/sim/gf_rot.h): base b fixed to the vehicle (right-front-up),
IMU frame m; middle axis = base x, inner axis = IMU z, C_m^b = R_x(alpha) R_z(beta), both
angles right-handed (the seed's "clockwise", seen looking along the axis). A schedule is
a sequence of :class:`Turn` (a turn about a base axis and/or an IMU axis, then a rest).
Angles in this module's arguments are in degrees where the name says ``_deg``; arrays
handed back are in radians (``_rad``).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from gfins_fmi._lib import (as_array, as_scalar, check_status, ffi, lib, ptr,
                            struct_columns, struct_doubles)
from gfins_fmi.io.records import ImuRecord
from gfins_fmi.nav.earth import quat_multiply, quat_to_dcm
from gfins_fmi.nav.strapdown import NavState
from gfins_fmi.sim.vehicle import describe_bad_profile

__all__ = ["Turn", "rest", "middle", "inner", "about_imu", "about_base", "RotationSchedule",
           "SEED001_TABLE", "seed001_path", "path_table", "check_seed001_table",
           "indexing_scheme", "continuous_scheme", "turntable_path_19", "RotatingImuRecord",
           "simulate_static", "simulate_on_vehicle", "MAX_TURNS"]

MAX_TURNS = int(lib.GF_ROT_MAX_SEGMENTS)
_AXES = {None: -1, "x": 0, "y": 1, "z": 2}
_DEG = np.pi / 180.0


@dataclass(frozen=True)
class Turn:
    """One segment of a schedule: a turn about a base axis (fixed in the vehicle; the
    middle axis is ``"x"``) and/or an IMU axis (the inner axis is ``"z"``) by signed
    angles (deg, right-handed), the larger of the two at ``rate_deg_s`` after a smooth
    ramp of ``ramp_s`` (and the same ramp down), then a rest of ``dwell_s``. A turn of no
    angle is a rest."""
    base_axis: str | None = None
    base_angle_deg: float = 0.0
    imu_axis: str | None = None
    imu_angle_deg: float = 0.0
    rate_deg_s: float = 5.0
    ramp_s: float = 1.0
    dwell_s: float = 0.0

    @property
    def angle_deg(self) -> float:
        return max(abs(self.base_angle_deg), abs(self.imu_angle_deg))

    @property
    def move_s(self) -> float:
        """Duration of the turn (0 for a rest)."""
        return 0.0 if self.angle_deg == 0 else self.angle_deg / self.rate_deg_s + self.ramp_s

    @property
    def duration_s(self) -> float:
        return self.move_s + self.dwell_s


def rest(dwell_s: float) -> Turn:
    """A rest of ``dwell_s`` (e.g. the 10 min alignment of seed 001)."""
    return Turn(dwell_s=dwell_s, ramp_s=0.0)


def middle(angle_deg: float, dwell_s: float = 0.0, rate_deg_s: float = 5.0,
           ramp_s: float = 1.0) -> Turn:
    """A turn of the middle (outer) axis, base x."""
    return Turn("x", angle_deg, None, 0.0, rate_deg_s, ramp_s, dwell_s)


def inner(angle_deg: float, dwell_s: float = 0.0, rate_deg_s: float = 5.0,
          ramp_s: float = 1.0) -> Turn:
    """A turn of the inner axis, IMU z."""
    return Turn(None, 0.0, "z", angle_deg, rate_deg_s, ramp_s, dwell_s)


def _signed_axis(axis: str) -> tuple[str, float]:
    a = axis.strip().lower()
    sign = -1.0 if a.startswith("-") else 1.0
    a = a.lstrip("+-")
    if a not in ("x", "y", "z"):
        raise ValueError(f"axis must be x, y or z with an optional sign (e.g. '-y'); got {axis!r}")
    return a, sign


def about_imu(axis: str, angle_deg: float, dwell_s: float = 0.0, rate_deg_s: float = 5.0,
              ramp_s: float = 1.0) -> Turn:
    """A turntable turn about the IMU's own axis (``"x"``, ``"-y"``, ...)."""
    a, s = _signed_axis(axis)
    return Turn(None, 0.0, a, s * angle_deg, rate_deg_s, ramp_s, dwell_s)


def about_base(axis: str, angle_deg: float, dwell_s: float = 0.0, rate_deg_s: float = 5.0,
               ramp_s: float = 1.0) -> Turn:
    """A turn about an axis fixed in the base (``"x"`` is the middle axis)."""
    a, s = _signed_axis(axis)
    return Turn(a, s * angle_deg, None, 0.0, rate_deg_s, ramp_s, dwell_s)


_BAD_SCHEDULE = {
    int(lib.GF_ROT_BAD_START): "q_mb0 must be a unit quaternion",
    int(lib.GF_ROT_BAD_REPEAT): "a repeated schedule must bring the IMU back to its start "
                                "attitude after one cycle (e.g. each axis turned by whole turns)",
    int(lib.GF_ROT_BAD_EMPTY_CYCLE): "a repeated schedule needs a cycle longer than 0 s",
}


@dataclass(frozen=True)
class RotationSchedule:
    """A sequence of turns (``repeat``: the sequence repeats; one cycle must then bring
    the IMU back to ``q_mb0``), starting from the IMU attitude ``q_mb0`` on the base
    (C_m^b, scalar first). Checked by the C core when built (``ValueError`` naming the
    turn and the rule)."""
    turns: tuple
    repeat: bool = False
    q_mb0: tuple = (1.0, 0.0, 0.0, 0.0)
    _state: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "turns", tuple(self.turns))
        if len(self.turns) > MAX_TURNS:
            raise ValueError(f"a schedule has at most {MAX_TURNS} turns; got {len(self.turns)} "
                             "(repeat a shorter cycle with repeat=True)")
        for k, t in enumerate(self.turns):
            if not isinstance(t, Turn):
                raise TypeError(f"turns[{k}] must be a Turn; got {type(t).__name__}")
            for name in ("base_angle_deg", "imu_angle_deg", "ramp_s", "dwell_s"):
                as_scalar(f"turns[{k}].{name}", getattr(t, name), "deg or s")
            if t.angle_deg:
                as_scalar(f"turns[{k}].rate_deg_s", t.rate_deg_s, "deg/s", above=0.0)
            for name in ("base_axis", "imu_axis"):
                if getattr(t, name) not in _AXES:
                    raise ValueError(f"turns[{k}].{name} must be None, 'x', 'y' or 'z'; got "
                                     f"{getattr(t, name)!r}")
            if t.base_angle_deg and t.base_axis is None or t.imu_angle_deg and t.imu_axis is None:
                raise ValueError(f"turns[{k}]: an angle needs its axis")
            if t.angle_deg and t.angle_deg / t.rate_deg_s < t.ramp_s:
                raise ValueError(f"turns[{k}]: the turn of {t.angle_deg:g} deg at {t.rate_deg_s:g} "
                                 f"deg/s lasts {t.angle_deg / t.rate_deg_s:g} s, shorter than its "
                                 f"ramp_s = {t.ramp_s:g} s: shorten the ramp or slow the turn")
        object.__setattr__(self, "_state", self._c_state(0.0))

    def c_schedule(self):
        """The schedule as a ``gf_rot_schedule`` (cffi)."""
        s = ffi.new("gf_rot_schedule *")
        s.q_mb0 = [float(v) for v in as_array("q_mb0", self.q_mb0, (4,), "1")]
        s.n_segments = len(self.turns)
        s.repeat = int(bool(self.repeat))
        for k, t in enumerate(self.turns):
            g = s.segment[k]
            g.base_axis = _AXES[t.base_axis]
            g.imu_axis = _AXES[t.imu_axis]
            g.base_angle_rad = t.base_angle_deg * _DEG
            g.imu_angle_rad = t.imu_angle_deg * _DEG
            g.move_s = t.move_s
            g.ramp_s = t.ramp_s if t.angle_deg else 0.0
            g.dwell_s = t.dwell_s
        return s

    def _c_state(self, t0_s: float):
        st = ffi.new("gf_rot_state *")
        bad = ffi.new("int *")
        status = lib.gf_rot_init(st, self.c_schedule(), float(t0_s), bad)
        if status == lib.GF_ERR_BAD_PARAMETER:
            b = int(bad[0])
            if b >= int(lib.GF_ROT_BAD_SEGMENT):
                k = b - int(lib.GF_ROT_BAD_SEGMENT)
                raise ValueError(f"turns[{k}] = {self.turns[k]} is refused: durations must be >= 0, "
                                 "a turn needs a duration, 2 ramp_s <= its duration, and the rate "
                                 f"at most {lib.GF_ROT_MAX_RATE_MDEG_S / 1000:g} deg/s")
            raise ValueError(f"schedule refused: {_BAD_SCHEDULE.get(b, f'code {b}')}")
        check_status(status, "gf_rot_init")
        return st

    def c_state(self, t0_s: float = 0.0):
        """The derived ``gf_rot_state`` with the schedule starting at ``t0_s``."""
        return self._state if t0_s == 0.0 else self._c_state(as_scalar("t0_s", t0_s, "s"))

    @property
    def duration_s(self) -> float:
        """Duration of the turns (one cycle when repeated)."""
        return float(self._state.cycle_s)

    @property
    def is_mechanism(self) -> bool:
        """Only middle and inner turns from the zero position: gimbal angles exist."""
        return bool(self._state.gimbal)

    @property
    def turn_end_times_s(self) -> np.ndarray:
        """End of each turn's rest (s from the start)."""
        return np.array([self._state.seg_t0_s[k + 1] for k in range(len(self.turns))])

    def fmu_parameters(self) -> dict:
        """The schedule as start values of the vehicle FMU (rotation = 1; arrays padded to
        MAX_TURNS). The FMU starts the schedule at its start time; q_mb0 must be the
        identity (the mechanism's zero position)."""
        if not np.allclose(np.abs(self.q_mb0), [1.0, 0.0, 0.0, 0.0]):
            raise ValueError("the vehicle FMU starts the IMU at the mechanism's zero position: "
                             "q_mb0 must be (1, 0, 0, 0)")
        s = self.c_schedule()
        n = len(self.turns)
        pad = MAX_TURNS - n

        def col(name, fill):
            return [getattr(s.segment[k], name) for k in range(n)] + [fill] * pad
        return {"rotation": 1, "rot_n": n, "rot_repeat": int(bool(self.repeat)),
                "rot_base_axis": col("base_axis", -1), "rot_imu_axis": col("imu_axis", -1),
                "rot_base_angle": col("base_angle_rad", 0.0), "rot_imu_angle": col("imu_angle_rad", 0.0),
                "rot_move": col("move_s", 0.0), "rot_ramp": col("ramp_s", 0.0),
                "rot_dwell": col("dwell_s", 0.0)}

    def poses(self, t_s, t0_s: float = 0.0) -> dict:
        """The mechanism at the times ``t_s`` (n,): ``q_mb`` (n, 4), ``w_bm_m_rad_s``
        (n, 3), ``gimbal_rad`` (n, 2: middle, inner)."""
        t = as_array("t_s", np.atleast_1d(t_s), (None,), "s")
        n = t.size
        q, w, g = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 2))
        done = ffi.new("size_t *")
        check_status(lib.gf_rot_poses(self.c_state(t0_s), n, ptr(t, n), ptr(q, 4 * n),
                                      ptr(w, 3 * n), ptr(g, 2 * n), done), "gf_rot_poses")
        return {"q_mb": q, "w_bm_m_rad_s": w, "gimbal_rad": g}


# ---- seed 001's calibration path ---------------------------------------------------------

#: Seed 001's path (its table 1 and steps 0-18): (axis, angle in deg, directions of
#: x_m, y_m, z_m after the turn; E N U W S D). Each row follows from the previous one by
#: the mechanism's kinematics (tests/sim/test_rotation.py, docs/rotating_ins.md).
SEED001_TABLE = (
    ("start", 0, "ENU"), ("middle", 90, "EUS"), ("middle", 180, "EDN"), ("middle", 180, "EUS"),
    ("inner", 90, "UWS"), ("inner", 180, "DES"), ("inner", 180, "UWS"), ("middle", 90, "SWD"),
    ("middle", 180, "NWU"), ("middle", 180, "SWD"), ("middle", 90, "DWN"), ("middle", 90, "NWU"),
    ("middle", 90, "UWS"), ("inner", 90, "WDS"), ("inner", 90, "DES"), ("inner", 90, "EUS"),
    ("middle", 90, "ESD"), ("middle", 90, "EDN"), ("middle", 90, "ENU"))


def seed001_path(repeats: int = 2, align_s: float = 600.0, dwell_s: float = 180.0,
                 rate_deg_s: float = 5.0, ramp_s: float = 1.0) -> RotationSchedule:
    """Seed 001's calibration path: ``align_s`` at rest in position 0 (x_m E, y_m N,
    z_m U with the base level and heading north), then the 18 turns of
    :data:`SEED001_TABLE` at ``rate_deg_s`` (seed: 5 deg/s), each followed by ``dwell_s``
    at rest (seed: 180 s), run ``repeats`` times (seed: 1-3, typically 2)."""
    if not (isinstance(repeats, int) and 1 <= repeats <= 3):
        raise ValueError(f"repeats must be 1, 2 or 3 (seed 001 runs the path 1-3 times); got {repeats!r}")
    turns = [rest(align_s)]
    for _ in range(repeats):
        for axis, angle, _dirs in SEED001_TABLE[1:]:
            make = middle if axis == "middle" else inner
            turns.append(make(angle, dwell_s, rate_deg_s, ramp_s))
    return RotationSchedule(tuple(turns))


_DIR_NAMES = {(1, 0, 0): "E", (-1, 0, 0): "W", (0, 1, 0): "N", (0, -1, 0): "S", (0, 0, 1): "U",
              (0, 0, -1): "D"}


def path_table(schedule: RotationSchedule) -> list[str]:
    """Directions (E N U W S D, ``?`` if not along one) of x_m, y_m, z_m at the end of
    each turn's rest, the base level and heading north (C_m^n = C_m^b), e.g. ``"EUS"``."""
    out = []
    for t in schedule.turn_end_times_s - 1e-6:
        C = quat_to_dcm(schedule.poses([t])["q_mb"][0])
        out.append("".join(_DIR_NAMES.get(tuple(int(v) for v in np.round(C[:, k])), "?")
                           if np.allclose(np.abs(C[:, k]).max(), 1.0, atol=1e-9) else "?"
                           for k in range(3)))
    return out


def check_seed001_table() -> list[dict]:
    """Each row of :data:`SEED001_TABLE` against the directions the mechanism gives after
    the row's turn from the previous position: a list of ``{"row", "turn", "published",
    "computed", "agrees"}``."""
    got = path_table(seed001_path(repeats=1, align_s=1.0, dwell_s=1.0))
    return [{"row": k, "turn": f"{axis} +{angle}" if angle else axis, "published": dirs,
             "computed": got[k], "agrees": got[k] == dirs}
            for k, (axis, angle, dirs) in enumerate(SEED001_TABLE)]


def turntable_path_19(dwells_s=None, rate_deg_s: float = 6.0, ramp_s: float = 0.5,
                      align_s: float = 300.0) -> RotationSchedule:
    """A 19-position turntable path: 18 turns of 90 deg about the IMU's own axes (+-x,
    +-y, +-z), each turned axis horizontal when it turns (so that its scale factor and
    misalignment tilt the IMU and show in the velocity at once), every axis up and down,
    every axis turned both ways at least twice, back to the start; after
    ``align_s`` at rest, ``dwells_s`` (18 values; default 20-70 s) after the turns. The
    sequence was chosen among random ones with these properties as the one whose worst
    observed parameter (gyro biases excepted: they need time, not turns) is best
    determined (calibration.system.covariance_study, 45 s dwells)."""
    seq = ("-x", "-z", "+z", "-z", "+z", "+x", "+x", "-x", "+y", "-y", "-y", "-y", "-x", "-z",
           "+z", "+x", "+y", "+y")
    if dwells_s is None:
        dwells_s = [20 + (37 * k) % 51 for k in range(18)]
    dwells_s = as_array("dwells_s", dwells_s, (18,), "s")
    turns = [rest(align_s)] + [about_imu(a, 90.0, float(d), rate_deg_s, ramp_s)
                               for a, d in zip(seq, dwells_s)]
    return RotationSchedule(tuple(turns))


def indexing_scheme(positions: int = 8, dwell_s: float = 10.0, rate_deg_s: float = 10.0,
                    ramp_s: float = 1.0) -> RotationSchedule:
    """A repeated dual-axis indexing scheme of 180 deg turns, each followed by a rest of
    ``dwell_s``:

    * 8 positions (the classic sequence: inner +180, middle +180, inner -180, middle
      -180, middle -180, inner -180, middle +180, inner +180): every axis turns both
      ways and every IMU axis spends equal time up and down, so constant biases cancel
      over a cycle. The inner turns do not cancel: each -180 is made with the inner axis
      pointing down, so all four turn the IMU the same way about the vertical, and the z
      gyro's scale factor error leaves 4 pi dK_gz of heading per cycle (126 urad for
      10 ppm; bench/study_rotation_modulation.py: 61 km in 8 h);
    * 16 positions: the 8 followed by the 8 with the roles of the axes exchanged (middle
      first), which cancels the turns' scale-factor errors as well (net attitude error
      of a cycle zero to round-off).
    """
    if positions not in (8, 16):
        raise ValueError(f"positions must be 8 or 16; got {positions!r}")
    a = [("i", 180), ("m", 180), ("i", -180), ("m", -180), ("m", -180), ("i", -180),
         ("m", 180), ("i", 180)]
    if positions == 16:
        a = a + [("m" if ax == "i" else "i", ang) for ax, ang in a]
    turns = tuple((inner if ax == "i" else middle)(ang, dwell_s, rate_deg_s, ramp_s)
                  for ax, ang in a)
    return RotationSchedule(turns, repeat=True)


def continuous_scheme(inner_rate_deg_s: float = 6.0, middle_rate_deg_s: float = 3.0,
                      half_cycle_s: float = 120.0, reverse: bool = True,
                      ramp_s: float = 1.0) -> RotationSchedule:
    """Continuous dual-axis rotation: both axes turn at once, the inner at
    ``inner_rate_deg_s`` and the middle at ``middle_rate_deg_s``, for ``half_cycle_s``
    (each must then make whole turns); with ``reverse`` the next half cycle turns both
    back (the reversal cancels the scale-factor error of the rotation itself)."""
    T = as_scalar("half_cycle_s", half_cycle_s, "s", above=0.0)
    wi = as_scalar("inner_rate_deg_s", inner_rate_deg_s, "deg/s")
    wm = as_scalar("middle_rate_deg_s", middle_rate_deg_s, "deg/s")
    ai, am = wi * T, wm * T
    for name, a in (("inner", ai), ("middle", am)):
        if abs(a / 360.0 - round(a / 360.0)) > 1e-9:
            raise ValueError(f"the {name} axis turns {a:g} deg per half cycle: make it whole turns "
                             "(rate x half_cycle_s a multiple of 360 deg)")
    # the larger angle sets the turn's rate; the ramps stretch the half cycle by ramp_s
    fwd = Turn("x" if am else None, am, "z" if ai else None, ai, max(abs(wi), abs(wm)), ramp_s, 0.0)
    turns = [fwd]
    if reverse:
        turns.append(dataclasses.replace(fwd, base_angle_deg=-am, imu_angle_deg=-ai))
    return RotationSchedule(tuple(turns), repeat=True)


# ---- simulation ---------------------------------------------------------------------------

@dataclass(frozen=True)
class RotatingImuRecord:
    """An IMU record of a rotating IMU: increments over (t_s[k] - dt, t_s[k]] in the IMU
    frame m, the true C_m^n and gimbal angles at t_s, and the base (static: its position
    and attitude; on a vehicle: the vehicle's truth per sample in ``vehicle``, and the IMU
    frame's exact rate w_im^m at t_s in ``w_im_m_rad_s``)."""
    t_s: np.ndarray
    dtheta_rad: np.ndarray
    dv_m_s: np.ndarray
    q_mn: np.ndarray
    gimbal_rad: np.ndarray
    dt_s: float
    lat_rad: float
    lon_rad: float
    h_m: float
    q_bn_base: np.ndarray
    schedule: RotationSchedule
    accel_delay_s: float = 0.0
    vehicle: object = None
    initial: object = None
    w_im_m_rad_s: object = None

    @property
    def dt_s_array(self) -> np.ndarray:
        return np.full(self.t_s.size, self.dt_s)

    def imu_record(self, dtheta_rad=None, dv_m_s=None, source: str = "gfins_fmi rotating IMU"):
        """As an :class:`gfins_fmi.io.ImuRecord` of increments (the given ones, e.g. with
        sensor errors applied, or the exact ones)."""
        return ImuRecord(self.t_s, self.dtheta_rad if dtheta_rad is None else dtheta_rad,
                         self.dv_m_s if dv_m_s is None else dv_m_s, "increments", source)


def simulate_static(schedule: RotationSchedule, duration_s: float, dt_s: float,
                    lat_rad: float, h_m: float, lon_rad: float = 0.0, heading_rad: float = 0.0,
                    accel_delay_s: float = 0.0) -> RotatingImuRecord:
    """Exact increments of an IMU turned by ``schedule`` on a static, level base heading
    ``heading_rad`` (clockwise from north) at (``lat_rad``, ``h_m``): n = duration/dt
    samples, one C call. ``accel_delay_s`` delays the accelerometer samples (|delay| <=
    dt; the gyro-accelerometer asynchrony of real systems).

    Raises
    ------
    ValueError
        Bad durations (a sample interval above 10 s), latitude beyond 89 deg, or a delay
        longer than a sample.
    """
    dt = as_scalar("dt_s", dt_s, "s", above=0.0, at_most=10.0)   # sim/gf_rot.h GF_ROT_MAX_DT_S
    dur = as_scalar("duration_s", duration_s, "s", above=0.0)
    lat = as_scalar("lat_rad", lat_rad, "rad", above=-np.radians(89.0), below=np.radians(89.0))
    h = as_scalar("h_m", h_m, "m", at_least=-1000.0, at_most=1e5)
    delay = as_scalar("accel_delay_s", accel_delay_s, "s", at_least=-dt, at_most=dt)
    psi = as_scalar("heading_rad", heading_rad, "rad")
    n = int(round(dur / dt))
    if n < 1:
        raise ValueError(f"duration_s = {dur} s holds no sample of dt_s = {dt} s")
    q_base = np.array([np.cos(psi / 2), 0.0, 0.0, -np.sin(psi / 2)])   # Rz(-psi)
    dth, dv, q, g = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 2))
    done = ffi.new("size_t *")
    check_status(lib.gf_rot_imu_static(schedule.c_state(), ptr(q_base, 4), lat, h, 0.0, n, dt,
                                       delay, ptr(dth, 3 * n), ptr(dv, 3 * n), ptr(q, 4 * n),
                                       ptr(g, 2 * n), done),
                 f"gf_rot_imu_static (stopped at sample {done[0]})")
    lon = as_scalar("lon_rad", lon_rad, "rad")
    q0 = quat_multiply(q_base, schedule.poses([0.0])["q_mb"][0])
    return RotatingImuRecord(np.arange(1, n + 1) * dt, dth, dv, q, g, dt, lat, lon, h, q_base,
                             schedule, delay, None, NavState(q0, np.zeros(3), lat, lon, h, 0.0))


def simulate_on_vehicle(schedule: RotationSchedule, profile, duration_s: float,
                        dt_s: float) -> RotatingImuRecord:
    """The rotating IMU on the vehicle of ``profile`` (:class:`gfins_fmi.sim.vehicle.
    VehicleProfile`), n = duration/dt samples after the start, in one C call. The
    vehicle's truth at each sample end is in ``record.vehicle`` (a dict of arrays: t_s,
    q_bn, v_n_m_s, lat_rad, lon_rad, h_m; body rates and increments)."""
    dt = as_scalar("dt_s", dt_s, "s", above=0.0)
    n = int(round(as_scalar("duration_s", duration_s, "s", above=0.0) / dt))
    if n < 1:
        raise ValueError(f"duration_s = {duration_s} s holds no sample of dt_s = {dt} s")
    veh = ffi.new("gf_vehicle_state *")
    first = ffi.new("gf_vehicle_sample *")
    bad = ffi.new("int *")
    st = lib.gf_vehicle_init(veh, profile.to_c(), 0.0, first, bad)
    if st == lib.GF_ERR_BAD_PARAMETER:
        raise ValueError(f"vehicle profile rejected: {describe_bad_profile(bad[0])}")
    check_status(st, "gf_vehicle_init")
    buf = np.zeros((n, struct_doubles("gf_vehicle_sample")))
    dth, dv, q, g = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 4)), np.empty((n, 2))
    w = np.empty((n, 3))
    done = ffi.new("size_t *")
    st = lib.gf_rot_imu_vehicle(schedule.c_state(), veh, n, dt, ptr(dth, 3 * n), ptr(dv, 3 * n),
                                ptr(w, 3 * n), ffi.NULL, ptr(g, 2 * n), ptr(q, 4 * n),
                                ffi.cast("gf_vehicle_sample *", ptr(buf, buf.size)), done)
    check_status(st, f"gf_rot_imu_vehicle (stopped at sample {done[0]} of {n})")
    cols = {k: np.array(v) for k, v in struct_columns(buf, "gf_vehicle_sample").items()}
    qb0 = np.array(list(first.q_bn))
    q0 = quat_multiply(qb0, schedule.poses([0.0])["q_mb"][0])
    return RotatingImuRecord(cols["time_s"], dth, dv, q, g, dt, float(first.lat_rad),
                             float(first.lon_rad), float(first.h_m), qb0, schedule, 0.0, cols,
                             NavState(q0, np.array(list(first.v_n_m_s)), float(first.lat_rad),
                                      float(first.lon_rad), float(first.h_m), 0.0), w)
