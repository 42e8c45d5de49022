"""A :class:`~gfins_fmi.fmi.system.System` as one container FMU (fmpy's container_fmu)
holding its FMUs, for tools that take a single FMU, and its run by fmpy."""
from __future__ import annotations

import contextlib
import json
import pathlib
import tempfile
import types
from typing import Iterable

import numpy as np

from gfins_fmi.fmi.paths import fmu_path
from gfins_fmi.fmi.system import System

__all__ = ["write_container", "run_container"]


def write_container(system: System, path: str | pathlib.Path, fmi_version: int = 2) -> pathlib.Path:
    """One container FMU (fmpy.container_fmu) holding the system's FMUs of
    ``fmi_version``: the connections inside, the recorded outputs exposed as outputs
    ``comp_var`` (FMI 2.0: ``comp_var_i`` per element) and the system's start values as
    parameters ``comp_param``; internal fixed step ``system.step_s``."""
    from fmpy import read_model_description   # lazy: fmpy (~30 ms) only where an FMU runs
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
    import fmpy.container_fmu as cfmu   # lazy: fmpy (~30 ms) only where an FMU runs
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
    from fmpy import simulate_fmu   # lazy: fmpy (~30 ms) only where an FMU runs
    return simulate_fmu(str(path), stop_time=stop_s, output_interval=step_s,
                        output=list(outputs) if outputs else None)
