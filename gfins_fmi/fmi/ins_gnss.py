"""The FMUs shipped with gfins_fmi: where they are, how to check them, how to run them.

Every FMU is built from the same C core as the Python API, for FMI 2.0 and FMI 3.0
co-simulation, and installed inside the package (``gfins_fmi/fmus/fmi<N>/``).

Sampling convention of every navigation FMU: ``doStep(t, h)`` processes the input
sample set for time ``t``; the outputs read after the step describe time ``t``. A
master that records outputs after each step (fmpy's ``simulate_fmu`` does) therefore
shows the solution of sample k in its row k + 1.
"""
from __future__ import annotations

import importlib.resources
import pathlib
import shutil
from typing import Callable, Mapping

import numpy as np

from gfins_fmi._lib import (GfinsError, as_array, as_positive_scalar, as_rows, as_scalar,
                            as_vector3)
from gfins_fmi.accel_array import Accel9Solution
from gfins_fmi.estimation.ins_gnss import InitialState

__all__ = ["MODELS", "fmu_path", "validate", "run_fmu", "run_accel9_fmu", "run_sins_fmu", "run_gfnav_fmu",
           "run_ins_gnss_fmu", "ins_gnss_fmu_parameters", "FmuRunError"]

#: model name -> model identifier of the FMUs shipped
MODELS = {"accel9": "gfins_accel9", "sins": "gfins_sins", "gfnav_cube6": "gfins_gfnav_cube6",
          "gfnav_qin9": "gfins_gfnav_qin9", "gfnav_12": "gfins_gfnav_12",
          "vehicle": "gfins_vehicle", "ins_gnss": "gfins_ins_gnss"}


class FmuRunError(GfinsError):
    """An FMU call failed; ``messages`` holds what the FMU logged, ``partial`` the
    outputs of the steps that completed."""

    def __init__(self, message: str, messages: list[str], partial=None):
        super().__init__(message)
        self.messages = messages
        self.partial = partial


def fmu_path(model: str = "accel9", fmi_version: int = 2) -> pathlib.Path:
    """Path of a shipped FMU.

    Parameters
    ----------
    model : str
        One of :data:`MODELS` (``"accel9"``: the 9-accelerometer solver; ``"sins"``:
        the strapdown navigator; ``"ins_gnss"``: the integrated navigator, EKF/UKF).
    fmi_version : {2, 3}
        FMI 2.0 (scalar variables, structured names ``A[1]`` ...) or FMI 3.0 (arrays).
    """
    if model not in MODELS:
        raise ValueError(f"unknown FMU model {model!r}; choose one of {sorted(MODELS)}")
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3; got {fmi_version!r}")
    fmi_version = int(fmi_version)
    res = importlib.resources.files("gfins_fmi") / "fmus" / f"fmi{fmi_version}" / f"{MODELS[model]}.fmu"
    path = pathlib.Path(str(res))
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: the FMUs are built by 'pip install .'")
    return path


def validate(path: str | pathlib.Path) -> list[str]:
    """Problems fmpy finds in an FMU (an empty list means it is valid)."""
    from fmpy.validation import validate_fmu
    return validate_fmu(str(path))


class _Log:
    """Collects an FMU's log messages (FMI 2 and FMI 3 callbacks)."""

    def __init__(self, echo: Callable[[str], None] | None = None):
        self.messages: list[str] = []
        self.echo = echo

    def add(self, status: int, category: bytes | None, message: bytes | None,
            fmi2: bool = False) -> None:
        text = (message or b"").decode(errors="replace")
        if fmi2:
            text = text.replace("%%", "%")
        cat = (category or b"").decode(errors="replace")
        line = f"[{cat}] {text}" if cat else text
        self.messages.append(line)
        if self.echo:
            self.echo(line)


class _Slave:
    """One instance of a shipped FMU through fmpy's FMU2Slave / FMU3Slave, with
    variables addressed by their FMI 3.0 names (FMI 2.0 scalars ``x[i]`` are gathered)."""

    def __init__(self, path: pathlib.Path, fmi_version: int, log: _Log, logging_on: bool,
                 instance_name: str | None = None):
        from fmpy import extract, read_model_description
        self.version = fmi_version
        self.md = read_model_description(str(path))
        self.unzipdir = extract(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        if fmi_version == 2:
            from fmpy import calloc, free
            from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE,
                                   fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                                   fmi2CallbackLoggerTYPE)
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName=instance_name or self.md.coSimulation.modelIdentifier)
            cb = fmi2CallbackFunctions()
            # No fmpy.logging.addLoggerProxy: it keeps one global logger for the whole
            # process, which would outlive this object. The FMU passes the formatted text
            # as the format with '%' doubled (see fmi2_glue.c), undone in _Log.add.
            self._logger = fmi2CallbackLoggerTYPE(
                lambda env, name, status, cat, msg: log.add(status, cat, msg, fmi2=True))
            cb.logger = self._logger
            # the FMU declares canNotUseMemoryManagementFunctions; fmpy's C allocator is
            # passed anyway because the standard asks for non-NULL pointers
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            self._callbacks = cb
            self.slave.instantiate(callbacks=cb, loggingOn=logging_on)
        else:
            from fmpy.fmi3 import FMU3Slave
            self.slave = FMU3Slave(guid=self.md.instantiationToken, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName=instance_name or self.md.coSimulation.modelIdentifier)
            self.slave.instantiate(loggingOn=logging_on,
                                   logMessage=lambda env, status, cat, msg: log.add(status, cat, msg))

    def refs(self, name: str) -> tuple[list[int], int, str]:
        """(value references, number of values, type) of a variable by FMI 3.0 name."""
        if self.version == 3:
            v = self.vars[name]
            n = int(np.prod([int(d.start) for d in v.dimensions])) if v.dimensions else 1
            return [v.valueReference], n, v.type
        if name in self.vars:
            return [self.vars[name].valueReference], 1, self.vars[name].type
        vrs, i = [], 1
        while f"{name}[{i}]" in self.vars:
            vrs.append(self.vars[f"{name}[{i}]"].valueReference)
            i += 1
        if not vrs:
            raise KeyError(f"the FMU has no variable {name!r}")
        return vrs, len(vrs), self.vars[f"{name}[1]"].type

    def group(self, names) -> tuple[list[int], int, str]:
        """(value references, number of values, "Float64" or "Int32") of several variables
        of one type, to be read or written in one call (:meth:`get_group`, :meth:`set_group`)."""
        vrs, n, kinds = [], 0, set()
        for name in names:
            r, k, typ = self.refs(name)
            vrs += r
            n += k
            kinds.add("Int32" if typ in ("Integer", "Int32") else "Float64")
        if len(kinds) != 1:
            raise ValueError(f"variables {list(names)} are not all of one type")
        return vrs, n, kinds.pop()

    def set_group(self, group, values) -> None:
        vrs, n, typ = group
        if typ == "Int32":
            (self.slave.setInteger if self.version == 2 else self.slave.setInt32)(vrs, [int(x) for x in values])
        else:
            (self.slave.setReal if self.version == 2 else self.slave.setFloat64)(vrs, [float(x) for x in values])

    def get_group(self, group) -> list:
        vrs, n, typ = group
        if typ == "Int32":
            return self.slave.getInteger(vrs) if self.version == 2 else self.slave.getInt32(vrs, n)
        return self.slave.getReal(vrs) if self.version == 2 else self.slave.getFloat64(vrs, n)

    def set(self, name: str, values) -> None:
        vrs, n, typ = self.refs(name)
        vals = np.atleast_1d(np.asarray(values))
        if vals.size != n:
            raise ValueError(f"{name} takes {n} values; got {vals.size}")
        if typ in ("Integer", "Int32"):
            (self.slave.setInteger if self.version == 2 else self.slave.setInt32)(vrs, [int(x) for x in vals])
        else:
            (self.slave.setReal if self.version == 2 else self.slave.setFloat64)(vrs, [float(x) for x in vals])

    def get(self, name: str) -> list:
        vrs, n, typ = self.refs(name)
        if typ in ("Integer", "Int32"):
            return self.slave.getInteger(vrs) if self.version == 2 else self.slave.getInt32(vrs, n)
        return self.slave.getReal(vrs) if self.version == 2 else self.slave.getFloat64(vrs, n)

    def initialize(self, start_s: float, stop_s: float, parameters: Mapping) -> None:
        if self.version == 2:
            self.slave.setupExperiment(startTime=start_s, stopTime=stop_s)
            self.slave.enterInitializationMode()
        else:
            self.slave.enterInitializationMode(startTime=start_s, stopTime=stop_s)
        for name, value in parameters.items():
            self.set(name, value)
        self.slave.exitInitializationMode()

    def close(self) -> None:
        try:
            self.slave.terminate()
        except Exception:
            pass
        self.slave.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def run_fmu(model: str, inputs: Mapping[str, np.ndarray], outputs: list[str], dt_s: float, *,
            parameters: Mapping | None = None, fmi_version: int = 2,
            start_time_s: float = 0.0, path: str | pathlib.Path | None = None,
            logging_on: bool = False, echo: Callable[[str], None] | None = None,
            progress: bool = False) -> dict[str, np.ndarray]:
    """Co-simulate a shipped FMU alone with fmpy as the master, one ``doStep`` per sample.

    Parameters
    ----------
    model : str
        One of :data:`MODELS`.
    inputs : mapping name -> array (n, k) or (n,)
        Input samples; row j is set before the step at ``start_time_s + j dt_s``.
    outputs : list of str
        Variables (FMI 3.0 names, e.g. ``"omega"``) read after each step.
    dt_s : float
        Communication step, s.
    parameters : mapping name -> value, optional
        Set in initialization mode.

    Returns
    -------
    dict name -> ndarray (n, k)
        Row j: the outputs after the step at sample j (they describe that sample).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and the rows completed (``partial``).
    """
    dt_s = as_positive_scalar("dt_s (communication step)", dt_s, "s")
    start_time_s = as_scalar("start_time_s", start_time_s, "s")
    arrays = {k: np.atleast_2d(np.asarray(v, dtype=float).T).T for k, v in inputs.items()}
    n = {a.shape[0] for a in arrays.values()}
    if len(n) != 1:
        raise ValueError(f"all inputs must have the same number of samples; got {sorted(n)}")
    n = n.pop()
    path = pathlib.Path(path) if path else fmu_path(model, fmi_version)
    log = _Log(echo)
    from fmpy.fmi1 import FMICallException
    try:
        slave = _Slave(path, fmi_version, log, logging_on)
    except FMICallException as exc:
        raise FmuRunError(f"FMI {fmi_version}.0 {model} FMU could not be instantiated: {exc} "
                          f"FMU log: {'; '.join(log.messages) or 'no message logged'}",
                          log.messages, {}) from exc
    out = {name: np.empty((n, slave.refs(name)[1])) for name in outputs}
    k = 0
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=n, unit="step", unit_scale=True, desc=f"{model} FMU")
    try:
        try:
            slave.initialize(start_time_s, start_time_s + n * dt_s, parameters or {})
            for k in range(n):
                for name, arr in arrays.items():
                    slave.set(name, arr[k])
                slave.slave.doStep(currentCommunicationPoint=start_time_s + k * dt_s,
                                   communicationStepSize=dt_s)
                for name in outputs:
                    out[name][k] = slave.get(name)
                if bar and k % 1000 == 999:
                    bar.update(1000)
            k = n
            if bar:
                bar.update(n - bar.n)
        except FMICallException as exc:
            detail = "; ".join(log.messages) or "no message logged"
            raise FmuRunError(f"FMI {fmi_version}.0 {model} FMU failed at sample {k}: {exc} "
                              f"FMU log: {detail}", log.messages,
                              {name: v[:k].copy() for name, v in out.items()}) from exc
    finally:
        if bar:
            bar.close()
        slave.close()
    return out


def run_accel9_fmu(A_m_s2, dt_s: float, l_m: float, omega_init_rad_s=(0.0, 0.0, 0.0), *,
                   fmi_version: int = 2, start_time_s: float = 0.0,
                   path: str | pathlib.Path | None = None, logging_on: bool = False,
                   echo: Callable[[str], None] | None = None) -> Accel9Solution:
    """Run a record through the 9-accelerometer FMU with fmpy as the master.

    One ``doStep`` per sample (communication step ``dt_s``); the outputs read after the
    step of sample k are row k of the result, so it lines up with
    :func:`gfins_fmi.solve_accel9` on the same record. ``l_m`` is checked by the FMU
    itself (that check is part of what runs here).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and, in ``partial``, an
        :class:`Accel9Solution` of the rows completed.
    """
    A = as_rows("A_m_s2", A_m_s2, 9, "m/s^2")
    w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
    names = ["f", "omega", "omega_dot", "omega_sq", "flags"]

    def solution(d):
        return Accel9Solution(d["f"], d["omega"], d["omega_dot"], d["omega_sq"],
                              d["flags"][:, 0].astype(np.uint8))
    try:
        d = run_fmu("accel9", {"A": A}, names, dt_s, parameters={"l": float(l_m), "omega_init": w0},
                    fmi_version=fmi_version, start_time_s=start_time_s, path=path,
                    logging_on=logging_on, echo=echo)
    except FmuRunError as exc:
        exc.partial = solution(exc.partial)
        raise
    return solution(d)


def run_sins_fmu(gyro, accel, dt_s: float, initial, *, config=None, h_ext_m=None,
                 fmi_version: int = 2, start_time_s: float | None = None,
                 progress: bool = False, imu_errors=None, lowpass_sos=None, gimbal_rad=None,
                 **kwargs):
    """Run a record through the strapdown FMU; the result lines up with
    :meth:`gfins_fmi.Strapdown.run` on the same record (for increments, the FMU takes
    the increment over (t_(k-1), t_k] at t_k, so the record is shifted by one step
    internally and its first step only starts the run).

    ``imu_errors`` (:class:`gfins_fmi.ImuErrors`) switches on the FMU's compensation of
    its inputs; ``lowpass_sos`` (n_sections <= 8, 6) its low-pass after it (the same as
    ``ImuErrors.compensate`` followed by ``signal_conditioning.BiquadFilter`` on the six channels).

    ``gimbal_rad`` (n, 2; the middle and inner angles at each record row's time) makes it
    the navigator of a rotating INS (rotating = 1): the record is the IMU frame's and the
    result is a :class:`gfins_fmi.rotation.RotatingNavSolution` with the vehicle attitude
    from the gimbal angles (as :func:`gfins_fmi.rotation.navigate`).

    Returns a :class:`gfins_fmi.NavSolution` (with ``gimbal_rad``: a RotatingNavSolution).
    """
    from gfins_fmi.sins import _INPUTS, _VERTICAL, NavSolution, SinsConfig
    cfg = config or SinsConfig()
    if cfg.earth != "wgs84":
        raise ValueError("the SINS FMU navigates on WGS-84 only (earth='wgs84')")
    if cfg.checked_subsamples() != 1:
        raise ValueError(f"subsamples = {cfg.subsamples}: the SINS FMU takes one sample per "
                         "communication step and makes one navigation update of it (the master's "
                         "step is the update interval); navigate subsampled records with "
                         "Strapdown.run")
    x0 = initial.checked()    # the same checks and messages as Strapdown
    cfg._c(x0.h_m)
    g = as_rows("gyro", gyro, 3, "rad or rad/s")
    a = as_rows("accel", accel, 3, "m/s or m/s^2")
    n = g.shape[0]
    if a.shape[0] != n:
        raise ValueError(f"gyro has {n} samples but accel has {a.shape[0]}")
    t0 = x0.t_s if start_time_s is None else as_scalar("start_time_s", start_time_s, "s")
    params = {"input_mode": int(_INPUTS[cfg.input]), "coning": int(cfg.coning),
              "vertical_mode": int(_VERTICAL[cfg.vertical]),
              "hold_height": cfg.held_height_m(x0.h_m), "baro_tau": cfg.baro_tau_s,
              "max_rate": cfg.max_rate_rad_s, "max_specific_force": cfg.max_specific_force_m_s2,
              "q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad, "lon0": x0.lon_rad,
              "h0": x0.h_m}
    if imu_errors is not None:
        params.update(imu_comp=1, **imu_errors.fmu_parameters())
    if lowpass_sos is not None:
        sos = np.asarray(lowpass_sos, float)
        if sos.ndim != 2 or sos.shape[1] != 6 or not 1 <= sos.shape[0] <= 8:
            raise ValueError(f"lowpass_sos must have shape (1..8, 6); got {sos.shape}")
        params.update(lowpass_sections=sos.shape[0],
                      lowpass_sos=np.r_[sos.ravel(), np.zeros(48 - sos.size)])
    he = np.full(n, np.nan) if h_ext_m is None else as_array("h_ext_m", h_ext_m, (n,), "m",
                                                             finite=False)
    gim = None if gimbal_rad is None else as_array("gimbal_rad", gimbal_rad, (n, 2), "rad")
    if gim is not None:
        params["rotating"] = 1
    if cfg.input == "increments":
        # sample j of the record covers (t_j, t_(j+1)]: set it at t_(j+1)
        z = np.zeros((1, 3))
        ins = {"dtheta": np.r_[z, g], "dv": np.r_[z, a], "gyro_rate": np.zeros((n + 1, 3)),
               "specific_force": np.zeros((n + 1, 3)), "h_ext": np.r_[np.nan, he]}
        if gim is not None:
            ins["gimbal"] = np.r_[gim[:1], gim]
    else:
        ins = {"gyro_rate": g, "specific_force": a, "dtheta": np.zeros((n, 3)),
               "dv": np.zeros((n, 3)), "h_ext": he}
        if gim is not None:
            ins["gimbal"] = gim
    shift = 1 if cfg.input == "increments" else 0   # FMU step k takes record row k - shift

    def solution(d):
        sl = slice(shift, None)
        sol = NavSolution(d["time_s"][sl, 0], d["q"][sl], d["v"][sl], d["lat"][sl, 0],
                          d["lon"][sl, 0], d["h"][sl, 0])
        if gim is None:
            return sol
        from gfins_fmi.rotation import RotatingNavSolution
        return RotatingNavSolution(sol, d["q_vehicle"][sl])
    outs = ["q", "v", "lat", "lon", "h", "time_s"] + (["q_vehicle"] if gim is not None else [])
    try:
        d = run_fmu("sins", ins, outs, dt_s, parameters=params,
                    fmi_version=fmi_version, start_time_s=t0, progress=progress, **kwargs)
    except FmuRunError as exc:
        k = len(exc.partial.get("q", [])) if exc.partial else 0
        exc.partial = solution(exc.partial) if exc.partial else None
        if k >= shift:
            exc.args = (f"record row {k - shift}: " + exc.args[0],)
        raise
    return solution(d)


def run_gfnav_fmu(layout_name: str, A_m_s2, dt_s: float, initial, *, l_m: float = 0.1,
                  strategy: str = "integrate", omega_init_rad_s=(0.0, 0.0, 0.0),
                  accel_noise_m_s2: float = 1e-4, sins=None, fmi_version: int = 2, **kwargs):
    """Run an array record through the gyro-free navigator FMU of a layout ("cube6",
    "qin9", "12"); the result lines up with :meth:`gfins_fmi.GyroFreeNavigator.run` on
    the same record (row k: the state at sample k).

    Returns (NavSolution, omega_rad_s (n, 3), f_m_s2 (n, 3), flags (n,)).
    """
    from gfins_fmi.gyrofree import STRATEGIES
    from gfins_fmi.sins import _EARTH, _VERTICAL, NavSolution, SinsConfig
    model = f"gfnav_{layout_name}"
    if model not in MODELS:
        raise ValueError(f"no navigator FMU for layout {layout_name!r}; choose cube6, qin9 or 12")
    n_in = {"cube6": 6, "qin9": 9, "12": 12}[layout_name]
    A = as_rows("A_m_s2", A_m_s2, n_in, "m/s^2")
    sc = sins or SinsConfig()
    if sc.subsamples != 1:
        raise ValueError(f"sins.subsamples = {sc.subsamples!r}: the gyro-free navigator FMU "
                         "makes one update per array sample; use subsamples=1")
    flat = sc.earth == "flat"
    x0 = initial.checked(flat)    # the same checks and messages as GyroFreeNavigator
    sc._c(x0.h_m)
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {sorted(STRATEGIES)}; got {strategy!r}")
    # l and accel_noise are checked by the FMU itself (that check is part of what runs)
    params = {"l": float(l_m), "strategy": int(STRATEGIES[strategy]),
              "accel_noise": float(accel_noise_m_s2),
              "omega_init": as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s"),
              "earth": int(_EARTH[sc.earth]), "flat_gravity": sc.flat_gravity_m_s2,
              "vertical_mode": int(_VERTICAL[sc.vertical]), "hold_height": sc.held_height_m(x0.h_m),
              "baro_tau": sc.baro_tau_s, "q0": x0.q_bn, "v0": x0.v_n_m_s, "lat0": x0.lat_rad,
              "lon0": x0.lon_rad, "h0": x0.h_m,
              "pos0": x0.pos_m if flat else np.zeros(3)}
    d = run_fmu(model, {"A": A}, ["q", "v", "lat", "lon", "h", "pos", "omega", "f", "flags",
                                  "time_s"], dt_s, parameters=params, fmi_version=fmi_version,
                start_time_s=x0.t_s, **kwargs)
    sol = NavSolution._from_pos(d["time_s"][:, 0], d["q"], d["v"],
                                d["pos"] if flat else np.c_[d["lat"], d["lon"], d["h"]], flat)
    return sol, d["omega"], d["f"], d["flags"][:, 0].astype(np.uint8)


# ---- the integrated navigator (gf_ins_gnss) ---------------------------------------------

#: FMU parameter -> gf_ins_config field (fmu/models/ins_gnss/model_spec.py maps the same)
_INS_CONFIG_FIELDS = {
    "filter": "filter", "input_mode": "input", "coning": "coning",
    "propagation_interval": "prop_interval_s", "max_imu_gap": "max_imu_gap_s",
    "max_rate": "max_rate_rad_s", "max_specific_force": "max_specific_force_m_s2",
    "scale_states": "scale_states", "baro_state": "baro_state", "odo_state": "odo_state",
    "odo_mount_state": "odo_mount_state",
    "ukf_alpha": "ukf_alpha", "ukf_beta": "ukf_beta", "ukf_kappa": "ukf_kappa",
    "gyro_arw": "noise.gyro_arw_rad_sqrt_s", "accel_vrw": "noise.accel_vrw_m_s_sqrt_s",
    "gyro_bias_std": "noise.gyro_bias_std_rad_s", "gyro_bias_tau": "noise.gyro_bias_tau_s",
    "accel_bias_std": "noise.accel_bias_std_m_s2", "accel_bias_tau": "noise.accel_bias_tau_s",
    "gyro_scale_std": "noise.gyro_scale_std", "gyro_scale_tau": "noise.gyro_scale_tau_s",
    "accel_scale_std": "noise.accel_scale_std", "accel_scale_tau": "noise.accel_scale_tau_s",
    "baro_bias_std": "noise.baro_bias_std_m", "baro_bias_tau": "noise.baro_bias_tau_s",
    "odo_scale_std": "noise.odo_scale_std", "odo_scale_tau": "noise.odo_scale_tau_s",
    "odo_mount_std": "noise.odo_mount_std_rad", "odo_mount_tau": "noise.odo_mount_tau_s",
    "gnss_lever_arm": "gnss_lever_m", "odo_lever_arm": "odo_lever_m", "odo_mount": "odo_mount_rad",
    "gate_prob": "gate_prob",
    "gate_reset_count": "gate_reset_count", "max_latency": "max_latency_s",
    "nhc": "nhc", "nhc_std": "nhc_std_m_s", "nhc_interval": "nhc_interval_s", "zupt": "zupt",
    "zupt_std": "zupt_std_m_s", "zaru_std": "zaru_std_rad_s", "zupt_interval": "zupt_interval_s",
    "still_window": "still_window_s", "still_accel_std": "still_accel_std_m_s2",
    "still_gyro": "still_gyro_rad_s"}


def ins_gnss_fmu_parameters(config, initial) -> dict:
    """Start values (FMI 3.0 names, SI) that make the integrated-navigator FMU the filter
    ``IntegratedNavigator(config, initial)``.

    The configuration is copied field by field from the C struct the batch API hands the
    core (``FilterConfig`` in datasheet units -> SI process noise included); the initial
    state and one standard deviation per error block (position in metres east, north,
    up; the defaults of :class:`gfins_fmi.estimation.InitialState`). Both objects are
    validated with the batch API's own checks and messages.

    Parameters
    ----------
    config : gfins_fmi.estimation.FilterConfig
    initial : gfins_fmi.estimation.InitialState
    """
    from gfins_fmi.estimation import FilterConfig, InitialState
    if not isinstance(config, FilterConfig):
        raise TypeError("config must be a gfins_fmi.estimation.FilterConfig")
    if not isinstance(initial, InitialState):
        raise TypeError("initial must be a gfins_fmi.estimation.InitialState")
    initial.covariance(config)            # the batch API's checks of the initial stds
    c = config._c()
    params = {}
    for name, path in _INS_CONFIG_FIELDS.items():
        value = c
        for part in path.split("."):
            value = getattr(value, part)
        params[name] = [float(x) for x in value] if name.endswith(("lever_arm", "mount")) else value
    nav = initial.nav
    noise = config.noise_si()

    def vec(x):
        return np.broadcast_to(np.asarray(x, dtype=float), (3,)).tolist()

    def given(x, default):
        return default if x is None else x

    sensors = np.zeros(16) if initial.sensors is None else np.asarray(initial.sensors, float)
    params.update(
        q0=np.asarray(nav.q_bn, float).tolist(), v0=np.asarray(nav.v_n_m_s, float).tolist(),
        lat0=float(nav.lat_rad), lon0=float(nav.lon_rad), h0=float(nav.h_m),
        sensors0=sensors.tolist(),
        std0_vel=vec(initial.velocity_std_m_s), std0_pos=vec(initial.position_std_m),
        std0_att=vec(initial.attitude_std_rad),
        std0_gyro_bias=vec(given(initial.gyro_bias_std_rad_s, noise["gyro_bias_std_rad_s"])),
        std0_accel_bias=vec(given(initial.accel_bias_std_m_s2, noise["accel_bias_std_m_s2"])),
        std0_gyro_scale=vec(given(initial.gyro_scale_std, config.gyro_scale_std)),
        std0_accel_scale=vec(given(initial.accel_scale_std, config.accel_scale_std)),
        std0_baro_bias=float(given(initial.baro_bias_std_m, config.baro_bias_std_m)),
        std0_odo_scale=float(given(initial.odometer_scale_std, config.odometer_scale_std)),
        std0_odo_mount=np.broadcast_to(np.asarray(given(initial.odometer_mount_std_rad,
                                                        config.odometer_mount_std_rad), float),
                                       (2,)).tolist(),
        # the batch API starts from the given attitude (no alignment phase); the alignment
        # parameters at their spec defaults
        align_time=0.0, align_heading=0, align_min_speed=1.0, align_travel_std=float(np.radians(10.0)))
    return params


_INS_FLOAT_OUT = ("q", "v", "lat", "lon", "h", "time_s", "std", "sensors", "nis", "update_time")
_INS_INT_OUT = ("standstill", "update_status", "update_count", "aligning")
_INS_GNSS_IN = ("gnss_time_s", "gnss_lat_rad", "gnss_lon_rad", "gnss_h_m", "gnss_vel_enu_m_s",
                "gnss_pos_std_m", "gnss_vel_std_m_s")
_INS_KINDS = 7     # per-kind monitoring outputs: GF_INS_MEAS_GNSS_POS .. GF_INS_MEAS_ZARU


def _monitor_innovations(counts, counts_before, update_time, update_status, nis) -> np.ndarray:
    """The innovation log of consecutive steps of the integrated-navigator FMU rebuilt from
    its per-kind monitoring outputs (rows: steps; columns: kinds GF_INS_MEAS_GNSS_POS ..
    ZARU): a kind's ``update_count`` grows by one per update, whose time, outcome and NIS
    ``update_time``, ``update_status`` and ``nis`` hold; the updates of a step ordered by
    time, then kind, as the core makes them. ``counts_before``: the counts before the
    first row. Fields t_s, type, status, m, nis; r and s_std NaN (not FMU outputs)."""
    from gfins_fmi.estimation.ins_gnss import _INNOV_DTYPE
    counts = np.asarray(counts)
    if len(counts) == 0:
        return np.zeros(0, _INNOV_DTYPE)
    # a count that changed is an update, unless the kind says "none yet" (status -1):
    # the monitoring restarts at the end of an alignment phase, and its counts drop to 0
    changed = counts != np.vstack([np.asarray(counts_before)[None, :], counts[:-1]])
    grew = changed & (np.asarray(update_status) != -1)
    r, k = np.nonzero(grew)
    t = np.asarray(update_time)[r, k]
    order = np.lexsort((k, t, r))
    r, k, t = r[order], k[order], t[order]
    inn = np.zeros(len(r), _INNOV_DTYPE)
    ty = k + 1
    inn["t_s"], inn["type"] = t, ty
    inn["status"], inn["nis"] = np.asarray(update_status)[r, k], np.asarray(nis)[r, k]
    inn["m"] = np.select([ty <= 2, ty == 5, ty <= 4], [3, 2, 1], 3)
    inn["r"] = inn["s_std"] = np.nan
    return inn


class _InsGnssDriver:
    """The integrated-navigator FMU fed a record by fmpy: one ``doStep`` per IMU sample at
    the sample's own time (increments: first a step at the start time without a sample),
    each measurement in the step of the first sample whose time reaches its time of
    validity within 1e-9 s — the grouping of ``gf_ins_run`` — so the FMU makes the core
    calls the batch API makes. Used by :func:`run_ins_gnss_fmu`; the tests roll it back
    through FMU states."""

    def __init__(self, imu, gnss, baro, odometer, *, config, initial, gnss_velocity=True,
                 fmi_version=2, path=None, parameters=None, logging_on=False, echo=None):
        from gfins_fmi.estimation.ins_gnss import _gather_measurements
        params = ins_gnss_fmu_parameters(config, initial)
        params.update(parameters or {})
        t = np.ascontiguousarray(np.asarray(imu.t_s, dtype=float))
        n = t.shape[0] if t.ndim == 1 else 0
        if t.ndim != 1 or n == 0:
            raise ValueError(f"imu.t_s must be a non-empty (n,) array; got shape {t.shape}")
        g = as_rows("imu.gyro", imu.gyro, 3, "rad or rad/s")
        a = as_rows("imu.accel", imu.accel, 3, "m/s or m/s^2")
        if g.shape[0] != n or a.shape[0] != n:
            raise ValueError(f"imu.gyro and imu.accel must have {n} rows like imu.t_s")
        kind = getattr(imu, "kind", config.input)
        if kind != config.input:
            raise ValueError(f"the IMU record holds {kind!r} but the filter is configured for "
                             f"input={config.input!r}")
        _gather_measurements(gnss, baro, odometer, gnss_velocity)   # the batch API's checks
        t0 = float(initial.nav.t_s)
        self.increments = config.input == "increments"
        if self.increments:
            if not t[0] > t0:
                raise ValueError(f"imu.t_s[0] = {t[0]!r} s must be after initial.nav.t_s = "
                                 f"{t0!r} s: an increment covers the interval since the "
                                 "previous sample")
            times = np.r_[t0, t]
        else:
            if t[0] != t0:
                raise ValueError(f"with rates the FMU takes the first sample at its start time: "
                                 f"initial.nav.t_s = {t0!r} s must equal imu.t_s[0] = {t[0]!r} s")
            times = t.copy()
        self.shift = 1 if self.increments else 0         # FMU step k = record row k - shift
        h = np.diff(times)
        self.times = times
        self.h = np.r_[h, h[-1] if len(h) else 1e-3]
        self.imu = np.c_[g, a]
        self.n_steps = len(times)
        t_reach = t + 1e-9              # gf_ins_run: sample k takes t_m <= t_k + 1e-9 s

        def schedule(tm, what):
            k = np.searchsorted(t_reach, np.asarray(tm, dtype=float), side="left")
            at = np.full(self.n_steps, -1)
            keep = np.flatnonzero(k < n)   # after the last sample: not delivered (as the batch)
            ks = k[keep]
            if np.any(np.diff(ks) == 0):
                j = int(ks[np.flatnonzero(np.diff(ks) == 0)[0]])
                raise ValueError(f"two {what} measurements fall into the interval of IMU sample "
                                 f"{j} (t = {t[j]!r} s): the FMU takes one per kind and step")
            at[ks + self.shift] = keep
            return at

        nan3 = np.full(3, np.nan)
        self.gnss_at = self.baro_at = self.odo_at = np.full(self.n_steps, -1)
        vel_valid = 0
        if gnss is not None:
            self.gnss_at = schedule(gnss.t_s, "GNSS")
            vel = getattr(gnss, "vel_enu_m_s", None) if gnss_velocity else None
            vel_valid = int(vel is not None)
            m = len(gnss.t_s)
            v = np.asarray(vel, float) if vel is not None else np.tile(nan3, (m, 1))
            vs = np.asarray(gnss.vel_std_m_s, float) if vel is not None else np.tile(nan3, (m, 1))
            self.gnss = np.c_[gnss.t_s, gnss.lat_rad, gnss.lon_rad, gnss.h_m, v,
                              np.asarray(gnss.pos_std_m, float), vs]
        if baro is not None:
            self.baro_at = schedule(baro.t_s, "barometer")
            self.baro = np.c_[baro.t_s, baro.h_m, baro.std_m]
        if odometer is not None:
            self.odo_at = schedule(odometer.t_s, "odometer")
            self.odo = np.c_[odometer.t_s, odometer.speed_m_s, odometer.std_m_s]
        params["gnss_vel_valid"] = vel_valid
        self.params = params
        self.version = fmi_version
        self.config = config
        self.log = _Log(echo)
        path = pathlib.Path(path) if path else fmu_path("ins_gnss", fmi_version)
        from fmpy.fmi1 import FMICallException
        try:
            self.slave = _Slave(path, fmi_version, self.log, logging_on)
        except FMICallException as exc:
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU could not be instantiated: "
                              f"{exc}", self.log.messages) from exc
        s = self.slave
        self.g_imu = s.group(["dtheta", "dv"] if self.increments else ["gyro_rate", "specific_force"])
        self.g_flags = s.group(["gnss_valid", "baro_valid", "odo_valid"])
        self.g_gnss = s.group(_INS_GNSS_IN)
        self.g_baro = s.group(["baro_time_s", "baro_h_m", "baro_std_m"])
        self.g_odo = s.group(["odo_time_s", "odo_speed_m_s", "odo_std_m_s"])
        self.g_out_f = s.group(_INS_FLOAT_OUT)
        self.g_out_i = s.group(_INS_INT_OUT)
        self.cols_f = self._columns(_INS_FLOAT_OUT)
        self.cols_i = self._columns(_INS_INT_OUT)
        self.out_f = np.full((self.n_steps, self.g_out_f[1]), np.nan)
        self.out_i = np.zeros((self.n_steps, self.g_out_i[1]), np.int64)
        self._flags = None
        self.failed_step = None

    def _columns(self, names) -> dict:
        cols, c = {}, 0
        for name in names:
            k = self.slave.refs(name)[1]
            cols[name] = slice(c, c + k)
            c += k
        return cols

    def initialize(self) -> None:
        self.slave.initialize(float(self.times[0]), float(self.times[-1] + self.h[-1]), self.params)

    def forget_inputs(self) -> None:
        """After an FMU state was restored (it holds the inputs): set every input again."""
        self._flags = None

    def run(self, k0: int, k1: int, bar=None) -> None:
        """FMU steps k0 .. k1 - 1; outputs into ``out_f``/``out_i`` rows k0 .. k1 - 1."""
        s = self.slave
        for k in range(k0, k1):
            r = k - self.shift
            if r >= 0:
                s.set_group(self.g_imu, self.imu[r])
            jg, jb, jo = int(self.gnss_at[k]), int(self.baro_at[k]), int(self.odo_at[k])
            flags = (int(jg >= 0), int(jb >= 0), int(jo >= 0))
            if flags != self._flags:
                s.set_group(self.g_flags, flags)
                self._flags = flags
            if jg >= 0:
                s.set_group(self.g_gnss, self.gnss[jg])
            if jb >= 0:
                s.set_group(self.g_baro, self.baro[jb])
            if jo >= 0:
                s.set_group(self.g_odo, self.odo[jo])
            try:
                s.slave.doStep(currentCommunicationPoint=float(self.times[k]),
                               communicationStepSize=float(self.h[k]))
            except Exception:
                self.failed_step = k
                raise
            self.out_f[k] = s.get_group(self.g_out_f)
            self.out_i[k] = s.get_group(self.g_out_i)
            if bar is not None and k % 1000 == 999:
                bar.update(1000)

    def solution(self, k_end: int | None = None):
        """The IntegratedSolution of the record rows whose FMU steps are done (up to FMU
        step ``k_end``, default all)."""
        from gfins_fmi.estimation import IntegratedSolution
        k_end = self.n_steps if k_end is None else k_end
        F, I = self.out_f[self.shift:k_end], self.out_i[self.shift:k_end]
        cf, ci = self.cols_f, self.cols_i
        counts = self.out_i[:, ci["update_count"]]
        before = counts[self.shift - 1] if self.shift else np.zeros(_INS_KINDS, np.int64)
        inn = _monitor_innovations(counts[self.shift:k_end], before, F[:, cf["update_time"]],
                                   I[:, ci["update_status"]], F[:, cf["nis"]])
        return IntegratedSolution(
            F[:, cf["time_s"]][:, 0].copy(), F[:, cf["q"]].copy(), F[:, cf["v"]].copy(),
            F[:, cf["lat"]][:, 0].copy(), F[:, cf["lon"]][:, 0].copy(), F[:, cf["h"]][:, 0].copy(),
            F[:, cf["std"]].copy(), F[:, cf["sensors"]].copy(),
            I[:, ci["standstill"]][:, 0].astype(bool), inn, self.config)

    def close(self) -> None:
        self.slave.close()


def run_ins_gnss_fmu(imu, gnss=None, baro=None, odometer=None, *, config, initial,
                     gnss_velocity: bool = True, fmi_version: int = 2,
                     path: str | pathlib.Path | None = None, parameters: Mapping | None = None,
                     logging_on: bool = False, echo: Callable[[str], None] | None = None,
                     progress: bool = False):
    """Run a record through the integrated-navigator FMU with fmpy as the master; the
    result lines up with ``IntegratedNavigator(config, initial).run(imu, gnss, baro,
    odometer)`` (row k: the state after IMU sample k).

    One ``doStep`` per IMU sample at the sample's time (with increments, a first step at
    ``initial.nav.t_s`` only starts the run; with rates ``imu.t_s[0]`` must be
    ``initial.nav.t_s``); each measurement is delivered in the step of the first sample
    whose time reaches its time of validity (within 1e-9 s), where the FMU splits the
    IMU interval at it. Measurements valid after the last sample are not delivered.

    Parameters
    ----------
    imu, gnss, baro, odometer, gnss_velocity
        As :meth:`gfins_fmi.estimation.IntegratedNavigator.run` (at most one measurement
        of a kind per IMU interval).
    config : FilterConfig
    initial : InitialState
        Turned into start values by :func:`ins_gnss_fmu_parameters`.
    parameters : mapping, optional
        More start values (FMI 3.0 names), overriding those.

    Returns
    -------
    gfins_fmi.estimation.IntegratedSolution
        ``innovations`` is rebuilt from the FMU's per-kind monitoring outputs: ``t_s``,
        ``type``, ``status``, ``m``, ``nis`` of every update; ``r`` and ``s_std`` are NaN
        (the FMU reports the NIS, not the residuals).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and, in ``partial``, the solution of the
        samples before it.
    """
    from fmpy.fmi1 import FMICallException
    drv = _InsGnssDriver(imu, gnss, baro, odometer, config=config, initial=initial,
                         gnss_velocity=gnss_velocity, fmi_version=fmi_version, path=path,
                         parameters=parameters, logging_on=logging_on, echo=echo)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=drv.n_steps, unit="step", unit_scale=True, desc="ins_gnss FMU")
    try:
        try:
            drv.initialize()
        except FMICallException as exc:
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU refused its parameters: {exc} "
                              f"FMU log: {'; '.join(drv.log.messages) or 'no message logged'}",
                              drv.log.messages) from exc
        try:
            drv.run(0, drv.n_steps, bar)
        except FMICallException as exc:
            k = drv.failed_step
            row = k - drv.shift
            raise FmuRunError(f"FMI {fmi_version}.0 ins_gnss FMU failed at record row {row}: {exc} "
                              f"FMU log: {'; '.join(drv.log.messages) or 'no message logged'}",
                              drv.log.messages, drv.solution(k)) from exc
        if bar:
            bar.update(drv.n_steps - bar.n)
        return drv.solution()
    finally:
        if bar:
            bar.close()
        drv.close()
