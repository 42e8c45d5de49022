"""The generic runner of a shipped FMU: its log (:class:`FmuLog`), one instance through
fmpy's FMU2Slave / FMU3Slave with variables addressed by their FMI 3.0 names
(:class:`FmuSlave`, shared by every master of the package), and :func:`run_fmu`, fmpy as
the master of one FMU, one ``doStep`` per sample.

Sampling convention of every navigation FMU: ``doStep(t, h)`` processes the input
sample set for time ``t``; the outputs read after the step describe time ``t``.
"""
from __future__ import annotations

import pathlib
import shutil
from typing import Callable, Mapping

import numpy as np

from gfins_fmi._lib import as_positive_scalar, as_scalar
from gfins_fmi.fmi.paths import FmuRunError, fmu_path

__all__ = ["FmuLog", "FmuSlave", "run_fmu"]


class FmuLog:
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


class FmuSlave:
    """One instance of a shipped FMU through fmpy's FMU2Slave / FMU3Slave, with
    variables addressed by their FMI 3.0 names (FMI 2.0 scalars ``x[i]`` are gathered)."""

    def __init__(self, path: pathlib.Path, fmi_version: int, log: FmuLog, logging_on: bool,
                 instance_name: str | None = None):
        from fmpy import extract, read_model_description   # lazy: fmpy (~30 ms) only where an FMU runs
        self.version = fmi_version
        self.md = read_model_description(str(path))
        self.unzipdir = extract(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        if fmi_version == 2:
            from fmpy import calloc, free   # lazy: fmpy (~30 ms) only where an FMU runs
            from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE,
                                   fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                                   fmi2CallbackLoggerTYPE)
            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                   modelIdentifier=self.md.coSimulation.modelIdentifier,
                                   instanceName=instance_name or self.md.coSimulation.modelIdentifier)
            cb = fmi2CallbackFunctions()
            # No fmpy.logging.addLoggerProxy: it keeps one global logger for the whole
            # process, which would outlive this object. The FMU passes the formatted text
            # as the format with '%' doubled (see fmi2_glue.c), undone in FmuLog.add.
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
            from fmpy.fmi3 import FMU3Slave   # lazy: fmpy (~30 ms) only where an FMU runs
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
    log = FmuLog(echo)
    from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs
    try:
        slave = FmuSlave(path, fmi_version, log, logging_on)
    except FMICallException as exc:
        raise FmuRunError(f"FMI {fmi_version}.0 {model} FMU could not be instantiated: {exc} "
                          f"FMU log: {'; '.join(log.messages) or 'no message logged'}",
                          log.messages, {}) from exc
    out = {name: np.empty((n, slave.refs(name)[1])) for name in outputs}
    k = 0
    bar = None
    if progress:
        from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
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
