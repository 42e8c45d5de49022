"""A :class:`~gfins_fmi.fmi.system.System` as an SSP 1.0 file (SystemStructure.ssd, the FMI
2.0 FMUs, a parameter set per component) that fmpy's SSP simulator, libcosim and other SSP
tools run, and its run by fmpy."""
from __future__ import annotations

import pathlib
import xml.etree.ElementTree as ET
import zipfile

import numpy as np

from gfins_fmi.fmi.paths import MODELS, fmu_path, fmu_variables
from gfins_fmi.fmi.system import System

__all__ = ["write_ssp", "run_ssp"]

_SSD = "http://ssp-standard.org/SSP1/SystemStructureDescription"
_SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
_SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"


def write_ssp(system: System, path: str | pathlib.Path, name: str = "VehicleNavigation") -> pathlib.Path:
    """Write ``system`` as an SSP 1.0 file with the FMI 2.0 FMUs (scalar connections).

    The archive holds SystemStructure.ssd (components, connectors, connections, the
    default experiment), resources/<fmu>.fmu and, per component, resources/<component>.ssv
    (its start values, named by variable) bound to the component by a ParameterBinding —
    the form both fmpy (through :func:`run_ssp`) and libcosim (which reads no
    system-level binding; :func:`gfins_fmi.fmi.osp.run_libcosim_ssp`) apply.
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
        variables = fmu_variables(model, 2)
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
    from fmpy.ssp.simulation import simulate_ssp   # lazy: fmpy (~30 ms) only where an FMU runs
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
