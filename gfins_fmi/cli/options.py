"""The argparse option types of every ``gfins`` command, one family: a value carries its
unit and bounds, and a bad one is refused at parse time in the option's terms (the
bounds and messages of :func:`gfins_fmi._lib.as_scalar`)."""
from __future__ import annotations

import argparse
import math

import dataclasses

from gfins_fmi._lib import as_scalar
from gfins_fmi.calibration.syscal_filter import Prior

__all__ = ["real", "count", "vector", "prior_setting", "GRADES"]

#: ``--grade``: the names of the IMU noise models of gfins_fmi.sim.scenarios.GRADES
GRADES = ("consumer", "tactical", "navigation")


def real(unit: str, **bounds):
    """A finite number in ``unit`` within ``bounds`` (``above``, ``at_least``, ``below``,
    ``at_most``, as :func:`gfins_fmi._lib.as_scalar`)."""
    def parse(text: str) -> float:
        try:
            x = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a number in {unit}; got {text!r}") from None
        try:
            return as_scalar("value", x, unit, **bounds)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc).removeprefix("value ")) from None
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
