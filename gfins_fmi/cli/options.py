"""The argparse option types of every ``gfins`` command, one family: a value carries its
unit and bounds, and a bad one is refused at parse time in the option's terms (the
bounds and messages of :func:`gfins_fmi._lib.as_scalar`)."""
from __future__ import annotations

import argparse
import dataclasses
import math
import re

from gfins_fmi._lib import as_scalar
from gfins_fmi.calibration.syscal_filter import Prior

__all__ = ["real", "count", "vector", "prior_setting", "noise_values", "NOISE_UNITS", "GRADES"]

#: ``--grade``: the names of the IMU noise models of gfins_fmi.sim.scenarios.GRADES
GRADES = ("consumer", "tactical", "navigation")


def real(unit: str, **bounds):
    """A finite number in ``unit`` within ``bounds`` (``above``, ``at_least``, ``below``,
    ``at_most``, as :func:`gfins_fmi._lib.as_scalar`). Every type of this family carries
    its unit as ``.unit`` (a vector: what it holds, with units)."""
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number in {unit}; got {text!r}") from None
        try:
            return as_scalar("value", x, unit, **bounds)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("value ")) from None
    parse.unit = unit      # named in a run's effective configuration
    return parse


def count(at_least: int):
    """An integer >= ``at_least``."""
    def parse(text: str) -> int:
        try:
            k = int(text)
        except ValueError:
            k = None
        if k is None or k < at_least:
            raise argparse.ArgumentTypeError(f"must be an integer >= {at_least}; got {text!r}")
        return k
    parse.unit = "count"
    return parse


def vector(n: int, what: str):
    """``n`` comma-separated finite numbers; ``what`` names them with their units."""
    def parse(text: str) -> list[float]:
        try:
            v = [float(x) for x in text.split(",")]
        except ValueError:
            v = []
        if len(v) != n or not all(math.isfinite(x) for x in v):
            raise argparse.ArgumentTypeError(f"expected {n} comma-separated finite numbers ({what}); "
                                             f"got {text!r}")
        return v
    parse.unit = what
    return parse



def prior_setting(text: str):
    """``--prior NAME=VALUE``: a prior 1-sigma (a
    :class:`~gfins_fmi.calibration.syscal_filter.Prior` field, in its unit), > 0
    (gravity_ug >= 0)."""
    names = [f.name for f in dataclasses.fields(Prior)]
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--prior takes NAME=VALUE with NAME one of {', '.join(names)}")
    k, v = text.split("=", 1)
    if k not in names:
        raise argparse.ArgumentTypeError(f"--prior: unknown {k!r}; one of {', '.join(names)}")
    val = real("its unit")(v)
    if not (val > 0 or (k == "gravity_ug" and val >= 0)):
        raise argparse.ArgumentTypeError(f"--prior {k} must be > 0; got {val}")
    return k, val


#: 1 ug in m/s^2 (gfins_fmi.estimation.config.UG; said here so that the parser stays light)
_UG_M_S2 = 9.80665e-6

#: ``--noise ARW,VRW,GB,AB,TAU``: each field's units (as typed, case and spaces ignored,
#: 'rt' or the root sign for 'sqrt', parentheses optional) and the factor to the unit
#: ImuNoise takes; the first of each is the unit of a bare number
NOISE_UNITS = (
    ("ARW", {"deg/sqrt(h)": 1.0, "deg/h/sqrt(hz)": 1.0 / 60.0, "rad/sqrt(s)": 60.0 * 180.0 / math.pi}),
    # ImuNoise's accelerometer density is ONE-sided (ug/sqrt(Hz)); the datasheet VRW (Allan,
    # m/s/sqrt(h)) N is the two-sided one: S = sqrt(2) N / 60 / ug
    ("VRW", {"ug/sqrt(hz)": 1.0, "mg/sqrt(hz)": 1000.0,
             "m/s/sqrt(h)": math.sqrt(2.0) / 60.0 / _UG_M_S2, "m/s/sqrt(s)": math.sqrt(2.0) / _UG_M_S2}),
    ("GB", {"deg/h": 1.0, "deg/s": 3600.0}),
    ("AB", {"ug": 1.0, "mg": 1000.0, "mgal": 1e-5 / _UG_M_S2, "m/s^2": 1.0 / _UG_M_S2}),
    ("TAU", {"s": 1.0, "h": 3600.0}),
)

_NUMBER_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _unit_key(unit: str) -> str:
    u = unit.lower().replace(" ", "").replace("\u221a", "sqrt").replace("\u00b5", "u").replace("\u03bc", "u")
    u = re.sub(r"sqrt\(?(h|hz|s)\)?", r"sqrt(\1)", re.sub(r"(?<!sq)rt\(?(h|hz|s)\)?", r"sqrt(\1)", u))
    return u.replace("m/s2", "m/s^2")


def noise_values(text: str) -> list[float]:
    """``--noise ARW,VRW,GB,AB,TAU``, each a number with an optional unit (NOISE_UNITS;
    a bare number is in the first unit of its field), converted to the units of
    :class:`~gfins_fmi.nav.imu_errors.ImuNoise`: deg/sqrt(h), ug/sqrt(Hz) one-sided, deg/h,
    ug, s. ``0.03m/s/sqrt(h)`` for the VRW is the datasheet's (Allan) figure: 72.1 ug/sqrt(Hz)
    one-sided."""
    parts = text.split(",")
    if len(parts) != len(NOISE_UNITS):
        raise argparse.ArgumentTypeError(f"expected 5 comma-separated values ARW,VRW,GB,AB,TAU; got {text!r}")
    out = []
    for part, (name, units) in zip(parts, NOISE_UNITS):
        m = _NUMBER_UNIT.match(part)
        if m is None:
            raise argparse.ArgumentTypeError(f"{name}: expected a number with an optional unit; got {part!r}")
        x, unit = float(m.group(1)), m.group(2)
        factor = units.get(_unit_key(unit), None) if unit else next(iter(units.values()))
        if factor is None:
            raise argparse.ArgumentTypeError(f"{name}: unknown unit {unit!r}; one of {', '.join(units)} "
                                             f"(a bare number is in {next(iter(units))})")
        if not (math.isfinite(x) and x >= 0) or (name == "TAU" and x == 0):
            raise argparse.ArgumentTypeError(f"{name} must be finite and {'> 0' if name == 'TAU' else '>= 0'}; "
                                             f"got {part!r}")
        out.append(x * factor)
    return out
