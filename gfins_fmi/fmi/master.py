"""The Python co-simulation master on fmpy's FMU2Slave / FMU3Slave (through
:class:`gfins_fmi.fmi.runner.FmuSlave`): Jacobi or Gauss-Seidel ordering, Float64 and
Int32 connections, roll-back through FMU states, progress bar."""
from __future__ import annotations

from typing import Callable

import numpy as np

from gfins_fmi.fmi.paths import MODELS, FmuRunError, fmu_path
from gfins_fmi.fmi.runner import FmuLog, FmuSlave
from gfins_fmi.fmi.system import System

__all__ = ["CoSimulation"]


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
        self.log = FmuLog(echo)
        self.slaves: dict[str, FmuSlave] = {}
        self.time_s = 0.0
        try:
            for name, (model, _) in system.components.items():
                if model not in MODELS:
                    raise ValueError(f"component {name}: unknown model {model!r}")
                self.slaves[name] = FmuSlave(fmu_path(model, fmi_version), fmi_version, self.log,
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
        from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs
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
        clock: :func:`gfins_fmi.fmi.osp.communication_points`).

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
            from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
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
