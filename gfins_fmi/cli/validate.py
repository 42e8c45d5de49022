"""``gfins validate`` and ``gfins info``: the shipped FMUs checked by fmpy, and where they
are."""
from __future__ import annotations

from gfins_fmi._version import __version__
from gfins_fmi.fmi.paths import MODELS, fmu_path, validate

__all__ = ["run", "info"]


def run(args) -> int:
    """``gfins validate``: fmpy's validation of every shipped FMU."""
    bad = 0
    for model in MODELS:
        for version in (2, 3):
            path = fmu_path(model, version)
            problems = validate(path)
            bad += len(problems)
            print(f"{path}: {len(problems)} problems")
            for p in problems:
                print(f"    {p}")
    return 1 if bad else 0


def info(args) -> int:
    """``gfins info``: the version and the paths of the shipped FMUs."""
    print(f"gfins_fmi {__version__}")
    for model in MODELS:
        for version in (2, 3):
            print(f"  FMU {model} (FMI {version}.0): {fmu_path(model, version)}")
    return 0
