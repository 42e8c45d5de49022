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
from typing import Callable

import numpy as np

from gfins_fmi._lib import GfinsError, as_positive_scalar, as_rows, as_vector3
from gfins_fmi.accel_array import Accel9Solution

__all__ = ["MODELS", "fmu_path", "validate", "run_accel9_fmu", "FmuRunError"]

#: model name -> model identifier of the FMUs shipped
MODELS = {"accel9": "gfins_accel9"}


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
        One of :data:`MODELS` (``"accel9"``: the 9-accelerometer solver).
    fmi_version : {2, 3}
        FMI 2.0 (scalar variables, structured names ``A[1]`` ...) or FMI 3.0 (arrays).
    """
    if model not in MODELS:
        raise ValueError(f"unknown FMU model {model!r}; choose one of {sorted(MODELS)}")
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version must be 2 or 3; got {fmi_version!r}")
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


_ACCEL9_OUTPUTS = ("f", "omega", "omega_dot", "omega_sq")


class _Accel9Fmu:
    """One instance of the accel9 FMU through fmpy, FMI 2 or FMI 3."""

    def __init__(self, path: pathlib.Path, fmi_version: int, log: _Log, logging_on: bool):
        from fmpy import extract, read_model_description
        self.version = fmi_version
        self.md = read_model_description(str(path))
        self.unzipdir = extract(str(path))
        vars_ = {v.name: v for v in self.md.modelVariables}
        self.vr = {}
        self.log = log
        if fmi_version == 2:
            from fmpy.fmi2 import (FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE,
                                   fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE)
            from fmpy import calloc, free
            for name, n in (("l", 0), ("omega_init", 3), ("A", 9), ("f", 3), ("omega", 3),
                            ("omega_dot", 3), ("omega_sq", 3), ("flags", 0)):
                names = [name] if n == 0 else [f"{name}[{i + 1}]" for i in range(n)]
                self.vr[name] = [vars_[s].valueReference for s in names]
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName="accel9")
            cb = fmi2CallbackFunctions()
            self._logger = fmi2CallbackLoggerTYPE(
                lambda env, name, status, cat, msg: log.add(status, cat, msg, fmi2=True))
            cb.logger = self._logger
            # the FMU declares canNotUseMemoryManagementFunctions; fmpy's C allocator
            # is passed anyway because the standard asks for non-NULL pointers
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            # No fmpy.logging.addLoggerProxy: it keeps one global logger for the whole
            # process, which would outlive this object. The FMU passes the formatted text
            # as the format with '%' doubled (see fmi2_glue.c), undone in _Log.add.
            self._callbacks = cb
            self.slave.instantiate(callbacks=cb, loggingOn=logging_on)
            self.set_real, self.get_real = self.slave.setReal, self.slave.getReal
            self.get_int = self.slave.getInteger
        else:
            from fmpy.fmi3 import FMU3Slave
            for name in ("l", "omega_init", "A", "f", "omega", "omega_dot", "omega_sq", "flags"):
                self.vr[name] = [vars_[name].valueReference]
            self.slave = FMU3Slave(guid=self.md.instantiationToken, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName="accel9")
            self.slave.instantiate(loggingOn=logging_on,
                                   logMessage=lambda env, status, cat, msg: log.add(status, cat, msg))
            self.set_real = self.slave.setFloat64
            self.get_real = lambda vr, n=None: self.slave.getFloat64(vr, n)
            self.get_int = self.slave.getInt32
        self.n_out = {"f": 3, "omega": 3, "omega_dot": 3, "omega_sq": 3}

    def initialize(self, start_s: float, stop_s: float, l_m: float, omega_init) -> None:
        if self.version == 2:
            self.slave.setupExperiment(startTime=start_s, stopTime=stop_s)
            self.slave.enterInitializationMode()
        else:
            self.slave.enterInitializationMode(startTime=start_s, stopTime=stop_s)
        self.set_real(self.vr["l"], [l_m])
        self.set_real(self.vr["omega_init"], list(omega_init))
        self.slave.exitInitializationMode()

    def outputs(self) -> tuple[list[list[float]], int]:
        if self.version == 2:
            vals = [self.get_real(self.vr[name]) for name in _ACCEL9_OUTPUTS]
        else:
            vals = [self.get_real(self.vr[name], 3) for name in _ACCEL9_OUTPUTS]
        return vals, int(self.get_int(self.vr["flags"])[0])

    def step(self, A_row, t_s: float, h_s: float) -> None:
        self.set_real(self.vr["A"], A_row)
        self.slave.doStep(currentCommunicationPoint=t_s, communicationStepSize=h_s)

    def close(self) -> None:
        try:
            self.slave.terminate()
        except Exception:
            pass
        self.slave.freeInstance()
        shutil.rmtree(self.unzipdir, ignore_errors=True)


def run_accel9_fmu(A_m_s2, dt_s: float, l_m: float, omega_init_rad_s=(0.0, 0.0, 0.0), *,
                   fmi_version: int = 2, start_time_s: float = 0.0,
                   path: str | pathlib.Path | None = None, logging_on: bool = False,
                   echo: Callable[[str], None] | None = None) -> Accel9Solution:
    """Run a record through the 9-accelerometer FMU with fmpy as the master.

    One ``doStep`` per sample (communication step ``dt_s``); the outputs read after the
    step of sample k are row k of the result, so it lines up with
    :func:`gfins_fmi.solve_accel9` on the same record.

    Parameters
    ----------
    A_m_s2 : array_like, shape (n, 9)
        Accelerometer outputs, m/s^2.
    dt_s, l_m, omega_init_rad_s
        As for :func:`gfins_fmi.solve_accel9`.
    fmi_version : {2, 3}
        Which FMU to run.
    start_time_s : float
        Time of the first sample, s.
    path : path, optional
        An FMU file to run instead of the shipped one.
    logging_on : bool
        Ask the FMU for debug messages too (errors are always logged).
    echo : callable, optional
        Called with each log line as it arrives (e.g. ``print``).

    Raises
    ------
    FmuRunError
        An FMU call failed; carries the FMU's log and the rows completed.
    """
    A = as_rows("A_m_s2", A_m_s2, 9, "m/s^2")
    dt_s = as_positive_scalar("dt_s (sampling interval)", dt_s, "s")
    l_m = float(l_m)  # the FMU itself validates l: that check is part of what runs here
    w0 = as_vector3("omega_init_rad_s", omega_init_rad_s, "rad/s")
    n = A.shape[0]
    fmu_file = pathlib.Path(path) if path else fmu_path("accel9", fmi_version)
    log = _Log(echo)
    out = Accel9Solution(np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                         np.empty((n, 3)), np.empty(n, dtype=np.uint8))
    fmu = _Accel9Fmu(fmu_file, fmi_version, log, logging_on)
    k = 0
    try:
        fmu.initialize(start_time_s, start_time_s + n * dt_s, l_m, w0)
        for k in range(n):
            fmu.step(A[k].tolist(), start_time_s + k * dt_s, dt_s)
            vals, flags = fmu.outputs()
            out.f_m_s2[k], out.omega_rad_s[k], out.omega_dot_rad_s2[k], out.omega_sq_rad2_s2[k] = vals
            out.flags[k] = flags
        k = n
    except Exception as exc:
        from fmpy.fmi1 import FMICallException
        if not isinstance(exc, FMICallException):
            raise
        detail = "; ".join(log.messages) or "no message logged"
        raise FmuRunError(f"FMI {fmi_version}.0 FMU failed at sample {k}: {exc} FMU log: {detail}",
                          log.messages, out._head(k)) from exc
    finally:
        fmu.close()
    return out
