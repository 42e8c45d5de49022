"""Builds the C core and its C tests from the source tree with CMake and runs them with
ctest: once as in a release build (warnings are errors) and once under
AddressSanitizer + UndefinedBehaviorSanitizer (any report aborts the test binary)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

from support.paths import ROOT


def _cmake_build_and_test(build_dir, *defines: str) -> str:
    cmake = shutil.which("cmake")
    ctest = shutil.which("ctest")
    if not cmake or not ctest:
        pytest.fail("cmake/ctest not found on PATH: install the test extra, pip install '.[test]'")
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=1",
               UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
    steps = [
        [cmake, "-S", str(ROOT), "-B", str(build_dir), *gen, *defines,
         f"-DPython_EXECUTABLE={sys.executable}"],  # fmugen.py runs with this Python
        [cmake, "--build", str(build_dir), "-j", "2"],
        [ctest, "--test-dir", str(build_dir), "--output-on-failure", "-j", "2"],
    ]
    log = []
    for cmd in steps:
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
        log.append(f"$ {' '.join(cmd)}\n{proc.stdout}{proc.stderr}")
        if proc.returncode != 0:
            pytest.fail("C build/test step failed:\n" + "\n".join(log)[-6000:])
    return "\n".join(log)


def test_c_tests_release(tmp_path):
    out = _cmake_build_and_test(tmp_path / "release", "-DCMAKE_BUILD_TYPE=Release")
    assert "100% tests passed" in out
    assert "test_fmu_glue" in out, "the FMU glue C test was not built (Python interpreter not found?)"


def test_c_tests_under_asan_ubsan(tmp_path):
    out = _cmake_build_and_test(tmp_path / "sanitized", "-DCMAKE_BUILD_TYPE=Debug",
                                "-DGFINS_SANITIZE=ON")
    assert "100% tests passed" in out
