"""Co-simulated systems: which FMUs take part, with which start values, and how they are
connected (:class:`System`, :class:`Connection`), and the builders of the usual ones: the
vehicle FMU feeding a navigator FMU (:func:`vehicle_navigation`), the vehicle with its
aiding sensors feeding the integrated navigator (:func:`vehicle_integrated_navigation`,
with :class:`InitialError` and the worked example :func:`integrated_example`), and a host
with a master INS and a slave IMU feeding the transfer-alignment FMU
(:func:`vehicle_transfer_alignment`).

Sampling. Every shipped FMU holds, after ``doStep(t, h)``, outputs describing one time:
the vehicle's describe t + h (``time_s`` output), a navigator's the sample it took at t.
A master must therefore hand a navigator the vehicle's outputs *at* t, i.e. pass the
outputs read after the previous step (Jacobi), or step the navigator before the vehicle
(Gauss-Seidel order ``["navigator", "vehicle"]``). See docs/cosim.md.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

from gfins_fmi._lib import as_scalar, as_vector3, lib
from gfins_fmi.estimation.config import FilterConfig, InitialState
from gfins_fmi.estimation.transfer import MasterErrors
from gfins_fmi.fmi.ins_gnss import ins_gnss_fmu_parameters
from gfins_fmi.fmi.transfer import transfer_fmu_parameters
from gfins_fmi.nav.earth import euler_to_quat, quat_multiply, radii, skew
from gfins_fmi.nav.strapdown import NavState
from gfins_fmi.sim.scenarios import NAVIGATION, TACTICAL
from gfins_fmi.sim.transfer import MEMS_SLAVE, roll_manoeuvre, straight_road
from gfins_fmi.sim.vehicle import Barometer, GnssReceiver, Odometer, VehicleProfile, simulate_vehicle

__all__ = ["System", "Connection", "vehicle_navigation", "vehicle_integrated_navigation",
           "vehicle_transfer_alignment", "InitialError", "integrated_example", "NAVIGATORS", "AIDING_VARIABLES",
           "TRUTH_OUTPUTS", "INS_OUTPUTS"]

#: navigator name -> (FMU model, vehicle outputs connected to the navigator inputs)
NAVIGATORS = {"gfnav_cube6": ("gfnav_cube6", [("A", "A", 6)]),
              "gfnav_qin9": ("gfnav_qin9", [("A", "A", 9)]),
              "gfnav_12": ("gfnav_12", [("A", "A", 12)]),
              "sins": ("sins", [("dtheta", "dtheta", 3), ("dv", "dv", 3)])}
_LAYOUT = {"gfnav_cube6": 0, "gfnav_qin9": 1, "gfnav_12": 2}


@dataclass(frozen=True)
class Connection:
    """``size`` values from output ``source_var`` of ``source`` to input ``dest_var`` of
    ``dest`` (FMI 3.0 names; element i is ``name[i + 1]`` in FMI 2.0). An array output
    longer than the input (the vehicle's A has 12 slots) is connected element-wise for
    the first ``size`` elements."""
    source: str
    source_var: str
    dest: str
    dest_var: str
    size: int = 1

    def scalars(self) -> list[tuple[str, str]]:
        """(source name, dest name) pairs of FMI 2.0 scalar variables."""
        if self.size == 1 and "[" not in self.source_var:
            return [(self.source_var, self.dest_var)]
        return [(f"{self.source_var}[{i}]", f"{self.dest_var}[{i}]") for i in range(1, self.size + 1)]


@dataclass
class System:
    """FMUs, their start values and their connections.

    Attributes
    ----------
    components : dict name -> (model, parameters)
        ``model`` one of :data:`gfins_fmi.fmi.paths.MODELS`; parameters by FMI 3.0 name
        (arrays as sequences).
    connections : list of Connection
    outputs : dict name -> list of variable names
        What the runs record (FMI 3.0 names).
    step_s, stop_s : float
        Communication step and stop time (s); start time 0 unless given to a run.
    sources : dict
        The Python objects the start values were made from, for the references
        (:func:`vehicle_integrated_navigation`: ``config``, ``initial``, ``gnss_velocity``).
    """
    components: dict
    connections: list
    outputs: dict = field(default_factory=dict)
    step_s: float = 0.01
    stop_s: float = 60.0
    sources: dict = field(default_factory=dict)

    def scalar_parameters(self, name: str) -> dict:
        """Start values of one component as FMI 2.0 scalars (``x[1]`` ...)."""
        out = {}
        for key, value in self.components[name][1].items():
            arr = np.asarray(value)
            if arr.ndim == 0:
                out[key] = value.item() if isinstance(value, np.generic) else value
            else:
                for i, x in enumerate(arr.ravel(), 1):
                    out[f"{key}[{i}]"] = x.item()
        return out


def vehicle_navigation(navigator: str = "gfnav_qin9", profile=None, *, step_s: float = 0.01,
                       stop_s: float | None = None, l_m: float = 0.1, skip_steps: int = 0,
                       imu_errors=None, array_bias_m_s2=None, imu_noise=None,
                       array_noise_m_s2: float = 0.0, noise_seed: int = 1,
                       navigator_parameters: Mapping | None = None,
                       hold_height: bool = True) -> System:
    """The vehicle FMU connected to a navigator FMU.

    Parameters
    ----------
    navigator : {"gfnav_cube6", "gfnav_qin9", "gfnav_12", "sins"}
        Gyro-free navigator (array outputs A connected) or strapdown INS (increments
        dtheta, dv connected; input_mode 0).
    profile : gfins_fmi.sim.vehicle.VehicleProfile, optional
        The manoeuvre (default: seed 001's vehicle test with a 60 s alignment).
    step_s, stop_s : float
        Communication step (s) and stop time (s; default: end of the profile + 30 s).
    l_m : float
        Lever arm of the array layout (gyro-free navigators).
    skip_steps : int
        Navigator doSteps to ignore at the start (1 under fmpy's SSP simulator, which
        passes no outputs before the first step); the navigator starts from the true
        state at ``skip_steps * step_s`` (from the C vehicle model).
    imu_errors : gfins_fmi.ImuErrors, optional
        Applied by the vehicle to its IMU outputs (not compensated by the navigator:
        pass ``navigator_parameters=dict(imu_comp=1, **imu_errors.fmu_parameters())``
        to compensate).
    array_bias_m_s2 : (n,) optional
        Biases of the array accelerometers.
    imu_noise : gfins_fmi.ImuNoise, optional
        Random IMU errors, drawn by the vehicle FMU's own generator (seed ``noise_seed``)
        with the conventions of ``ImuNoise.sample``.
    array_noise_m_s2 : float
        White-noise std per sample of each array accelerometer (drawn by the FMU).
    navigator_parameters : mapping, optional
        More navigator start values (FMI 3.0 names), e.g. ``{"strategy": 3}``.
    hold_height : bool
        Hold the navigator's height at the vehicle's (a ground vehicle): vertical_mode 1.
    """
    if navigator == "ins_gnss":
        raise ValueError("the integrated navigator needs the aiding sensors: use "
                         "fmi.vehicle_integrated_navigation(profile, gnss=..., config=...)")
    if navigator not in NAVIGATORS:
        raise ValueError(f"navigator must be one of {sorted(NAVIGATORS)}; got {navigator!r}")
    profile = profile or VehicleProfile.seed001(align_s=60.0)
    stop_s = profile.duration_s() + 30.0 if stop_s is None else float(stop_s)
    model, links = NAVIGATORS[navigator]
    truth, start = _vehicle_start(profile, step_s, skip_steps)
    veh = _vehicle_parameters(profile, imu_errors, imu_noise, noise_seed,
                              noise=array_noise_m_s2 > 0)
    veh["l"] = float(l_m)
    if navigator in _LAYOUT:
        veh["array_layout"] = _LAYOUT[navigator]
    if array_noise_m_s2 > 0:
        veh["array_noise"] = float(array_noise_m_s2)
    if array_bias_m_s2 is not None:
        b = np.zeros(12)
        b[:len(np.ravel(array_bias_m_s2))] = np.ravel(array_bias_m_s2)
        veh["array_bias"] = b.tolist()
    nav = {**_start_parameters(start), "skip_steps": int(skip_steps)}
    if hold_height:
        nav.update(vertical_mode=1, hold_height=profile.h0_m)
    if navigator in _LAYOUT:
        nav.update(l=float(l_m), omega_init=truth.gyro_rad_s[int(skip_steps)].tolist())
    nav.update(navigator_parameters or {})
    conns = [Connection("vehicle", a, "navigator", b, n) for a, b, n in links]
    outputs = {"vehicle": TRUTH_OUTPUTS + [c.source_var for c in conns],
               "navigator": list(TRUTH_OUTPUTS)}
    return System({"vehicle": ("vehicle", veh), "navigator": (model, nav)}, conns, outputs,
                  float(step_s), stop_s)


#: what a run records of the vehicle's truth and of a navigator's solution
TRUTH_OUTPUTS = ["time_s", "lat", "lon", "h", "v", "euler", "q"]


def _vehicle_start(profile, step_s: float, skip_steps: int):
    """The vehicle record up to the navigator's start, ``skip_steps`` steps after the
    vehicle's (C vehicle model), and the true state there (a NavState)."""
    if isinstance(skip_steps, bool) or int(skip_steps) != skip_steps or skip_steps < 0:
        raise ValueError(f"skip_steps must be an integer >= 0; got {skip_steps!r}")
    truth = simulate_vehicle(profile, skip_steps * step_s, step_s)
    return truth, NavState.from_trajectory(truth, int(skip_steps))


def _vehicle_parameters(profile, imu_errors, imu_noise, noise_seed: int, noise: bool = False) -> dict:
    """Start values of the vehicle FMU: the profile, the IMU errors it applies, its random
    IMU errors (on with ``imu_noise`` or ``noise``) and the seed of its generators (IMU
    noise and aiding sensors)."""
    if isinstance(noise_seed, bool) or not isinstance(noise_seed, (int, np.integer)) \
            or not 0 <= noise_seed < 2 ** 31:
        raise ValueError(f"noise_seed must be an integer in [0, 2**31) (an FMU Int32); got "
                         f"{noise_seed!r}")
    veh = profile.as_parameters()
    if imu_errors is not None:
        veh.update(imu_errors=1, **imu_errors.fmu_parameters())
    if imu_noise is not None or noise:
        veh.update(noise=1, **(imu_noise.fmu_parameters() if imu_noise is not None else {}))
    veh["noise_seed"] = int(noise_seed)
    return veh


def _start_parameters(nav) -> dict:
    """A navigator's initial-state start values (the navigators' common parameters)."""
    return {"q0": np.asarray(nav.q_bn, float).tolist(), "v0": np.asarray(nav.v_n_m_s, float).tolist(),
            "lat0": float(nav.lat_rad), "lon0": float(nav.lon_rad), "h0": float(nav.h_m)}


# ---- vehicle + integrated navigator ----------------------------------------------------
#: the aiding outputs of the vehicle connected to the integrated navigator's inputs of the
#: same names (FMI 3.0 names, sizes), by sensor
AIDING_VARIABLES = {
    "gnss": [("gnss_valid", 1), ("gnss_time_s", 1), ("gnss_lat_rad", 1), ("gnss_lon_rad", 1),
             ("gnss_h_m", 1), ("gnss_vel_enu_m_s", 3), ("gnss_pos_std_m", 3),
             ("gnss_vel_std_m_s", 3)],
    "baro": [("baro_valid", 1), ("baro_time_s", 1), ("baro_h_m", 1), ("baro_std_m", 1)],
    "odometer": [("odo_valid", 1), ("odo_time_s", 1), ("odo_speed_m_s", 1), ("odo_std_m_s", 1)],
}
#: what a run records of the integrated navigator (beyond the solution): its 1-sigma,
#: sensor-error estimates and the per-kind monitoring outputs
INS_OUTPUTS = ["std", "sensors", "n_imu", "n_updates", "n_rejected", "nis", "update_status",
                "update_time", "update_count", "standstill"]


@dataclass(frozen=True)
class InitialError:
    """Errors of a navigator's initial state against the vehicle's true start, in the
    integrated filter's definitions (csrc/est/gf_ins_gnss.h): position east, north, up (m),
    velocity east, north, up (m/s), attitude phi east, north, up (rad) with
    C_b^n(initial) = (I - [phi x]) C_b^n(true) to first order (q = q(-phi) (x) q_true)."""
    position_m: tuple = (0.0, 0.0, 0.0)
    velocity_m_s: tuple = (0.0, 0.0, 0.0)
    attitude_rad: tuple = (0.0, 0.0, 0.0)

    def apply(self, nav):
        """``nav`` (a NavState) with these errors."""
        dp = as_vector3("InitialError.position_m", self.position_m, "m")
        dv = as_vector3("InitialError.velocity_m_s", self.velocity_m_s, "m/s")
        phi = as_vector3("InitialError.attitude_rad", self.attitude_rad, "rad")
        RM, RN, _, _ = radii(nav.lat_rad)
        angle = float(np.linalg.norm(phi))
        axis = phi / angle if angle > 0 else phi
        q_err = np.r_[np.cos(angle / 2), -np.sin(angle / 2) * axis]          # q(-phi)
        return NavState(quat_multiply(q_err, np.asarray(nav.q_bn, float)), np.asarray(nav.v_n_m_s, float) + dv,
                        nav.lat_rad + dp[1] / (RM + nav.h_m),
                        nav.lon_rad + dp[0] / ((RN + nav.h_m) * np.cos(nav.lat_rad)),
                        nav.h_m + dp[2], nav.t_s)


def vehicle_integrated_navigation(profile=None, *, gnss: GnssReceiver | None = GnssReceiver(),
                                  baro: Barometer | None = None, odometer: Odometer | None = None,
                                  config=None, initial_uncertainty: Mapping | None = None,
                                  initial_error: InitialError | None = None,
                                  gnss_velocity: bool = True, step_s: float = 0.01,
                                  stop_s: float | None = None, skip_steps: int = 0,
                                  imu_errors=None, imu_noise=None, noise_seed: int = 1) -> System:
    """The vehicle FMU with its aiding sensors connected to the integrated-navigator FMU
    (``gfins_ins_gnss``): IMU increments ``dtheta``, ``dv`` and, per sensor switched on,
    the epochs (``gnss_valid``, ``gnss_time_s`` ... ``odo_std_m_s``, same names on both
    sides; see :data:`AIDING_VARIABLES`).

    Parameters
    ----------
    profile : gfins_fmi.sim.vehicle.VehicleProfile, optional
        The manoeuvre (default: seed 001's vehicle test with a 60 s alignment).
    gnss, baro, odometer : GnssReceiver, Barometer, Odometer or None
        The aiding sensors the vehicle simulates (default: a ``GnssReceiver()``, 1 Hz; no
        barometer, no odometer). Their lever arms are the filter's: the receiver's antenna
        lever arm becomes ``config.gnss_lever_arm_m``, the odometer's
        ``config.odometer_lever_arm_m`` (a config that states another, non-zero one is
        refused).
    config : gfins_fmi.estimation.FilterConfig, optional
        The filter (default: ``FilterConfig(imu=imu_noise)``, or the tactical-grade IMU of
        ``sim.scenarios.TACTICAL`` without ``imu_noise``; ``max_latency_s`` the
        receiver's latency plus one step). With a GNSS latency, epochs arrive after
        their time of validity: ``config.max_latency_s`` must cover it (refused
        otherwise: every epoch would be stale).
    initial_uncertainty : mapping, optional
        Keyword arguments of :class:`gfins_fmi.estimation.InitialState` (position_std_m,
        velocity_std_m_s, attitude_std_rad, gyro_bias_std_rad_s, ..., sensors).
    initial_error : InitialError, optional
        Errors of the filter's initial state against the vehicle's true start (default:
        none; the start is the truth at ``skip_steps * step_s`` from the C vehicle model).
    gnss_velocity : bool
        Use the epochs' velocities too (the navigator's ``gnss_vel_valid``).
    step_s, stop_s : float
        Communication step (s) and stop time (s; default: end of the profile + 30 s).
    skip_steps : int
        Navigator doSteps to ignore at the start (1 for fmpy's SSP simulator and container,
        which pass no outputs before the first step).
    imu_errors : gfins_fmi.ImuErrors, optional
        Deterministic IMU errors the vehicle applies (the filter estimates biases, and
        scale factors with ``config.scale_factors``).
    imu_noise : gfins_fmi.ImuNoise, optional
        Random IMU errors drawn by the vehicle FMU (seed ``noise_seed``).
    noise_seed : int
        Seed of the vehicle's generators: IMU noise and aiding sensors (= the ``seed`` of
        ``simulate_vehicle``, which gives the same epochs), 0 <= seed < 2**31.

    Returns
    -------
    System
        ``sources`` holds the ``config`` and ``initial`` (InitialState) the navigator's
        start values were made from, for :func:`direct_navigation`.
    """
    for name, value, cls in (("gnss", gnss, GnssReceiver), ("baro", baro, Barometer),
                             ("odometer", odometer, Odometer)):
        if value is not None and not isinstance(value, cls):
            raise TypeError(f"{name} must be a {cls.__name__} or None; got {type(value).__name__}")
    if initial_error is not None and not isinstance(initial_error, InitialError):
        raise TypeError(f"initial_error must be a gfins_fmi.fmi.system.InitialError; got {type(initial_error).__name__}")
    step_s = as_scalar("step_s", step_s, "s", above=0.0)
    profile = profile or VehicleProfile.seed001(align_s=60.0)
    stop_s = profile.duration_s() + 30.0 if stop_s is None else as_scalar("stop_s", stop_s, "s",
                                                                           at_least=step_s)
    latency = gnss.latency_s if gnss is not None else 0.0
    if config is None:
        config = FilterConfig(imu=imu_noise if imu_noise is not None else TACTICAL,
                              max_latency_s=latency + step_s if latency > 0 else 0.0)
    elif not isinstance(config, FilterConfig):
        raise TypeError(f"config must be a gfins_fmi.estimation.FilterConfig; got {type(config).__name__}")
    # the filter's lever arms are the sensors' (one installation)
    arms = {}
    for field_name, sensor in (("gnss_lever_arm_m", gnss), ("odometer_lever_arm_m", odometer)):
        if sensor is None:
            continue
        mounted = tuple(float(x) for x in sensor.lever_arm_m)
        stated = tuple(float(x) for x in getattr(config, field_name))
        if any(stated) and stated != mounted:
            raise ValueError(f"config.{field_name} = {stated} m differs from the sensor's "
                             f"lever_arm_m = {mounted} m: the filter takes the sensor's; leave "
                             "the config's at zero")
        arms[field_name] = mounted
    config = replace(config, **arms)
    if latency > 0:
        if config.max_latency_s < latency:
            raise ValueError(f"the GNSS epochs arrive {latency} s after their time of validity "
                             f"but config.max_latency_s = {config.max_latency_s} s: every epoch "
                             f"would be stale; set FilterConfig(max_latency_s >= {latency})")
        history = int(lib.GF_INS_HISTORY)
        if latency >= (history - 1) * step_s:
            raise ValueError(f"GNSS latency {latency} s spans more than the filter's history "
                             f"of {history} IMU samples ({(history - 1) * step_s:g} s at "
                             f"step_s = {step_s} s): the epochs would be stale")
    _, start = _vehicle_start(profile, step_s, skip_steps)
    nav0 = initial_error.apply(start) if initial_error is not None else start
    initial = InitialState(nav0, **dict(initial_uncertainty or {}))
    nav = ins_gnss_fmu_parameters(config, initial)          # checks config and initial
    nav["skip_steps"] = int(skip_steps)
    if not gnss_velocity:
        nav["gnss_vel_valid"] = 0
    veh = _vehicle_parameters(profile, imu_errors, imu_noise, noise_seed)
    conns = [Connection("vehicle", v, "navigator", v, 3) for v in ("dtheta", "dv")]
    for key, sensor in (("gnss", gnss), ("baro", baro), ("odometer", odometer)):
        if sensor is not None:
            veh.update(sensor.fmu_parameters())
            conns += [Connection("vehicle", v, "navigator", v, n) for v, n in AIDING_VARIABLES[key]]
    outputs = {"vehicle": TRUTH_OUTPUTS + [c.source_var for c in conns],
               "navigator": TRUTH_OUTPUTS + INS_OUTPUTS}
    return System({"vehicle": ("vehicle", veh), "navigator": ("ins_gnss", nav)}, conns, outputs,
                  step_s, stop_s,
                  sources={"config": config, "initial": initial, "gnss_velocity": bool(gnss_velocity)})


def integrated_example() -> dict:
    """Keyword arguments of :func:`vehicle_integrated_navigation` for the worked example
    (examples/cosim_ins_gnss.py) and ``gfins cosim --navigator ins_gnss``: a tactical-grade
    IMU (random errors of ``sim.scenarios.TACTICAL`` drawn by the vehicle FMU); a
    GNSS receiver at 1 Hz, 0.37 s off the IMU grid, 0.1 s latency, antenna 1.9 m from the
    IMU, out from 300 s to 360 s (seed 001's first 180 deg turn and 30 s after it); a
    barometer at 10 Hz with a 2 m bias; an odometer at 10 Hz with a 0.5 % scale error on a
    wheel beside and below the IMU (the vehicle's point without sideslip is the IMU, so a
    wheel point with no forward offset obeys the non-holonomic constraint); the filter with
    barometer-bias and odometer-scale states, NHC, 0.2 s of latency allowed; initial
    errors of 1-1.2 m, 0.05 m/s and 2-10 mrad within its initial uncertainty."""
    return dict(
        gnss=GnssReceiver(rate_hz=1.0, offset_s=0.37, latency_s=0.1, lever_arm_m=(0.3, 1.1, 1.5),
                          outages_s=((300.0, 360.0),)),
        baro=Barometer(rate_hz=10.0, offset_s=0.05, bias0_m=2.0, std_m=0.5),
        odometer=Odometer(rate_hz=10.0, offset_s=0.03, lever_arm_m=(0.75, 0.0, -0.3),
                          scale_error=0.005, std_m_s=0.05),
        config=FilterConfig(imu=TACTICAL, baro_bias=True, baro_bias_std_m=3.0,
                            odometer_scale=True, nhc=True, max_latency_s=0.2),
        initial_uncertainty=dict(position_std_m=(1.5, 1.5, 2.0), velocity_std_m_s=0.1,
                                 attitude_std_rad=(0.005, 0.005, 0.02)),
        initial_error=InitialError(position_m=(1.0, -0.8, 1.2), velocity_m_s=(0.05, -0.04, 0.02),
                                   attitude_rad=(0.002, -0.002, 0.01)),
        imu_noise=TACTICAL, noise_seed=11)


# ---- host + master INS + slave IMU -> transfer alignment -----------------------------------
#: what a run records of the transfer-alignment FMU
TRANSFER_FMU_OUTPUTS = ["time_s", "euler", "mount", "mount_std", "time_offset", "time_offset_std",
                        "sensors", "n_updates", "n_rejected"]


def vehicle_transfer_alignment(profile=None, schedule=None, *, mount_rad=(0.0058, -0.0044, 0.0073),
                               slave_gyro_bias_rad_s=(3e-4, -5e-4, 4e-4),
                               slave_accel_bias_m_s2=(0.02, -0.015, 0.025), slave_noise=MEMS_SLAVE,
                               master_noise=NAVIGATION, master_interval_s: float = 0.1,
                               config: FilterConfig | None = None, mount_std_rad: float = 0.02,
                               master_errors: MasterErrors = MasterErrors((0.015, 0.015, 0.005), 2e-5),
                               step_s: float = 0.01, stop_s: float = 60.0, seed: int = 1) -> System:
    """A host, its master INS and a slave IMU co-simulated with the transfer-alignment FMU:

    ``host`` (vehicle FMU: ``profile``, default a straight road at 10 m/s, its platform
    rolled by ``schedule``, default +-30 deg, its IMU with ``master_noise``) feeds
    ``master`` (the SINS FMU, height held: the master INS) with its increments;
    ``slave_imu`` (a second vehicle FMU on the same motion) is the slave: its IMU error
    model turns its outputs by the mounting (``mount_rad`` heading, pitch, roll of the
    slave in the master's axes, as the cross-coupling I - [a x], a = (pitch, roll,
    -heading): first order, 3e-5 of |f| for 25') and adds the biases and ``slave_noise``;
    ``slave`` (the transfer-alignment FMU) takes the slave's increments, the master's
    attitude, velocity, position and time (``master_time_s``) and the host's rate, every
    ``master_interval_s``. Both IMUs sit at one point and share one clock: lever arm and
    time offset are not simulated here (the Python simulator has them:
    :mod:`gfins_fmi.sim.transfer`), so the filter estimates the mounting and the biases.
    In a Jacobi master the master INS's outputs reach the slave one step late: its epoch
    at t_(k-1) is applied at the filter's time t_(k-1), before sample k (the host's rate
    then describes t_k: 10 ms apart).
    """
    step_s = as_scalar("step_s", step_s, "s", above=0.0)
    profile = profile or straight_road()
    schedule = schedule or roll_manoeuvre()
    a = as_vector3("mount_rad", mount_rad, "rad")
    cfg = config or FilterConfig(imu=slave_noise, master_mount=True)
    _, start = _vehicle_start(profile, step_s, 0)
    q_slave = quat_multiply(np.asarray(start.q_bn, float), euler_to_quat(*cfg.master_mount_rad))
    nav0 = NavState(q_slave, start.v_n_m_s, start.lat_rad, start.lon_rad, start.h_m, 0.0)
    initial = InitialState(nav0, attitude_std_rad=1e-3, gyro_bias_std_rad_s=1e-3, accel_bias_std_m_s2=0.03,
                           master_mount_std_rad=mount_std_rad, attitude_from_master=True)
    slave = transfer_fmu_parameters(cfg, initial, master_errors=master_errors)
    slave.update(master_valid=1, master_interval=float(master_interval_s))
    rot = schedule.fmu_parameters()
    host = {**_vehicle_parameters(profile, None, master_noise, seed), **rot}
    N = -skew(np.array([a[1], a[2], -a[0]]))                   # I + N = C_m^s to first order
    imu = dict(imu_errors=1, gyro_misalign=N.ravel().tolist(), accel_misalign=N.ravel().tolist(),
               gyro_bias=[float(x) for x in slave_gyro_bias_rad_s],
               accel_bias=[float(x) for x in slave_accel_bias_m_s2])
    slave_imu = {**_vehicle_parameters(profile, None, slave_noise, seed + 1), **rot, **imu}
    master = {**_start_parameters(start), "vertical_mode": 1, "hold_height": profile.h0_m}
    conns = [Connection("host", v, "master", v, 3) for v in ("dtheta", "dv")]
    conns += [Connection("slave_imu", v, "slave", v, 3) for v in ("dtheta", "dv")]
    conns += [Connection("master", "euler", "slave", "master_euler", 3),
              Connection("master", "v", "slave", "master_vel", 3),
              Connection("master", "lat", "slave", "master_lat", 1),
              Connection("master", "lon", "slave", "master_lon", 1),
              Connection("master", "h", "slave", "master_h", 1),
              Connection("master", "time_s", "slave", "master_time_s", 1),
              Connection("host", "gyro_rate", "slave", "master_rate", 3)]
    outputs = {"host": list(TRUTH_OUTPUTS), "master": list(TRUTH_OUTPUTS), "slave": TRANSFER_FMU_OUTPUTS}
    return System({"host": ("vehicle", host), "slave_imu": ("vehicle", slave_imu), "master": ("sins", master),
                   "slave": ("transfer_align", slave)}, conns, outputs, step_s, float(stop_s),
                  sources={"config": cfg, "initial": initial, "mount_rad": tuple(a)})
