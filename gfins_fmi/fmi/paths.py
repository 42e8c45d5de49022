"""The FMUs shipped with gfins_fmi: where they are, how to check them, how to run them.

Every FMU is built from the same C core as the Python API, for FMI 2.0 and FMI 3.0
co-simulation, and installed inside the package (``gfins_fmi/fmus/fmi<N>/``).

Sampling convention of every navigation FMU: ``doStep(t, h)`` processes the input
sample set for time ``t``; the outputs read after the step describe time ``t``. A
master that records outputs after each step (fmpy's ``simulate_fmu`` does) therefore
shows the solution of sample k in its row k + 1.
"""
from __future__ import annotations

import importlib.resources
import pathlib

from gfins_fmi._lib import GfinsError

__all__ = ["MODELS", "FmuRunError", "fmu_path", "validate", "fmu_variables"]

#: model name -> model identifier of the FMUs shipped
MODELS = {"accel9": "gfins_accel9", "sins": "gfins_sins", "gfnav_cube6": "gfins_gfnav_cube6",
          "gfnav_qin9": "gfins_gfnav_qin9", "gfnav_12": "gfins_gfnav_12",
          "vehicle": "gfins_vehicle", "ins_gnss": "gfins_ins_gnss",
          "transfer_align": "gfins_transfer_align"}


class FmuRunError(GfinsError):
    """An FMU call failed; ``messages`` holds what the FMU logged, ``partial`` the
    outputs of the steps that completed."""

    def __init__(self, message: str, messages: list[str], partial=None):
        super().__init__(message)
        self.messages = messages
        self.partial = partial


def fmu_path(model: str = "accel9", fmi_version: int = 2) -> pathlib.Path:
    """Path of a shipped FMU.

    Parameters
    ----------
    model : str
        One of :data:`MODELS` (``"accel9"``: the 9-accelerometer solver; ``"sins"``:
        the strapdown navigator; ``"ins_gnss"``: the integrated navigator, EKF/UKF).
    fmi_version : {2, 3}
        FMI 2.0 (scalar variables, structured names ``A[1]`` ...) or FMI 3.0 (arrays).
    """
    if model not in MODELS:
        raise ValueError(f"unknown FMU model {model!r}; choose one of {sorted(MODELS)}")
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3; got {fmi_version!r}")
    fmi_version = int(fmi_version)
    res = importlib.resources.files("gfins_fmi") / "fmus" / f"fmi{fmi_version}" / f"{MODELS[model]}.fmu"
    path = pathlib.Path(str(res))
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: the FMUs are built by 'pip install .'")
    return path


def validate(path: str | pathlib.Path) -> list[str]:
    """Problems fmpy finds in an FMU (an empty list means it is valid)."""
    from fmpy.validation import validate_fmu   # lazy: fmpy only where an FMU is opened
    return validate_fmu(str(path))


def fmu_variables(model: str, fmi_version: int) -> dict:
    """The model variables of a shipped FMU by name (fmpy's model description)."""
    from fmpy import read_model_description   # lazy: fmpy only where an FMU is opened
    md = read_model_description(str(fmu_path(model, fmi_version)))
    return {v.name: v for v in md.modelVariables}
