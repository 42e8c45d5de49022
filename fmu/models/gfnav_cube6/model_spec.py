"""Gyro-free navigator FMU, layout cube6: the spec is built by fmu/models/gfnav/spec.py."""
import pathlib
import runpy

MODEL = runpy.run_path(str(pathlib.Path(__file__).resolve().parent.parent / "gfnav" / "spec.py"))["make"]("cube6", 6)
