"""OSP libcosim as a second, independent co-simulation master.

libcosim (Open Simulation Platform, C++, FMI Library for FMI 2.0 import; ``libcosimpy``
is its Python binding, an optional dependency: ``pip install 'gfins_fmi[osp]'``) runs
the FMI 2.0 FMUs of a :class:`gfins_fmi.fmi.system.System` (:func:`run_libcosim`) or the SSP
file that :func:`gfins_fmi.fmi.ssp.write_ssp` writes (:func:`run_libcosim_ssp`), with
its fixed-step algorithm; the results come back in the layout of
:meth:`gfins_fmi.fmi.master.CoSimulation.run`.

What libcosim does, as measured here against our master (docs/cosim.md):

* **Jacobi.** Every FMU steps from the same communication point with the inputs set
  from the outputs read after the previous step (libcosim steps the FMUs in parallel
  threads, then transfers); after initialization the connections are propagated, so
  the first step sees the outputs at the start time (no ``skip_steps`` needed, unlike
  fmpy's SSP simulator).
* **Integer-nanosecond clock.** Time is an int64 count of nanoseconds (the step must be
  a whole number of them). An FMU gets t_k = (k h_ns) / 1e9 as a double and the step
  t_(k+1) - t_k — not t0 + k h and h, which differ by an ulp now and then. With those
  communication points (:func:`communication_points`, passed to ``CoSimulation.run``)
  our master produces libcosim's results bit for bit.
* **SSP.** It reads the archive's SystemStructure.ssd, the components' ParameterBindings
  (a system-level binding it ignores: :func:`gfins_fmi.fmi.ssp.write_ssp` binds per
  component) and the connections; the step size is given here (our .ssd carries no OSP
  algorithm annotation).
"""
from __future__ import annotations

import ctypes
import pathlib
import tempfile
import zipfile
from typing import Mapping

import numpy as np

from gfins_fmi._lib import as_scalar
from gfins_fmi.fmi.paths import MODELS, FmuRunError, fmu_path
from gfins_fmi.fmi.runner import FmuLog, FmuSlave

__all__ = ["available", "communication_points", "run_libcosim", "run_libcosim_ssp"]

_NS = 1_000_000_000


def available() -> str | None:
    """None when libcosimpy can be used here, else the reason it cannot."""
    try:
        # lazy: libcosimpy: optional extra (OSP)
        import libcosimpy.CosimExecution  # noqa: F401
        from libcosimpy._internal import libcosimc
        libcosimc()                  # loads the bundled C library (lazily loaded otherwise)
    except ImportError as exc:
        return (f"libcosimpy is not importable ({exc}); pip install 'gfins_fmi[osp]' "
                "(wheels for Linux x86_64 and Windows x64, Python 3.11-3.14)")
    except OSError as exc:       # the bundled libcosimc shared library does not load
        return f"libcosimpy's libcosimc does not load here: {exc}"
    return None


def _libcosim():
    reason = available()
    if reason:
        raise ImportError(reason)
    # lazy: libcosimpy: optional extra (OSP)
    from libcosimpy import CosimExecution, CosimLogging, CosimObserver
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimSlave import CosimLocalSlave
    return CosimExecution.CosimExecution, CosimLocalSlave, CosimObserver.CosimObserver, \
        CosimVariableType, CosimLogging


def _log_level(level: str) -> None:
    """libcosim's log output level (global to the library): trace ... fatal."""
    logging = _libcosim()[4]
    try:
        logging.log_output_level(logging.CosimLogLevel[level.upper()])
    except KeyError:
        raise ValueError(f"log_level must be one of "
                         f"{[m.name.lower() for m in logging.CosimLogLevel]}; got {level!r}") from None


def _step_ns(step_s: float) -> int:
    step_s = as_scalar("step_s", step_s, "s", above=0.0)
    ns = int(round(step_s * _NS))
    if ns < 1 or abs(ns - step_s * _NS) > 1e-6 * ns:
        raise ValueError(f"step_s = {step_s!r} s is not a whole number of nanoseconds, "
                         "libcosim's time unit")
    return ns


def communication_points(step_s: float, n_steps: int) -> np.ndarray:
    """The n_steps + 1 communication points (s) of a libcosim run from 0: k h_ns / 1e9,
    as libcosim converts its nanosecond clock for the FMUs."""
    return (np.arange(int(n_steps) + 1, dtype=np.int64) * _step_ns(step_s)).astype(float) / _NS


def _steps(stop_s: float, step_s: float) -> int:
    n = int(round(stop_s / step_s))
    if n < 1:
        raise ValueError(f"stop_s = {stop_s!r} s is shorter than one step ({step_s!r} s)")
    return n


class _Run:
    """One libcosim execution: slaves by name, their variables, a time-series observer."""

    def __init__(self, execution, n_rows: int):
        Observer, self.VT = _libcosim()[2:4]
        self.ex = execution
        self.index = {info.name.decode(): info.index for info in self.ex.slave_infos()}
        self.vars = {name: {v.name.decode(): v for v in self.ex.slave_variables(i)}
                     for name, i in self.index.items()}
        # every row kept (without a size libcosim keeps the last 10 000 samples)
        self.obs = Observer.create_time_series(buffer_size=int(n_rows))
        self.ex.add_observer(self.obs)
        self.recorded: dict = {}        # "comp.var" -> [scalar variable descriptions]

    def scalars(self, comp: str, var: str) -> list:
        """The FMI 2.0 scalar variables of ``var`` (FMI 3.0 name: ``v`` -> v[1], v[2] ...)."""
        vs = self.vars[comp]
        if var in vs:
            return [vs[var]]
        out, i = [], 1
        while f"{var}[{i}]" in vs:
            out.append(vs[f"{var}[{i}]"])
            i += 1
        if not out:
            raise ValueError(f"component {comp!r} has no variable {var!r}")
        return out

    def record(self, outputs: Mapping[str, list]) -> None:
        for comp, names in outputs.items():
            if comp not in self.index:
                raise ValueError(f"no component {comp!r} in the libcosim execution "
                                 f"(has {sorted(self.index)})")
            for var in names:
                scalars = self.scalars(comp, var)
                for v in scalars:
                    self.obs.start_time_series(self.index[comp], v.reference, self.VT(v.type))
                self.recorded[f"{comp}.{var}"] = (comp, scalars)

    def _series(self, comp: str, v, n_rows: int) -> np.ndarray:
        """Rows 0..n_rows-1 of one recorded variable, read with libcosimc's C function
        (cosim_observer_slave_get_{real,integer}_samples) straight into numpy arrays:
        libcosimpy's reader builds Python lists (half of a 60 000-step run's time) and
        drops one sample when step 0 is among those read (0.0.6)."""
        from libcosimpy._internal import libcosimc   # lazy: libcosimpy: optional extra (OSP)
        real = self.VT(v.type) == self.VT.REAL
        fn = libcosimc()["cosim_observer_slave_get_real_samples" if real
                         else "cosim_observer_slave_get_integer_samples"]
        ctype = ctypes.c_double if real else ctypes.c_int
        fn.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32, ctypes.c_int64, ctypes.c_size_t,
                       ctypes.POINTER(ctype), ctypes.POINTER(ctypes.c_int64), ctypes.POINTER(ctypes.c_int64)]
        fn.restype = ctypes.c_int64
        values = np.empty(n_rows, np.float64 if real else np.intc)
        steps = np.empty(n_rows, np.int64)
        times = np.empty(n_rows, np.int64)
        got = fn(ctypes.cast(self.obs.ptr(), ctypes.c_void_p), self.index[comp], v.reference, 0, n_rows,
                 values.ctypes.data_as(ctypes.POINTER(ctype)),
                 steps.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
                 times.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)))
        if got != n_rows or not np.array_equal(steps, np.arange(n_rows)):
            raise FmuRunError(f"libcosim returned {got} samples of {comp}.{v.name.decode()} "
                              f"(steps {steps[:min(got, 3)].tolist()}...); expected steps 0..{n_rows - 1}", [])
        return values.astype(float)

    def simulate(self, n_steps: int, step_ns: int) -> dict:
        from libcosimpy._internal import get_last_error_message   # lazy: libcosimpy: optional extra (OSP)
        if not self.ex.simulate_until(n_steps * step_ns):
            raise FmuRunError(f"libcosim stopped with an error: {get_last_error_message()}",
                              [get_last_error_message()])
        status = self.ex.status()
        if status.current_time != n_steps * step_ns:
            raise FmuRunError(f"libcosim stopped at {status.current_time} ns, not "
                              f"{n_steps * step_ns} ns: {get_last_error_message()}", [])
        out = {key: np.stack([self._series(comp, v, n_steps + 1) for v in scalars], axis=1)
               for key, (comp, scalars) in self.recorded.items()}
        out["time"] = communication_points(step_ns / _NS, n_steps)
        return out


def _connect_integers(ex):
    """``CosimExecution.connect_integer_variables``; libcosimpy 0.0.6's calls a function
    it never defined (AttributeError): then the C function it wrapped under another name."""
    def connect(*args):
        try:
            return ex.connect_integer_variables(*args)
        except AttributeError:
            return ex._CosimExecution__connect_int_variables(ex._CosimExecution__ptr, *args)
    return connect


def _check_initialization(components, stop_s: float) -> None:
    """Initialise each (name, FMI 2.0 FMU path, scalar start values) with fmpy and raise
    FmuRunError with the FMU's log if it refuses: inside libcosim an FMU that fails its
    initialization ends the whole process (libcosimpy 0.0.6: the error escapes one of
    libcosim's worker threads), so start values are checked before it sees them."""
    from fmpy.fmi1 import FMICallException   # lazy: fmpy (~30 ms) only where an FMU runs

    for name, path, params in components:
        log = FmuLog()
        slave = FmuSlave(pathlib.Path(path), 2, log, False, instance_name=name)
        try:
            slave.initialize(0.0, stop_s, params)
        except FMICallException as exc:
            raise FmuRunError(f"{name} refuses its start values ({exc}): "
                              f"{'; '.join(log.messages[-3:]) or 'no message logged'}",
                              log.messages) from None
        finally:
            slave.close()


def run_libcosim(system, stop_s: float | None = None, step_s: float | None = None,
                 log_level: str = "warning") -> dict:
    """Run a :class:`gfins_fmi.fmi.system.System` with libcosim (its FMI 2.0 FMUs).

    Start values are set as libcosim initial values; every connection (Real or Integer
    scalars) is a libcosim connection; ``system.outputs`` are recorded by a time-series
    observer after the initialization and after every step.

    Returns
    -------
    dict "comp.var" -> ndarray (n_steps + 1, size), plus "time" (n_steps + 1,): the
    layout of ``CoSimulation.run`` (row k: the outputs at communication point k).

    Raises
    ------
    ImportError
        libcosimpy cannot be used here (the message says why).
    ValueError
        A step that is not a whole number of nanoseconds, an unknown variable.
    FmuRunError
        An FMU refuses its start values (checked first, with its log), or libcosim
        stopped with an error (its message).
    """
    Execution, LocalSlave, _, VT, _ = _libcosim()
    _log_level(log_level)
    h = system.step_s if step_s is None else step_s
    stop = system.stop_s if stop_s is None else stop_s
    ns = _step_ns(h)
    n = _steps(stop, ns / _NS)
    _check_initialization([(name, fmu_path(model, 2), system.scalar_parameters(name))
                           for name, (model, _) in system.components.items()], n * ns / _NS)
    ex = Execution.from_step_size(ns)
    slaves = []                              # kept alive while the execution runs
    for name, (model, _) in system.components.items():
        if model not in MODELS:
            raise ValueError(f"component {name}: unknown model {model!r}")
        slaves.append(LocalSlave(str(fmu_path(model, 2)), name))
        if ex.add_local_slave(slaves[-1]) < 0:
            raise FmuRunError(f"libcosim could not load {model}'s FMI 2.0 FMU", [])
    run = _Run(ex, n + 1)
    for name in system.components:
        for key, value in system.scalar_parameters(name).items():
            (v,) = run.scalars(name, key)
            if VT(v.type) == VT.REAL:
                ok = ex.real_initial_value(run.index[name], v.reference, float(value))
            else:
                ok = ex.integer_initial_value(run.index[name], v.reference, int(value))
            if not ok:
                raise ValueError(f"libcosim refused the start value {name}.{key} = {value!r}")
    for c in system.connections:
        for a, b in c.scalars():
            (src,), (dst,) = run.scalars(c.source, a), run.scalars(c.dest, b)
            connect = ex.connect_real_variables if VT(src.type) == VT.REAL else _connect_integers(ex)
            if connect(run.index[c.source], src.reference, run.index[c.dest], dst.reference) != 0:
                raise ValueError(f"libcosim refused the connection {c.source}.{a} -> {c.dest}.{b}")
    run.record(system.outputs)
    return run.simulate(n, ns)


def run_libcosim_ssp(path: str | pathlib.Path, outputs: Mapping[str, list], stop_s: float,
                     step_s: float, log_level: str = "warning") -> dict:
    """Load an SSP file (e.g. written by :func:`gfins_fmi.fmi.ssp.write_ssp`) into libcosim
    and run it with a fixed step; libcosim applies the archive's parameter set and
    connections itself. ``outputs``: {component: [variable (FMI 3.0 name)]} to record.
    Returns the layout of :func:`run_libcosim`."""
    Execution = _libcosim()[0]
    _log_level(log_level)
    ns = _step_ns(step_s)
    n = _steps(stop_s, ns / _NS)
    path = pathlib.Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no SSP file at {path}")
    from fmpy.ssp.ssd import read_ssd   # lazy: fmpy (~30 ms) only where an FMU runs
    with tempfile.TemporaryDirectory() as tmp:
        zipfile.ZipFile(path).extractall(tmp)
        _check_initialization(
            [(c.name, pathlib.Path(tmp) / c.source,
              {p.name: p.value for b in c.parameterBindings for ps in b.parameterValues
               for p in ps.parameters}) for c in read_ssd(str(path)).system.elements], n * ns / _NS)
    try:
        ex = Execution.from_ssp_file(str(path), ns)
    except AssertionError as exc:                 # libcosimpy's way of saying it failed
        from libcosimpy._internal import get_last_error_message   # lazy: libcosimpy: optional extra (OSP)
        raise FmuRunError(f"libcosim could not load {path}: {get_last_error_message()}", []) from exc
    run = _Run(ex, n + 1)
    run.record(outputs)
    return run.simulate(n, ns)
