"""The argparse option types of every ``gfins`` command, one family: a value carries its
unit and bounds, and a bad one is refused at parse time in the option's terms (the
bounds and messages of :func:`gfins_fmi._lib.as_scalar`)."""
from __future__ import annotations

import argparse
import math

from gfins_fmi._lib import as_scalar
from gfins_fmi.nav.imu_errors import ImuNoise
from gfins_fmi.sim.scenarios import CONSUMER, NAVIGATION, TACTICAL

__all__ = ["real", "count", "vector", "GRADES", "imu_noise"]

#: ``--grade``: the IMU noise models of gfins_fmi.sim.scenarios by name
GRADES = {"consumer": CONSUMER, "tactical": TACTICAL, "navigation": NAVIGATION}


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


def imu_noise(grade: str, noise=None) -> ImuNoise:
    """The IMU noise model of ``--grade``, or of ``--noise`` ARW,VRW,GB,AB,TAU
    (deg/sqrt(h), ug/sqrt(Hz), deg/h, ug, s) when given."""
    if noise:
        arw, vrw, gb, ab, tau = noise
        return ImuNoise(gyro_arw_deg_sqrt_h=arw, accel_vrw_ug_sqrt_hz=vrw, gyro_bias_instability_deg_h=gb,
                        accel_bias_instability_ug=ab, gyro_correlation_time_s=tau,
                        accel_correlation_time_s=tau)
    return GRADES[grade]
