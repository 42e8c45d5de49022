"""Warnings are failures in the test suite (pyproject.toml's pytest ``filterwarnings``):
the setting is there, it is in force in this run, and every place where a test silences
a warning says why.

Why: a slip that makes a smoothed variance negative showed up only as "invalid value in
sqrt" warnings in a passing run (issue 25); as an error it fails the test that computes
the square root.
"""
from __future__ import annotations

import re
import tomllib
import warnings

import numpy as np
import pytest

from support.paths import ROOT


def test_pyproject_turns_warnings_into_errors():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    filters = cfg.get("filterwarnings", [])
    # the first filter is the default for every warning; later entries could only narrow
    # it, and none is wanted (an expected warning is asserted where it happens)
    assert filters == ["error"], filters


def test_a_numpy_floating_point_warning_fails_a_test():
    with pytest.raises(RuntimeWarning, match="invalid value encountered in sqrt"):
        np.sqrt(np.array([-1.0]))
    with pytest.raises(RuntimeWarning, match="divide by zero"):
        np.float64(1.0) / np.array([0.0])
    with pytest.raises(DeprecationWarning):
        warnings.warn("old", DeprecationWarning)


# ways a test can silence a warning instead of asserting it
_SILENCE = re.compile(r"np\.errstate\(.*ignore|warnings\.(simplefilter|filterwarnings)\(\s*['\"]ignore"
                      r"|pytest\.mark\.filterwarnings|suppress_warnings")


def test_every_silenced_warning_in_the_tests_says_why():
    """Within three lines before a silencing statement (or on its line) a comment or the
    enclosing docstring's last lines say why the warning is expected there."""
    missing = []
    for path in sorted((ROOT / "tests").rglob("*.py")):
        if path.name == "test_warnings.py":
            continue
        lines = path.read_text().splitlines()
        for i, line in enumerate(lines):
            if not _SILENCE.search(line):
                continue
            window = lines[max(0, i - 3):i + 1]
            if not any("#" in w or '"""' in w for w in window):
                missing.append(f"{path.relative_to(ROOT)}:{i + 1}: {line.strip()}")
    assert not missing, "warnings silenced without a reason:\n" + "\n".join(missing)
