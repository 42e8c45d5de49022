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

__all__ = ["MODELS", "fmu_path", "validate", "run_fmu", "run_accel9_fmu", "run_sins_fmu", "run_gfnav_fmu",
           "FmuRunError"]

#: model name -> model identifier of the FMUs shipped
MODELS = {"accel9": "gfins_accel9", "sins": "gfins_sins", "gfnav_cube6": "gfins_gfnav_cube6",
          "gfnav_qin9": "gfins_gfnav_qin9", "gfnav_12": "gfins_gfnav_12",
          "vehicle": "gfins_vehicle"}


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
        the strapdown navigator).
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
                 progress: bool = False, imu_errors=None, lowpass_sos=None, **kwargs):
    """Run a record through the strapdown FMU; the result lines up with
    :meth:`gfins_fmi.Strapdown.run` on the same record (for increments, the FMU takes
    the increment over (t_(k-1), t_k] at t_k, so the record is shifted by one step
    internally and its first step only starts the run).

    ``imu_errors`` (:class:`gfins_fmi.ImuErrors`) switches on the FMU's compensation of
    its inputs; ``lowpass_sos`` (n_sections <= 8, 6) its low-pass after it (the same as
    ``ImuErrors.compensate`` followed by ``signal_conditioning.BiquadFilter`` on the six channels).

    Returns a :class:`gfins_fmi.NavSolution`.
    """
    from gfins_fmi.sins import _INPUTS, _VERTICAL, NavSolution, SinsConfig
    cfg = config or SinsConfig()
    if cfg.earth != "wgs84":
        raise ValueError("the SINS FMU navigates on WGS-84 only (earth='wgs84')")
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
    if cfg.input == "increments":
        # sample j of the record covers (t_j, t_(j+1)]: set it at t_(j+1)
        z = np.zeros((1, 3))
        ins = {"dtheta": np.r_[z, g], "dv": np.r_[z, a], "gyro_rate": np.zeros((n + 1, 3)),
               "specific_force": np.zeros((n + 1, 3)), "h_ext": np.r_[np.nan, he]}
    else:
        ins = {"gyro_rate": g, "specific_force": a, "dtheta": np.zeros((n, 3)),
               "dv": np.zeros((n, 3)), "h_ext": he}
    shift = 1 if cfg.input == "increments" else 0   # FMU step k takes record row k - shift

    def solution(d):
        sl = slice(shift, None)
        return NavSolution(d["time_s"][sl, 0], d["q"][sl], d["v"][sl], d["lat"][sl, 0],
                           d["lon"][sl, 0], d["h"][sl, 0])
    try:
        d = run_fmu("sins", ins, ["q", "v", "lat", "lon", "h", "time_s"], dt_s, parameters=params,
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
