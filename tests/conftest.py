"""The tests' set-up: one BLAS thread, the installed package (never the source folder),
and the shared fixtures. Shared helpers are in tests/support/ (``from support.truth import
...``): this folder is on sys.path as the folder of this conftest.py."""
from __future__ import annotations

import os
import pathlib
import sys

# One BLAS thread (before numpy loads OpenBLAS): the tests' matrices are small, and
# OpenBLAS's threads spin-wait for work — on a busy 2-core machine a scipy expm of a
# 16 x 16 matrix took minutes (threads spinning against each other and other jobs).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Tests exercise the installed package (with its compiled core and FMUs), never the
# source folder: `python -m pytest` from the root would otherwise import ./gfins_fmi.
sys.path[:] = [p for p in sys.path if pathlib.Path(p or ".").resolve() != ROOT]
# Imported once here, before any test captures output: an editable install rebuilds the
# core on first import and its build writes to the real stdout.
import gfins_fmi  # noqa: E402,F401


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)
