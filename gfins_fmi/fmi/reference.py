"""Co-simulation of the vehicle FMU with a navigator FMU, three ways:

* :class:`CoSimulation` — a Python master on fmpy's FMU2Slave / FMU3Slave (Jacobi or
  Gauss-Seidel ordering, roll-back through FMU states, progress bar);
* :func:`write_ssp` / :func:`run_ssp` — an SSP 1.0 file (SystemStructure.ssd, the FMI
  2.0 FMUs, a parameter set) that fmpy's SSP simulator and other SSP tools run;
* :func:`write_container` / :func:`run_container` — one container FMU (fmpy's
  container_fmu) holding both FMUs, for tools that take a single FMU.

A :class:`System` says which FMUs take part, with which start values, and how they are
connected; :func:`vehicle_navigation` builds the usual one (vehicle -> navigator).
:func:`direct_navigation` runs the navigator of a system through cffi on given sensor
data: the reference that every co-simulated result is compared with.

Sampling. Every shipped FMU holds, after ``doStep(t, h)``, outputs describing one time:
the vehicle's describe t + h (``time_s`` output), a navigator's the sample it took at t.
A master must therefore hand a navigator the vehicle's outputs *at* t, i.e. pass the
outputs read after the previous step (Jacobi), or step the navigator before the vehicle
(Gauss-Seidel order ``["navigator", "vehicle"]``). See docs/cosim.md.
"""
from __future__ import annotations

import contextlib
import json
import pathlib
import tempfile
import types
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass, field
from typing import Callable, Iterable, Mapping

import numpy as np

from gfins_fmi.fmu import MODELS, FmuRunError, _Log, _Slave, fmu_path
from gfins_fmi.vehicle import Barometer, GnssReceiver, Odometer

__all__ = ["System", "Connection", "vehicle_navigation", "vehicle_integrated_navigation",
           "InitialError", "CoSimulation", "write_ssp", "run_ssp", "write_container",
           "run_container", "direct_navigation", "integrated_recording", "navigation_errors",
           "differences_from_direct", "compare_runners", "NAVIGATORS", "AIDING_VARIABLES"]

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
        ``model`` one of :data:`gfins_fmi.fmu.MODELS`; parameters by FMI 3.0 name
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
    profile : gfins_fmi.vehicle.VehicleProfile, optional
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
    from gfins_fmi.vehicle import VehicleProfile
    if navigator == "ins_gnss":
        raise ValueError("the integrated navigator needs the aiding sensors: use "
                         "cosim.vehicle_integrated_navigation(profile, gnss=..., config=...)")
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
    outputs = {"vehicle": _TRUTH_OUTPUTS + [c.source_var for c in conns],
               "navigator": list(_TRUTH_OUTPUTS)}
    return System({"vehicle": ("vehicle", veh), "navigator": (model, nav)}, conns, outputs,
                  float(step_s), stop_s)


#: what a run records of the vehicle's truth and of a navigator's solution
_TRUTH_OUTPUTS = ["time_s", "lat", "lon", "h", "v", "euler", "q"]


def _vehicle_start(profile, step_s: float, skip_steps: int):
    """The vehicle record up to the navigator's start, ``skip_steps`` steps after the
    vehicle's (C vehicle model), and the true state there (a NavState)."""
    from gfins_fmi.sins import NavState
    from gfins_fmi.vehicle import simulate_vehicle
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
_INS_OUTPUTS = ["std", "sensors", "n_imu", "n_updates", "n_rejected", "nis", "update_status",
                "update_time", "update_count", "standstill"]


@dataclass(frozen=True)
class InitialError:
    """Errors of a navigator's initial state against the vehicle's true start, in the
    integrated filter's definitions (csrc/gf_ins_gnss.h): position east, north, up (m),
    velocity east, north, up (m/s), attitude phi east, north, up (rad) with
    C_b^n(initial) = (I - [phi x]) C_b^n(true) to first order (q = q(-phi) (x) q_true)."""
    position_m: tuple = (0.0, 0.0, 0.0)
    velocity_m_s: tuple = (0.0, 0.0, 0.0)
    attitude_rad: tuple = (0.0, 0.0, 0.0)

    def apply(self, nav):
        """``nav`` (a NavState) with these errors."""
        from gfins_fmi._lib import as_vector3
        from gfins_fmi.sins import NavState
        from gfins_fmi.trajectory import _qmul, radii
        dp = as_vector3("InitialError.position_m", self.position_m, "m")
        dv = as_vector3("InitialError.velocity_m_s", self.velocity_m_s, "m/s")
        phi = as_vector3("InitialError.attitude_rad", self.attitude_rad, "rad")
        RM, RN, _, _ = radii(nav.lat_rad)
        angle = float(np.linalg.norm(phi))
        axis = phi / angle if angle > 0 else phi
        q_err = np.r_[np.cos(angle / 2), -np.sin(angle / 2) * axis]          # q(-phi)
        return NavState(_qmul(q_err, np.asarray(nav.q_bn, float)), np.asarray(nav.v_n_m_s, float) + dv,
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
    profile : gfins_fmi.vehicle.VehicleProfile, optional
        The manoeuvre (default: seed 001's vehicle test with a 60 s alignment).
    gnss, baro, odometer : GnssReceiver, Barometer, Odometer or None
        The aiding sensors the vehicle simulates (default: a ``GnssReceiver()``, 1 Hz; no
        barometer, no odometer). Their lever arms are the filter's: the receiver's antenna
        lever arm becomes ``config.gnss_lever_arm_m``, the odometer's
        ``config.odometer_lever_arm_m`` (a config that states another, non-zero one is
        refused).
    config : gfins_fmi.estimation.FilterConfig, optional
        The filter (default: ``FilterConfig(imu=imu_noise)``, or the tactical-grade IMU of
        ``estimation.scenarios.TACTICAL`` without ``imu_noise``; ``max_latency_s`` the
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
    from dataclasses import replace
    from gfins_fmi._lib import as_scalar, lib
    from gfins_fmi.estimation import FilterConfig, InitialState
    from gfins_fmi.estimation.scenarios import TACTICAL
    from gfins_fmi.fmu import ins_gnss_fmu_parameters
    from gfins_fmi.vehicle import VehicleProfile
    for name, value, cls in (("gnss", gnss, GnssReceiver), ("baro", baro, Barometer),
                             ("odometer", odometer, Odometer)):
        if value is not None and not isinstance(value, cls):
            raise TypeError(f"{name} must be a {cls.__name__} or None; got {type(value).__name__}")
    if initial_error is not None and not isinstance(initial_error, InitialError):
        raise TypeError(f"initial_error must be a cosim.InitialError; got {type(initial_error).__name__}")
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
    outputs = {"vehicle": _TRUTH_OUTPUTS + [c.source_var for c in conns],
               "navigator": _TRUTH_OUTPUTS + _INS_OUTPUTS}
    return System({"vehicle": ("vehicle", veh), "navigator": ("ins_gnss", nav)}, conns, outputs,
                  step_s, stop_s,
                  sources={"config": config, "initial": initial, "gnss_velocity": bool(gnss_velocity)})


def integrated_example() -> dict:
    """Keyword arguments of :func:`vehicle_integrated_navigation` for the worked example
    (examples/cosim_ins_gnss.py) and ``gfins cosim --navigator ins_gnss``: a tactical-grade
    IMU (random errors of ``estimation.scenarios.TACTICAL`` drawn by the vehicle FMU); a
    GNSS receiver at 1 Hz, 0.37 s off the IMU grid, 0.1 s latency, antenna 1.9 m from the
    IMU, out from 300 s to 360 s (seed 001's first 180 deg turn and 30 s after it); a
    barometer at 10 Hz with a 2 m bias; an odometer at 10 Hz with a 0.5 % scale error on a
    wheel beside and below the IMU (the vehicle's point without sideslip is the IMU, so a
    wheel point with no forward offset obeys the non-holonomic constraint); the filter with
    barometer-bias and odometer-scale states, NHC, 0.2 s of latency allowed; initial
    errors of 1-1.2 m, 0.05 m/s and 2-10 mrad within its initial uncertainty."""
    from gfins_fmi.estimation import FilterConfig
    from gfins_fmi.estimation.scenarios import TACTICAL
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


# ---- Python master --------------------------------------------------------------------
class CoSimulation:
    """A co-simulation master on fmpy's FMU2Slave / FMU3Slave.

    Parameters
    ----------
    system : System
    fmi_version : {2, 3}
    algorithm : {"jacobi", "gauss-seidel"}
        Jacobi: at each communication point every input takes the outputs held at that
        point, then every FMU steps. Gauss-Seidel: the FMUs step one after the other in
        ``order``, each taking the outputs its sources hold at that moment (already
        stepped ones: the new outputs).
    order : list of str, optional
        Gauss-Seidel order (default: the order of ``system.components``).
    logging_on : bool
        Debug logging of the FMUs (errors are always collected).
    echo : callable, optional
        Receives every log line as it arrives.

    Notes
    -----
    After initialization every connection is propagated once, so the first step sees
    the outputs at the start time. ``get_state``/``set_state`` roll every FMU and the
    master's clock back together; ``serialize_state``/``deserialize_state`` give and
    take bytes.
    """

    def __init__(self, system: System, fmi_version: int = 2, algorithm: str = "jacobi",
                 order: list | None = None, logging_on: bool = False,
                 echo: Callable[[str], None] | None = None):
        if algorithm not in ("jacobi", "gauss-seidel"):
            raise ValueError(f"algorithm must be 'jacobi' or 'gauss-seidel'; got {algorithm!r}")
        if fmi_version not in (2, 3):
            raise ValueError(f"fmi_version must be 2 or 3; got {fmi_version!r}")
        self.system = system
        self.version = fmi_version
        self.algorithm = algorithm
        self.order = list(order or system.components)
        if sorted(self.order) != sorted(system.components):
            raise ValueError(f"order must list every component once: {sorted(system.components)}")
        self.log = _Log(echo)
        self.slaves: dict[str, _Slave] = {}
        self.time_s = 0.0
        try:
            for name, (model, _) in system.components.items():
                if model not in MODELS:
                    raise ValueError(f"component {name}: unknown model {model!r}")
                self.slaves[name] = _Slave(fmu_path(model, fmi_version), fmi_version, self.log,
                                           logging_on, instance_name=name)
            # the connections grouped by (source, dest, type): one get and one set per
            # group and step, whatever the number of variables
            groups: dict = {}   # (source, dest, type) -> [source vrs, read, picked, dest vrs, set]
            for c in system.connections:
                for comp in (c.source, c.dest):
                    if comp not in self.slaves:
                        raise ValueError(f"connection {c}: no component {comp!r}")
                s_vrs, s_n, s_typ = self._refs(c.source, c.source_var, c.size)
                d_vrs, d_n, d_typ = self._refs(c.dest, c.dest_var, c.size)
                if s_typ != d_typ:
                    raise ValueError(f"connection {c}: {s_typ} output to {d_typ} input")
                if d_n != c.size:
                    raise ValueError(f"connection {c}: {c.dest}.{c.dest_var} has {d_n} elements")
                g = groups.setdefault((c.source, c.dest, s_typ), [[], 0, [], [], 0])
                g[2] += range(g[1], g[1] + c.size)
                g[0] += s_vrs
                g[1] += s_n
                g[3] += d_vrs
                g[4] += d_n
            self._links = []  # (dest, dest group, source, source group, picked elements or None)
            for (src, dst, typ), (s_vrs, s_n, pick, d_vrs, d_n) in groups.items():
                self._links.append((dst, (d_vrs, d_n, typ), src, (s_vrs, s_n, typ),
                                    None if pick == list(range(s_n)) else pick))
        except Exception:
            self.close()
            raise

    def _refs(self, comp: str, var: str, size: int):
        """(value refs, values read, "Float64" or "Int32") of a connected variable whose
        first ``size`` elements are used: FMI 2.0 the scalars themselves, FMI 3.0 the
        whole array (a longer output feeding a shorter input is read whole)."""
        vrs, n, typ = self.slaves[comp].refs(var)
        typ = "Int32" if typ in ("Integer", "Int32") else "Float64"
        if size > n:
            raise ValueError(f"{comp}.{var} has {n} elements; the connection needs {size}")
        if self.version == 2:
            return vrs[:size], size, typ
        return vrs, n, typ

    def _transfer(self, dest: str | None = None):
        for d, dst, src_comp, src, pick in self._links:
            if dest is None or d == dest:
                values = self.slaves[src_comp].get_group(src)
                if pick is not None:
                    values = [values[i] for i in pick]
                self.slaves[d].set_group(dst, values)

    def _call(self, what: str, fn, *args, **kwargs):
        from fmpy.fmi1 import FMICallException
        try:
            return fn(*args, **kwargs)
        except FMICallException as exc:
            raise FmuRunError(f"{what} failed: {exc}. FMU log: "
                              f"{'; '.join(self.log.messages[-5:]) or 'no message logged'}",
                              self.log.messages) from exc

    def initialize(self, start_s: float = 0.0, stop_s: float | None = None) -> None:
        """Set the start values, initialise every FMU, propagate the connections once."""
        stop = self.system.stop_s if stop_s is None else stop_s
        for name, (_, params) in self.system.components.items():
            self._call(f"initialising {name}", self.slaves[name].initialize, start_s, stop, params)
        self.time_s = float(start_s)
        self._start_s = float(start_s)
        self._steps = 0
        self._transfer()

    def step(self, h_s: float) -> None:
        """One communication step of every FMU from the current time."""
        t = self.time_s
        if self.algorithm == "jacobi":
            self._transfer()
            for name in self.order:
                self._call(f"{name}.doStep at t = {t:.9g} s", self.slaves[name].slave.doStep,
                           currentCommunicationPoint=t, communicationStepSize=h_s)
        else:
            for name in self.order:
                self._transfer(name)
                self._call(f"{name}.doStep at t = {t:.9g} s", self.slaves[name].slave.doStep,
                           currentCommunicationPoint=t, communicationStepSize=h_s)
        self._steps += 1
        self.time_s = t + h_s

    def read(self, comp: str, var: str) -> list:
        """Current value(s) of a variable (FMI 3.0 name)."""
        return self.slaves[comp].get(var)

    def run(self, stop_s: float | None = None, step_s: float | None = None,
            progress: bool = False, points=None) -> dict:
        """Step with a fixed step to ``stop_s`` and record ``system.outputs`` after the
        initialization and after every step.

        ``points`` (s), optional: the communication points instead, starting at the
        current time; step k goes from points[k] to points[k + 1] (e.g. another master's
        clock: :func:`gfins_fmi.osp.communication_points`).

        Returns
        -------
        dict "comp.var" -> ndarray (n_rows, size), plus "time" (n_rows,): the master's
        time when the row was read.

        Raises
        ------
        FmuRunError
            An FMU call failed; the message carries the FMU's log, ``partial`` the rows
            recorded before the failing step.
        """
        h = self.system.step_s if step_s is None else step_s
        stop = self.system.stop_s if stop_s is None else stop_s
        n = int(round((stop - self.time_s) / h))
        if points is not None:
            points = np.asarray(points, dtype=float)
            if points.ndim != 1 or points.size < 2 or points[0] != self.time_s \
                    or not np.all(np.diff(points) > 0):
                raise ValueError(f"points must be increasing communication points (s) from the "
                                 f"current time {self.time_s!r} s")
            n = points.size - 1
        # one get call per component, type and row: all its recorded variables together,
        # into one table per group, split into variables at the end
        plan = []   # (component, (vrs, count, type), table, [(name, start, stop)])
        for c, names in self.system.outputs.items():
            by_type: dict = {}
            for v in names:
                r, cnt, typ = self.slaves[c].refs(v)
                typ = "Int32" if typ in ("Integer", "Int32") else "Float64"
                vrs, parts = by_type.setdefault(typ, ([], []))
                start = parts[-1][2] if parts else 0
                vrs += r
                parts.append((f"{c}.{v}", start, start + cnt))
            for typ, (vrs, parts) in by_type.items():
                table = np.empty((n + 1, parts[-1][2]), np.int64 if typ == "Int32" else float)
                plan.append((c, (vrs, parts[-1][2], typ), table, parts))
        times = np.empty(n + 1)
        t0 = self.time_s

        def record(i):
            times[i] = self.time_s
            for c, group, table, _ in plan:
                table[i] = self.slaves[c].get_group(group)

        def split(rows):
            out = {name: table[:rows, a:b].copy() for _, _, table, parts in plan
                   for name, a, b in parts}
            out["time"] = times[:rows].copy()
            return out
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=n, unit="step", unit_scale=True, desc="co-simulation")
        done = 0
        try:
            record(0)
            for k in range(n):
                # communication points t0 + k h (computed, not accumulated), or those given
                if points is None:
                    self.time_s = t0 + k * h
                    self.step(h)
                    self.time_s = t0 + (k + 1) * h
                else:
                    self.time_s = points[k]
                    self.step(points[k + 1] - points[k])
                    self.time_s = points[k + 1]
                record(k + 1)
                done = k + 1
                if bar and k % 1000 == 999:
                    bar.update(1000)
        except FmuRunError as exc:  # keep what was recorded
            exc.partial = split(done + 1)
            raise
        finally:
            if bar:
                bar.update(n - bar.n)
                bar.close()
        return split(n + 1)

    # -- roll-back ------------------------------------------------------------------------
    def get_state(self) -> dict:
        """FMU states of every component and the master's clock."""
        st = {name: self._call(f"{name}.getFMUState",
                               s.slave.getFMUstate if self.version == 2 else s.slave.getFMUState)
              for name, s in self.slaves.items()}
        return {"time_s": self.time_s, "fmus": st}

    def set_state(self, state: dict) -> None:
        for name, s in self.slaves.items():
            fn = s.slave.setFMUstate if self.version == 2 else s.slave.setFMUState
            self._call(f"{name}.setFMUState", fn, state["fmus"][name])
        self.time_s = state["time_s"]

    def free_state(self, state: dict) -> None:
        for name, s in self.slaves.items():
            fn = s.slave.freeFMUstate if self.version == 2 else s.slave.freeFMUState
            fn(state["fmus"][name])

    def serialize_state(self, state: dict) -> dict:
        """The state as bytes per component (can be stored and restored later)."""
        out = {}
        for name, s in self.slaves.items():
            fn = s.slave.serializeFMUstate if self.version == 2 else s.slave.serializeFMUState
            out[name] = bytes(self._call(f"{name}.serialize", fn, state["fmus"][name]))
        return {"time_s": state["time_s"], "fmus": out}

    def deserialize_state(self, data: dict) -> dict:
        st = {}
        for name, s in self.slaves.items():
            fn = s.slave.deSerializeFMUstate if self.version == 2 else s.slave.deserializeFMUState
            st[name] = self._call(f"{name}.deserialize", fn, data["fmus"][name])
        return {"time_s": data["time_s"], "fmus": st}

    def close(self) -> None:
        for s in self.slaves.values():
            s.close()
        self.slaves = {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---- SSP ------------------------------------------------------------------------------
_SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
_SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
_SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"


def _fmu_variables(model: str, fmi_version: int) -> dict:
    from fmpy import read_model_description
    md = read_model_description(str(fmu_path(model, fmi_version)))
    return {v.name: v for v in md.modelVariables}


def write_ssp(system: System, path: str | pathlib.Path, name: str = "VehicleNavigation") -> pathlib.Path:
    """Write ``system`` as an SSP 1.0 file with the FMI 2.0 FMUs (scalar connections).

    The archive holds SystemStructure.ssd (components, connectors, connections, the
    default experiment), resources/<fmu>.fmu and, per component, resources/<component>.ssv
    (its start values, named by variable) bound to the component by a ParameterBinding —
    the form both fmpy (through :func:`run_ssp`) and libcosim (which reads no
    system-level binding; :func:`gfins_fmi.osp.run_libcosim_ssp`) apply.
    Connectors: every connected variable, the recorded outputs and the parameters set.
    """
    ET.register_namespace("ssd", _SSD)
    ET.register_namespace("ssc", _SSC)
    ET.register_namespace("ssv", _SSV)
    path = pathlib.Path(path)
    root = ET.Element(f"{{{_SSD}}}SystemStructureDescription", version="1.0", name=name)
    sysel = ET.SubElement(root, f"{{{_SSD}}}System", name=name,
                          description="gfins_fmi: vehicle FMU connected to a navigator FMU")
    elements = ET.SubElement(sysel, f"{{{_SSD}}}Elements")
    psets = {}
    for comp, (model, _) in system.components.items():
        variables = _fmu_variables(model, 2)
        el = ET.SubElement(elements, f"{{{_SSD}}}Component", name=comp,
                           type="application/x-fmu-sharedlibrary",
                           source=f"resources/{MODELS[model]}.fmu")
        conns = ET.SubElement(el, f"{{{_SSD}}}Connectors")
        names: dict[str, str] = {}
        for c in system.connections:
            for a, b in c.scalars():
                if c.source == comp:
                    names[a] = "output"
                if c.dest == comp:
                    names[b] = "input"
        for var in system.outputs.get(comp, []):
            for scalar in ([var] if var in variables else
                           [k for k in variables if k.startswith(var + "[")]):
                names.setdefault(scalar, "output")
        params = system.scalar_parameters(comp)
        for pname in params:
            names.setdefault(pname, "parameter")
        for cname, kind in names.items():
            if cname not in variables:
                raise ValueError(f"{comp} ({model}) has no variable {cname!r}")
            con = ET.SubElement(conns, f"{{{_SSD}}}Connector", name=cname, kind=kind)
            typ = variables[cname].type
            ET.SubElement(con, f"{{{_SSC}}}{'Integer' if typ == 'Integer' else 'Real'}")
        if not params:
            continue
        ET.SubElement(ET.SubElement(el, f"{{{_SSD}}}ParameterBindings"),
                      f"{{{_SSD}}}ParameterBinding", source=f"resources/{comp}.ssv")
        pset = ET.Element(f"{{{_SSV}}}ParameterSet", version="1.0", name=f"{comp} start values")
        params_el = ET.SubElement(pset, f"{{{_SSV}}}Parameters")
        for pname, value in params.items():
            p = ET.SubElement(params_el, f"{{{_SSV}}}Parameter", name=pname)
            if variables[pname].type == "Integer":
                ET.SubElement(p, f"{{{_SSV}}}Integer", value=str(int(value)))
            else:
                ET.SubElement(p, f"{{{_SSV}}}Real", value=repr(float(value)))
        psets[comp] = pset
    connections = ET.SubElement(sysel, f"{{{_SSD}}}Connections")
    for c in system.connections:
        for a, b in c.scalars():
            ET.SubElement(connections, f"{{{_SSD}}}Connection", startElement=c.source,
                          startConnector=a, endElement=c.dest, endConnector=b)
    ET.SubElement(root, f"{{{_SSD}}}DefaultExperiment", startTime="0.0",
                  stopTime=repr(float(system.stop_s)))
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ET.tostring(root, encoding="utf-8", xml_declaration=True))
        for comp, pset in psets.items():
            z.writestr(f"resources/{comp}.ssv", ET.tostring(pset, encoding="utf-8", xml_declaration=True))
        for model in {m for m, _ in system.components.values()}:
            z.write(fmu_path(model, 2), f"resources/{MODELS[model]}.fmu")
    return path


def run_ssp(path: str | pathlib.Path, stop_s: float, step_s: float) -> np.ndarray:
    """Simulate an SSP written by :func:`write_ssp` with fmpy's SSP simulator.

    fmpy parses the components' ParameterBindings but applies a parameter set only when
    handed one: their values are passed as one set named ``component.variable``.
    Returns fmpy's structured array: a row per step, recorded *after* the step at
    ``time`` (so the vehicle's outputs in a row describe ``time + step_s``, a
    navigator's the sample taken at ``time``).
    """
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import ParameterSet, read_ssd
    params = ParameterSet(name="start values")
    for comp in read_ssd(str(path)).system.elements:
        for binding in comp.parameterBindings:
            for pset in binding.parameterValues:
                for p in pset.parameters:
                    p.name = f"{comp.name}.{p.name}"
                    params.parameters.append(p)
    return simulate_ssp(str(path), start_time=0.0, stop_time=stop_s, step_size=step_s,
                        parameter_set=params)


# ---- container FMU --------------------------------------------------------------------
def write_container(system: System, path: str | pathlib.Path, fmi_version: int = 2) -> pathlib.Path:
    """One container FMU (fmpy.container_fmu) holding the system's FMUs of
    ``fmi_version``: the connections inside, the recorded outputs exposed as outputs
    ``comp_var`` (FMI 2.0: ``comp_var_i`` per element) and the system's start values as
    parameters ``comp_param``; internal fixed step ``system.step_s``."""
    from fmpy import read_model_description
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Configuration
    from fmpy.container_fmu.config import Connection as CConnection
    from fmpy.model_description import CoSimulation as MdCoSim
    from fmpy.model_description import (DefaultExperiment, Dimension, ModelDescription,
                                        ModelVariable, Unknown)
    real = "Real" if fmi_version == 2 else "Float64"
    integer = "Integer" if fmi_version == 2 else "Int32"
    comps, mds = {}, {}
    for name, (model, _) in system.components.items():
        fpath = pathlib.Path(fmu_path(model, fmi_version))
        mds[name] = read_model_description(str(fpath))
        comps[name] = Component(name=name, filename=fpath, modelDescription=mds[name])
    var_of = {name: {v.name: v for v in md.modelVariables} for name, md in mds.items()}

    def elements(comp, var, size=None):
        """Component variables addressing var (FMI 2: scalars)."""
        vs = var_of[comp]
        if fmi_version == 3 or var in vs:
            return [vs[var]]
        n = size or sum(1 for k in vs if k.startswith(var + "["))
        return [vs[f"{var}[{i}]"] for i in range(1, n + 1)]

    connections = []
    for c in system.connections:
        if fmi_version == 3:
            n_src = int(var_of[c.source][c.source_var].dimensions[0].start) \
                if var_of[c.source][c.source_var].dimensions else 1
            if n_src != c.size:
                raise ValueError(f"FMI 3.0 container: {c.source}.{c.source_var} has {n_src} "
                                 f"elements, {c.dest}.{c.dest_var} takes {c.size}; FMI 3.0 "
                                 "connects whole arrays: use fmi_version=2 (scalars)")
        connections.append(CConnection(comps[c.source], elements(c.source, c.source_var, c.size),
                                       comps[c.dest], elements(c.dest, c.dest_var, c.size)))
    # the container binary takes value reference 0 as time in FMI 2.0 too
    variables = [ModelVariable(type=real, variability="continuous", causality="independent",
                               name="time")]
    mappings = {}
    for comp, names in system.outputs.items():
        for var in names:
            for cv in elements(comp, var):
                shape = [Dimension(start=d.start, valueReference=None) for d in cv.dimensions]
                mv = ModelVariable(type=real if cv.type in ("Real", "Float64") else integer,
                                   variability="discrete", causality="output", initial="calculated",
                                   name=f"{comp}_{cv.name}".replace("[", "_").replace("]", ""),
                                   dimensions=shape)
                variables.append(mv)
                mappings[mv] = [(comps[comp], cv)]
    for comp, (_, params) in system.components.items():
        for pname, value in params.items():
            arr = np.ravel(np.asarray(value, dtype=float))
            if fmi_version == 3 and arr.size > 1:
                continue  # fmpy 0.3.x containers set array parameters element by element: refused
            cvs = elements(comp, pname)
            vals = arr if fmi_version == 2 else [arr]
            for cv, val in zip(cvs, vals):
                is_int = cv.type in ("Integer", "Int32")
                val = np.ravel(val)
                start = " ".join(str(int(x)) if is_int else repr(float(x)) for x in val)
                mv = ModelVariable(type=integer if is_int else real, variability="fixed",
                                   causality="parameter", initial="exact",
                                   name=f"{comp}_{cv.name}".replace("[", "_").replace("]", ""),
                                   start=start,
                                   dimensions=[Dimension(start=d.start, valueReference=None)
                                               for d in cv.dimensions])
                variables.append(mv)
                mappings[mv] = [(comps[comp], cv)]
    md = ModelDescription(fmiVersion=f"{fmi_version}.0", modelName="gfins_vehicle_navigation",
                          instantiationToken="{7a2c9f4e-3b1d-4e8a-9c6f-5d2b8e1a4f70}",
                          defaultExperiment=DefaultExperiment(startTime="0", stopTime=str(system.stop_s),
                                                              stepSize=str(system.step_s)),
                          coSimulation=MdCoSim(fixedInternalStepSize=system.step_s),
                          modelVariables=variables)
    if fmi_version == 2:
        md.guid = md.instantiationToken
    md.outputs = [Unknown(variable=v) for v in variables if v.causality == "output"]
    md.initialUnknowns = [Unknown(variable=v) for v in variables if v.causality == "output"]
    config = Configuration(parallelDoStep=False, modelDescription=md,
                           components=list(comps.values()), connections=connections,
                           variableMappings=mappings)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    import fmpy.container_fmu as cfmu
    with tempfile.TemporaryDirectory() as tmp, _container_json_fixes(cfmu):
        create_container_fmu(config, pathlib.Path(tmp), path)
    return path


@contextlib.contextmanager
def _container_json_fixes(module):
    """Three workarounds for fmpy 0.3.x's container.json writer, active while a container
    is written: (1) FMI 3.0 array connections have a numpy integer size that json cannot
    write ("Object of type int64 is not JSON serializable"); (2) FMI 2.0 connections get
    the FMI 2.0 type names (Real, Integer), which the container binary refuses
    ("unknown variant `Real`"): renamed to Float64, Int32; (3) an array start value is
    written as one string, which the container cannot parse: split into elements."""
    def dump(data, f, **kw):
        for v in data.get("variables", []):
            if "start" in v and len(v["start"]) == 1 and " " in str(v["start"][0]):
                v["start"] = str(v["start"][0]).split()
        for c in data.get("connections", []):
            c["variableType"] = {"Real": "Float64", "Integer": "Int32"}.get(
                c["variableType"], c["variableType"])
        json.dump(data, f, default=int, **kw)
    saved = module.json
    module.json = types.SimpleNamespace(dump=dump)
    try:
        yield
    finally:
        module.json = saved


def run_container(path: str | pathlib.Path, stop_s: float, step_s: float,
                  outputs: Iterable[str] | None = None) -> np.ndarray:
    """Simulate a container FMU with fmpy.simulate_fmu, one output row per step (row at
    ``time`` read after the step that ends there)."""
    from fmpy import simulate_fmu
    return simulate_fmu(str(path), stop_time=stop_s, output_interval=step_s,
                        output=list(outputs) if outputs else None)


# ---- reference: the navigator through cffi --------------------------------------------
def _start_values(model: str, given: Mapping) -> Callable:
    """A lookup of a component's start values: the system's, else the FMU's own (its
    modelDescription), so the cffi reference runs with exactly what the FMU runs."""
    variables = _fmu_variables(model, 3)

    def value(name):
        if name in given:
            return given[name]
        v = variables[name]
        cast = float if v.type == "Float64" else int
        items = [cast(x) for x in str(v.start).split()]
        return items if v.dimensions else items[0]
    return value


def direct_navigation(system: System, sensors: Mapping[str, np.ndarray], start_time_s: float = 0.0,
                      imu_errors=None, initial=None):
    """Run the system's navigator through cffi (no FMU) on sensor records.

    Parameters
    ----------
    sensors : mapping
        ``{"A": (n, n_sensors)}`` array samples at t_k = start + (skip + k) h for a
        gyro-free navigator, or ``{"dtheta": (n, 3), "dv": (n, 3)}`` increments over
        (t_(k-1), t_k], k = skip + 1 ... for the SINS.

        For the integrated navigator (``ins_gnss``): what :func:`integrated_recording`
        returns; the batch API then runs on it (see :func:`_integrated_reference`).
    initial : gfins_fmi.estimation.InitialState, optional
        ``ins_gnss`` only: the batch API's initial state (default: the system's, with the
        covariance the FMU makes of its stds: both convert with gf_earth).
    imu_errors : gfins_fmi.ImuErrors, optional
        The error model the SINS FMU compensates (``imu_comp = 1``; its
        ``fmu_parameters()`` must be the navigator's): the increments are compensated
        as mean rates over the step with the FMU's arithmetic before navigating.

    Returns
    -------
    NavSolution
        Row k: the state at t_(skip + k) (gyro-free: the sample; SINS: after the k-th
        increment, row 0 the initial state). ``ins_gnss``: the IntegratedSolution of
        ``IntegratedNavigator.run``, row k the state after the k-th increment.
    """
    from gfins_fmi.gyrofree import STRATEGIES, GyroFreeNavigator, layout
    from gfins_fmi.sins import _VERTICAL, NavState, SinsConfig, Strapdown
    model, nav = system.components["navigator"]
    if model == "ins_gnss":
        return _integrated_reference(system, sensors, initial)
    value = _start_values(model, nav)
    h = system.step_s
    t0 = start_time_s + value("skip_steps") * h
    init = NavState(np.asarray(value("q0"), float), np.asarray(value("v0"), float),
                    value("lat0"), value("lon0"), value("h0"), t0)
    vertical = {v: k for k, v in _VERTICAL.items()}[value("vertical_mode")]
    cfg = dict(vertical=vertical, hold_height_m=value("hold_height"), baro_tau_s=value("baro_tau"))
    if model.startswith("gfnav_"):
        strategy = {v: k for k, v in STRATEGIES.items()}[value("strategy")]
        navi = GyroFreeNavigator(layout(model[len("gfnav_"):], value("l")), init, strategy=strategy,
                                 omega_init_rad_s=value("omega_init"),
                                 accel_noise_m_s2=value("accel_noise"), sins=SinsConfig(**cfg))
        sol, _ = navi.run(sensors["A"], h)
        return sol
    if value("lowpass_sections"):
        raise ValueError("direct_navigation: the SINS FMU's low-pass is not reproduced here; "
                         "filter the record with gfins_fmi.signal_conditioning.BiquadFilter first")
    dth, dv = sensors["dtheta"], sensors["dv"]
    if value("imu_comp"):
        if imu_errors is None or not all(np.array_equal(v, value(k))
                                         for k, v in imu_errors.fmu_parameters().items()):
            raise ValueError("the navigator compensates IMU errors (imu_comp = 1): pass the "
                             "ImuErrors whose fmu_parameters() it was given as imu_errors")
        k = 1.0 / h                                    # the FMU's arithmetic, to the bit
        w, f = imu_errors.compensate(dth * k, dv * k)
        dth, dv = w / k, f / k
    sd = Strapdown(init, SinsConfig(input="increments", coning=bool(value("coning")),
                                    max_rate_rad_s=value("max_rate"),
                                    max_specific_force_m_s2=value("max_specific_force"), **cfg))
    return sd.run(dth, dv, h)


def _series(result, kind: str, comp: str, var: str, size: int | None = None) -> np.ndarray:
    """A variable recorded by a run, (rows,) for a scalar (``size`` None) or (rows, size):
    ``kind`` "master" (:meth:`CoSimulation.run`: arrays under "comp.var"), "ssp"
    (:func:`run_ssp`: FMI 2.0 scalars "comp.var[i]") or "container" (:func:`run_container`:
    "comp_var_i")."""
    if kind not in ("master", "ssp", "container"):
        raise ValueError(f"kind must be 'master', 'ssp' or 'container'; got {kind!r}")
    if kind == "master":
        a = np.asarray(result[f"{comp}.{var}"])
        return a[:, 0] if size is None else a[:, :size]

    def key(i=None):
        k = f"{comp}.{var}" if i is None else f"{comp}.{var}[{i}]"
        return k.replace(".", "_").replace("[", "_").replace("]", "") if kind == "container" else k
    if size is None:
        return np.asarray(result[key()])
    return np.stack([np.asarray(result[key(i)]) for i in range(1, size + 1)], 1)


def integrated_recording(system: System, result, kind: str = "master") -> dict:
    """What the integrated navigator of a run (:func:`vehicle_integrated_navigation`)
    consumed and produced, read from the recorded rows.

    Every runner records a navigator one row after the vehicle outputs it consumed (the
    navigator's row j took the vehicle's row j - 1): the Python master (Jacobi, or
    Gauss-Seidel with the navigator first) records the initial row and then a row after
    each step; the SSP simulator and the container hand a step what was read after the
    previous one. The navigator's IMU samples are its rows where ``n_imu`` counts 1, 2,
    ... N; the row before the first is its start (the first doStep of an increments
    navigator only starts the run; skipped steps come before it). Epochs delivered with
    the start step are never handed to the filter (the FMU counts them as rejected).

    Parameters
    ----------
    kind : {"master", "ssp", "container"}
        The runner that made ``result`` (see :func:`differences_from_direct`).

    Returns
    -------
    dict
        ``t_s`` (N + 1,): the start time and the sample times (the navigator's own
        ``time_s``); ``dtheta``, ``dv`` (N, 3): the increments it took; ``gnss``,
        ``baro``, ``odometer``: the epochs it was handed (``GnssMeasurements`` ...;
        None for a sensor not connected) and ``gnss_sample`` ... (m,): the sample, 1 .. N,
        each came with; ``solution``: the navigator's rows as an ``IntegratedSolution``
        (innovations from its monitoring outputs, residuals NaN).
    """
    from gfins_fmi.estimation import IntegratedSolution
    from gfins_fmi.fmu import _monitor_innovations
    from gfins_fmi.vehicle import BaroMeasurements, GnssMeasurements, OdometerMeasurements
    model, _ = system.components["navigator"]
    if model != "ins_gnss":
        raise ValueError(f"integrated_recording reads an ins_gnss navigator; this system's is {model!r}")

    def nav(var, size=None):
        return _series(result, kind, "navigator", var, size)

    def veh(var, size=None):
        return _series(result, kind, "vehicle", var, size)
    n_imu = nav("n_imu").astype(np.int64)
    rows = np.flatnonzero(n_imu > 0)
    N = len(rows)
    if N == 0 or rows[0] < 1 or not np.array_equal(n_imu[rows], np.arange(1, N + 1)) \
            or not np.array_equal(rows, np.arange(rows[0], rows[0] + N)):
        raise ValueError("the recording does not show one IMU sample per navigator step after "
                         "its start (n_imu 1, 2, ...): was it made by a CoSimulation (Jacobi or "
                         "navigator first), run_ssp or run_container of this system?")
    start = rows[0] - 1
    used = rows - 1                                  # the vehicle rows the samples took
    T = nav("time_s")
    out = {"t_s": np.r_[T[start], T[rows]], "dtheta": veh("dtheta", 3)[used],
           "dv": veh("dv", 3)[used]}
    links = {c.dest_var for c in system.connections}
    kinds = {"gnss": ("gnss", GnssMeasurements), "baro": ("baro", BaroMeasurements),
             "odometer": ("odo", OdometerMeasurements)}
    for key, (prefix, cls) in kinds.items():
        out[key] = out[f"{key}_sample"] = None
        if f"{prefix}_valid" not in links:
            continue
        k = np.flatnonzero(veh(f"{prefix}_valid")[used] > 0)
        out[f"{key}_sample"] = k + 1
        r = used[k]
        if key == "gnss":
            v = {f: veh(f"gnss_{f}", 3)[r] for f in ("vel_enu_m_s", "pos_std_m", "vel_std_m_s")}
            out[key] = cls(veh("gnss_time_s")[r], veh("gnss_lat_rad")[r], veh("gnss_lon_rad")[r],
                           veh("gnss_h_m")[r], v["pos_std_m"], v["vel_enu_m_s"], v["vel_std_m_s"],
                           np.zeros(len(r), np.int8))
        elif key == "baro":
            out[key] = cls(veh("baro_time_s")[r], veh("baro_h_m")[r], veh("baro_std_m")[r])
        else:
            out[key] = cls(veh("odo_time_s")[r], veh("odo_speed_m_s")[r], veh("odo_std_m_s")[r])
    counts = nav("update_count", 7).astype(np.int64)
    inn = _monitor_innovations(counts[rows], counts[start], nav("update_time", 7)[rows],
                               nav("update_status", 7)[rows].astype(np.int64), nav("nis", 7)[rows])
    out["solution"] = IntegratedSolution(
        T[rows], nav("q", 4)[rows], nav("v", 3)[rows], nav("lat")[rows], nav("lon")[rows],
        nav("h")[rows], nav("std", 9)[rows], nav("sensors", 16)[rows],
        nav("standstill")[rows].astype(bool), inn, system.sources.get("config"))
    return out


def _integrated_reference(system: System, rec: Mapping, initial=None):
    """The batch API (``IntegratedNavigator.run``) on what the co-simulated integrated
    navigator consumed (:func:`integrated_recording`), each epoch handed in with the IMU
    sample it arrived with.

    ``IntegratedNavigator.run`` takes an epoch with the first sample whose time reaches
    its time of validity; so does the FMU when the epoch arrives in time (zero latency:
    the vehicle delivers it at the end of the step it falls in, the navigator gets it with
    that step's increment). An epoch that arrives later (latency) reaches the FMU with a
    later sample, valid before that sample's interval: the batch API is then fed in pieces
    (it continues where it stopped), a piece starting at each such sample, so that the
    epoch comes with it, and the core makes the same delayed update (its history,
    ``FilterConfig.max_latency_s``). A time of validity within the FMU's clock tolerance
    after the sample (1e-9 max(1, |t|) s, beyond the core's 1e-9 s) is taken at the
    sample, as the FMU does. ``initial`` (default: the system's as the FMU takes it,
    same start as the FMU) starts the filter at the recorded start time.
    """
    from dataclasses import fields, replace
    from gfins_fmi.estimation import IntegratedNavigator, IntegratedSolution
    from gfins_fmi.io.records import ImuRecord
    cfg = system.sources["config"]
    init = system.sources["initial"] if initial is None else initial
    t = np.asarray(rec["t_s"], float)
    T = t[1:]
    N = len(T)
    init = replace(init, nav=replace(init.nav, t_s=float(t[0])))
    starts, epochs = {0}, {}
    for key in ("gnss", "baro", "odometer"):
        m = rec.get(key)
        if m is None:
            continue
        k = np.asarray(rec[f"{key}_sample"]) - 1                # 0-based sample
        tk = T[k]
        tm = np.array(m.t_s, float)
        clock = (tm > tk + 1e-9) & (tm - tk <= 1e-9 * np.maximum(1.0, np.abs(tk)))
        tm[clock] = tk[clock]
        natural = np.searchsorted(T + 1e-9, tm, side="left")  # gf_ins_run's sample
        starts.update(k[natural < k].tolist())
        epochs[key] = (replace(m, t_s=tm), k)
    bounds = sorted(starts) + [N]
    navigator = IntegratedNavigator(cfg, init)
    parts = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        imu = ImuRecord(T[a:b], rec["dtheta"][a:b], rec["dv"][a:b], kind="increments",
                        source="co-simulation")
        sel = {}
        for key, (m, k) in epochs.items():
            take = (k >= a) & (k < b)
            sel[key] = type(m)(**{f.name: getattr(m, f.name)[take] for f in fields(m)}) \
                if np.any(take) else None
        parts.append(navigator.run(imu, sel.get("gnss"), sel.get("baro"), sel.get("odometer"),
                                   gnss_velocity=system.sources.get("gnss_velocity", True)))
    cat = {f: np.concatenate([getattr(p, f) for p in parts])
           for f in ("t_s", "q_bn", "v_n_m_s", "lat_rad", "lon_rad", "h_m", "std", "sensors",
                     "standstill", "innovations")}
    return IntegratedSolution(**cat, config=cfg)


def navigation_errors(result: Mapping) -> dict:
    """Navigation error against the vehicle's truth for a :meth:`CoSimulation.run`
    result (Jacobi, or Gauss-Seidel with the navigator first): row k + 1 of the
    navigator describes the time of row k of the vehicle.

    Returns
    -------
    dict with t_s (n,), horizontal_m (n,) horizontal position error (m, north/east with
    the WGS-84 radii), velocity_m_s (n,) norm of the horizontal velocity error and
    attitude_rad (n, 3) the attitude error as a rotation vector (ENU, rad) of
    q_nav (x) q_true* (its norm is the error angle).
    """
    from gfins_fmi.trajectory import attitude_error_rad, radii
    t = result["vehicle.time_s"][:-1, 0]
    lat_t, lon_t = result["vehicle.lat"][:-1, 0], result["vehicle.lon"][:-1, 0]
    lat_n, lon_n = result["navigator.lat"][1:, 0], result["navigator.lon"][1:, 0]
    h = result["vehicle.h"][:-1, 0]
    RM, RN, _, _ = radii(lat_t)
    north = (lat_n - lat_t) * (RM + h)
    east = (lon_n - lon_t) * (RN + h) * np.cos(lat_t)
    dv = result["navigator.v"][1:, :2] - result["vehicle.v"][:-1, :2]
    return dict(t_s=t, horizontal_m=np.hypot(north, east),
                velocity_m_s=np.linalg.norm(dv, axis=1),
                attitude_rad=attitude_error_rad(result["navigator.q"][1:], result["vehicle.q"][:-1]))


def differences_from_direct(system: System, result, kind: str = "master", imu_errors=None) -> dict:
    """Max |difference| between a co-simulated navigator and :func:`direct_navigation`
    on the sensor data recorded in ``result`` (0.0 when bit-identical).

    ``kind``: "master" (a :meth:`CoSimulation.run` result), "ssp" (:func:`run_ssp`) or
    "container" (:func:`run_container`, FMI 2.0). The rows are aligned as each runner
    records them (see their docstrings); ``imu_errors`` as for :func:`direct_navigation`.
    Returns {"lat_rad": ..., "v_m_s": ...}; for the integrated navigator (``ins_gnss``)
    also "lon_rad", "h_m", "q", "std" and "sensors", against the batch API
    (``IntegratedNavigator.run``) on the recorded increments and epochs.
    """
    model, nav = system.components["navigator"]
    if kind not in ("master", "ssp", "container"):
        raise ValueError(f"kind must be 'master', 'ssp' or 'container'; got {kind!r}")
    if model == "ins_gnss":
        rec = integrated_recording(system, result, kind)
        ref, sol = direct_navigation(system, rec), rec["solution"]
        return {name: float(np.max(np.abs(getattr(sol, f) - getattr(ref, f))))
                for name, f in (("lat_rad", "lat_rad"), ("lon_rad", "lon_rad"), ("h_m", "h_m"),
                                ("v_m_s", "v_n_m_s"), ("q", "q_bn"), ("std", "std"),
                                ("sensors", "sensors"))}
    gyro_free = model.startswith("gfnav_")
    n_in = NAVIGATORS[model][1][0][2] if gyro_free else 3

    def rows(comp, var, size=None):
        return _series(result, kind, comp, var, size)
    # the navigator's row j took the vehicle's row j - 1 (every runner); its first sample
    # comes after the initial row (master, container), the skipped steps and, for the
    # SINS, the step that only starts it
    first = (kind != "ssp") + int(nav.get("skip_steps", 0)) + (0 if gyro_free else 1)
    data = ({"A": rows("vehicle", "A", n_in)[first - 1:-1]} if gyro_free else
            {k: rows("vehicle", k, 3)[first - 1:-1] for k in ("dtheta", "dv")})
    lat, v = rows("navigator", "lat")[first:], rows("navigator", "v", 3)[first:]
    sol = direct_navigation(system, data, imu_errors=imu_errors)
    return {"lat_rad": float(np.max(np.abs(sol.lat_rad - lat))),
            "v_m_s": float(np.max(np.abs(sol.v_n_m_s - v)))}


def compare_runners(navigator: str, profile, stop_s: float, out_dir: str | pathlib.Path,
                    step_s: float = 0.01, fmi_version: int = 3,
                    runners: Iterable[str] = ("master", "ssp", "container"),
                    progress: bool = False, options: Mapping | None = None) -> dict:
    """Run vehicle + ``navigator`` along ``profile`` through each runner and compare each
    navigation solution with the cffi navigator on the sensor data that runner recorded
    (``"ins_gnss"``: :func:`vehicle_integrated_navigation` with ``options``, default
    :func:`integrated_example`, against the batch API ``IntegratedNavigator.run``).

    "master": :class:`CoSimulation` (FMI ``fmi_version``); "ssp": an SSP file in
    ``out_dir`` run by fmpy's SSP simulator; "container": an FMI 2.0 container FMU in
    ``out_dir`` run by fmpy (both with ``skip_steps = 1``, see :func:`run_ssp`).

    Returns
    -------
    dict runner -> {"wall_s", "diff" ({"lat_rad", "v_m_s"}), "path" (written file or
    None)}; the "master" entry also has "errors" (:func:`navigation_errors`).
    """
    import time
    from gfins_fmi._lib import as_scalar
    step_s = as_scalar("step_s", step_s, "s", above=0.0)
    stop_s = as_scalar("stop_s", stop_s, "s", at_least=step_s)
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    out = {}
    for runner in runners:
        skip = 0 if runner == "master" else 1
        if navigator == "ins_gnss":
            system = vehicle_integrated_navigation(
                profile, step_s=step_s, stop_s=stop_s, skip_steps=skip,
                **(integrated_example() if options is None else dict(options)))
        else:
            system = vehicle_navigation(navigator, profile, step_s=step_s, stop_s=stop_s,
                                        skip_steps=skip)
        t0 = time.perf_counter()
        path = None
        if runner == "master":
            with CoSimulation(system, fmi_version=fmi_version) as m:
                m.initialize()
                result = m.run(progress=progress)
        elif runner == "ssp":
            path = write_ssp(system, out_dir / "vehicle_navigation.ssp")
            result = run_ssp(path, stop_s, step_s)
        elif runner == "container":
            path = write_container(system, out_dir / "vehicle_navigation.fmu", fmi_version=2)
            result = run_container(path, stop_s, step_s)
        else:
            raise ValueError(f"runner must be 'master', 'ssp' or 'container'; got {runner!r}")
        entry = dict(wall_s=time.perf_counter() - t0, path=path,
                     diff=differences_from_direct(system, result, runner))
        if runner == "master":
            entry["errors"] = navigation_errors(result)
        out[runner] = entry
    return out
