"""Generate an FMU's modelDescription.xml (FMI 2.0 and 3.0) and its C variable table
from a model spec (``fmu/models/<model>/model_spec.py``).

Usage::

    python fmugen.py SPEC.py OUTDIR [FILE ...]

writes ``OUTDIR/fmi2/modelDescription.xml``, ``OUTDIR/fmi3/modelDescription.xml`` and
``OUTDIR/model_vars.h`` (the glue's tables) and ``OUTDIR/model_extra.h`` (the spec's own
``c_extra`` C text, if it has one: tables a model.c derives from its spec, e.g. refusal
texts). The instantiation token is a hash of the spec and of the FILEs
(the model's ``model.h``, the core headers its ModelData embeds, this generator), so it
changes whenever the interface or the layout of a serialized FMU state can. Standard
library only: it runs at build time.
"""
from __future__ import annotations

import hashlib
import math
import pathlib
import runpy
import sys
from xml.sax.saxutils import quoteattr

# SI base-unit exponents of every unit a spec may use.
UNITS = {
    "m": dict(m=1),
    "s": dict(s=1),
    "m/s": dict(m=1, s=-1),
    "m/s2": dict(m=1, s=-2),
    "rad": dict(rad=1),
    "rad/s": dict(rad=1, s=-1),
    "rad/s2": dict(rad=1, s=-2),
    "rad2/s2": dict(rad=2, s=-2),
    "s2/m": dict(m=-1, s=2),
    "Hz": dict(s=-1),
}

CAUSALITY_C = {"independent": "FMU_CAUSALITY_INDEPENDENT", "parameter": "FMU_CAUSALITY_PARAMETER",
               "input": "FMU_CAUSALITY_INPUT", "output": "FMU_CAUSALITY_OUTPUT"}
VARIABILITY_C = {"fixed": "FMU_VARIABILITY_FIXED", "tunable": "FMU_VARIABILITY_TUNABLE",
                 "discrete": "FMU_VARIABILITY_DISCRETE", "continuous": "FMU_VARIABILITY_CONTINUOUS"}
TYPE_C = {"Float64": "FMU_TYPE_FLOAT64", "Int32": "FMU_TYPE_INT32"}
FMI2_TYPE = {"Float64": "Real", "Int32": "Integer"}


def _count(var: dict) -> int:
    return math.prod(var["shape"]) if var["shape"] else 1


def _initial(var: dict) -> str | None:
    if var["causality"] == "output":
        return "calculated"
    if var["causality"] == "parameter":
        return "exact"
    return None  # inputs: initial is not given for inputs


def _fmt(value, type_: str) -> str:
    if type_ != "Float64":
        return str(int(value))
    v = float(value)
    return "NaN" if math.isnan(v) else repr(v)   # xs:double spells it NaN


def _starts(var: dict) -> list:
    start = var.get("start")
    if start is None:
        return []
    if isinstance(start, (list, tuple)):
        if len(start) != _count(var):
            raise ValueError(f"{var['name']}: {len(start)} start values for {_count(var)} elements")
        return list(start)
    return [start] * _count(var)


def _unit_definitions(variables: list[dict], extra: tuple = ()) -> str:
    used = sorted({v["unit"] for v in variables if v.get("unit")} | set(extra))
    lines = ["  <UnitDefinitions>"]
    for name in used:
        if name not in UNITS:
            raise ValueError(f"unit {name!r} is not in fmugen.UNITS")
        attrs = " ".join(f'{k}="{e}"' for k, e in UNITS[name].items())
        lines.append(f'    <Unit name="{name}">\n      <BaseUnit {attrs}/>\n    </Unit>')
    lines.append("  </UnitDefinitions>")
    return "\n".join(lines)


def _log_categories() -> str:
    return ("  <LogCategories>\n"
            '    <Category name="logStatusError" description="Errors: bad input, bad call sequence"/>\n'
            '    <Category name="logStatusWarning" description="Warnings"/>\n'
            '    <Category name="logEvents" description="Initialization and termination"/>\n'
            "  </LogCategories>")


def _default_experiment(model: dict) -> str:
    d = model["default_experiment"]
    return (f'  <DefaultExperiment startTime="{d["start_time"]!r}" stopTime="{d["stop_time"]!r}" '
            f'stepSize="{d["step_size"]!r}"/>')


def _common_attrs(v: dict) -> str:
    s = f' causality="{v["causality"]}" variability="{v["variability"]}"'
    init = _initial(v)
    if init:
        s += f' initial="{init}"'
    return s


def fmi2_description(model: dict, token: str) -> tuple[str, list[tuple]]:
    """FMI 2.0 modelDescription; returns the XML and the scalar table (vr, var, element)."""
    scalars = []  # (vr, var, element index)
    vr = 1
    for v in model["variables"]:
        for e in range(_count(v)):
            scalars.append((vr, v, e))
            vr += 1
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           '<fmiModelDescription fmiVersion="2.0"'
           f' modelName="{model["model_name"]}" guid="{token}"'
           f' description={quoteattr(model["description"])}'
           ' generationTool="gfins_fmi fmugen" variableNamingConvention="structured"'
           ' numberOfEventIndicators="0">',
           f'  <CoSimulation modelIdentifier="{model["model_identifier"]}"'
           ' canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="true"'
           ' canSerializeFMUstate="true" canNotUseMemoryManagementFunctions="true"/>',
           _unit_definitions(model["variables"]), _log_categories(), _default_experiment(model),
           "  <ModelVariables>"]
    outputs, initial_unknowns = [], []
    for index, (vr, v, e) in enumerate(scalars, start=1):
        name = f'{v["name"]}[{e + 1}]' if v["shape"] else v["name"]
        starts = _starts(v)
        type_attrs = ""
        if v.get("unit"):
            type_attrs += f' unit="{v["unit"]}"'
        if starts:
            type_attrs += f' start="{_fmt(starts[e], v["type"])}"'
        out.append(f'    <ScalarVariable name="{name}" valueReference="{vr}"'
                   f' description={quoteattr(v["description"])}{_common_attrs(v)}>')
        out.append(f'      <{FMI2_TYPE[v["type"]]}{type_attrs}/>')
        out.append("    </ScalarVariable>")
        if v["causality"] == "output":
            outputs.append(index)
            if _initial(v) == "calculated":
                initial_unknowns.append(index)
    out.append("  </ModelVariables>")
    out.append("  <ModelStructure>")
    out.append("    <Outputs>")
    out += [f'      <Unknown index="{i}"/>' for i in outputs]
    out.append("    </Outputs>")
    out.append("    <InitialUnknowns>")
    out += [f'      <Unknown index="{i}"/>' for i in initial_unknowns]
    out.append("    </InitialUnknowns>")
    out.append("  </ModelStructure>")
    out.append("</fmiModelDescription>")
    return "\n".join(out) + "\n", scalars


def fmi3_description(model: dict, token: str) -> tuple[str, list[tuple]]:
    """FMI 3.0 modelDescription; returns the XML and the variable table (vr, var)."""
    table = [(vr, v) for vr, v in enumerate(model["variables"], start=1)]
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           '<fmiModelDescription fmiVersion="3.0"'
           f' modelName="{model["model_name"]}" instantiationToken="{token}"'
           f' description={quoteattr(model["description"])}'
           ' generationTool="gfins_fmi fmugen" variableNamingConvention="structured">',
           f'  <CoSimulation modelIdentifier="{model["model_identifier"]}"'
           ' canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true"'
           ' canSerializeFMUState="true" providesIntermediateUpdate="false"'
           ' hasEventMode="false" canReturnEarlyAfterIntermediateUpdate="false"/>',
           _unit_definitions(model["variables"], extra=("s",)),  # "s": the unit of time
           _log_categories(), _default_experiment(model),
           "  <ModelVariables>",
           '    <Float64 name="time" valueReference="0" causality="independent"'
           ' variability="continuous" unit="s" description="Simulation time"/>']
    outputs = []
    for vr, v in table:
        starts = _starts(v)
        attrs = f'name="{v["name"]}" valueReference="{vr}" description={quoteattr(v["description"])}'
        attrs += _common_attrs(v)
        if v.get("unit"):
            attrs += f' unit="{v["unit"]}"'
        if starts:
            attrs += f' start="{" ".join(_fmt(s, v["type"]) for s in starts)}"'
        if v["shape"]:
            out.append(f'    <{v["type"]} {attrs}>')
            out += [f'      <Dimension start="{n}"/>' for n in v["shape"]]
            out.append(f'    </{v["type"]}>')
        else:
            out.append(f'    <{v["type"]} {attrs}/>')
        if v["causality"] == "output":
            outputs.append(vr)
    out.append("  </ModelVariables>")
    out.append("  <ModelStructure>")
    out += [f'    <Output valueReference="{vr}"/>' for vr in outputs]
    out += [f'    <InitialUnknown valueReference="{vr}"/>' for vr in outputs]
    out.append("  </ModelStructure>")
    out.append("</fmiModelDescription>")
    return "\n".join(out) + "\n", table


def c_table(model: dict, token: str, scalars: list[tuple], table3: list[tuple]) -> str:
    """C header with the identifier, token, start values and the two VR tables."""
    lines = ["/* Generated by fmu/tools/fmugen.py from model_spec.py — do not edit. */",
             "#ifndef MODEL_VARS_H", "#define MODEL_VARS_H", "",
             "#include <math.h>", "#include <stddef.h>", '#include "fmu_model.h"',
             '#include "model.h"', "",
             f'#define MODEL_IDENTIFIER_STRING "{model["model_identifier"]}"',
             f'#define INSTANTIATION_TOKEN "{token}"', ""]

    def row(vr, v, offset_expr, count, name):
        return (f'    {{{vr}u, {TYPE_C[v["type"]]}, {CAUSALITY_C[v["causality"]]}, '
                f'{VARIABILITY_C[v["variability"]]}, {offset_expr}, {count}u, "{name}"}},')

    lines.append("/* FMI 2.0: one scalar per value reference (VR 1 is the first row). */")
    lines.append("static const FmuVariable kFmi2Variables[] = {")
    for vr, v, e in scalars:
        ctype = "double" if v["type"] == "Float64" else "int32_t"
        off = f'offsetof(ModelData, {v["field"]}) + {e}u * sizeof({ctype})'
        name = f'{v["name"]}[{e + 1}]' if v["shape"] else v["name"]
        lines.append(row(vr, v, off, 1, name))
    lines.append("};")
    lines.append("")
    lines.append("/* FMI 3.0: one (array) variable per value reference; VR 0 is time. */")
    lines.append("static const FmuVariable kFmi3Variables[] = {")
    for vr, v in table3:
        lines.append(row(vr, v, f'offsetof(ModelData, {v["field"]})', _count(v), v["name"]))
    lines.append("};")
    lines.append("")
    lines.append("static inline void model_set_start_values(ModelData *d)")
    lines.append("{")
    for v in model["variables"]:
        for e, s in enumerate(_starts(v)):
            idx = f"[{e}]" if v["shape"] else ""
            lit = _fmt(s, v["type"])
            lit = "NAN" if lit == "NaN" else lit          # C spelling (math.h)
            lines.append(f'    d->{v["field"]}{idx} = {lit};')
    lines.append("}")
    lines.append("")
    lines.append("#endif /* MODEL_VARS_H */")
    return "\n".join(lines) + "\n"


def extra_header(model: dict) -> str:
    """C header with the spec's ``c_extra`` text (empty without one), for model.c."""
    return "\n".join(["/* Generated by fmu/tools/fmugen.py from model_spec.py — do not edit. */",
                      "#ifndef MODEL_EXTRA_H", "#define MODEL_EXTRA_H", "",
                      "#include <stddef.h>", '#include "model.h"', "",
                      model.get("c_extra", "").rstrip("\n"), "", "#endif /* MODEL_EXTRA_H */", ""])


def main(argv: list[str]) -> int:
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    spec_path, outdir = pathlib.Path(argv[1]), pathlib.Path(argv[2])
    model = runpy.run_path(str(spec_path))["MODEL"]
    h = hashlib.sha256(spec_path.read_bytes())
    for extra in sorted(argv[3:]):
        h.update(pathlib.Path(extra).read_bytes())
    digest = h.hexdigest()
    token = "{%s-%s-%s-%s-%s}" % (digest[:8], digest[8:12], digest[12:16], digest[16:20], digest[20:32])
    xml2, scalars = fmi2_description(model, token)
    xml3, table3 = fmi3_description(model, token)
    for sub, text in (("fmi2", xml2), ("fmi3", xml3)):
        (outdir / sub).mkdir(parents=True, exist_ok=True)
        (outdir / sub / "modelDescription.xml").write_text(text, encoding="utf-8")
    (outdir / "model_vars.h").write_text(c_table(model, token, scalars, table3), encoding="utf-8")
    (outdir / "model_extra.h").write_text(extra_header(model), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
