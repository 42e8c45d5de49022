"""A short, seeded, bounded run of every fuzz target of fuzz/ (fuzz/README.md): the
libFuzzer targets (built with clang under ASan + UBSan: C core entry points, each FMU's
state deserializer, setters and call sequences) and the atheris target of the record
readers. Each starts from its committed seed corpus, which holds the inputs of every
finding fixed so far (regressions), and runs a few hundred mutations with a fixed seed: a
crash, a sanitizer report, an oracle failure or a hang fails the test with the log. The
long runs (>= 10^6 executions per target) are documented in fuzz/README.md."""
from __future__ import annotations

import importlib.util
import os
import shutil
import sys

import pytest

from support.paths import ROOT

sys.path.insert(0, str(ROOT / "fuzz"))
import run as fuzz_run  # noqa: E402  (fuzz/run.py)

RUNS = 300   # mutations per target after the seed corpus: seconds in all
# the default run builds and runs the C-core targets, two FMU targets (the integrated
# navigator and a gyro-free one: every C module and the FMI glue) and the integrated
# navigator's crafted-state target (its oracle: refused, or finite outputs; its corpus
# replays the state it found, issue 21); GFINS_FUZZ_ALL=1 adds the other FMU targets
# (their build costs the test run ~25 s more on two cores)
ALL = bool(os.environ.get("GFINS_FUZZ_ALL"))
DEFAULT_C = ["fuzz_sins", "fuzz_accel", "fuzz_filters", "fuzz_rotation", "fuzz_ins_fb", "fuzz_text", "fuzz_fmu_ins_gnss",
             "fuzz_fmu_gfnav_cube6", "fuzz_fmu_state_ins_gnss"]


@pytest.fixture(scope="module")
def fuzz_build(tmp_path_factory):
    if not shutil.which("clang"):
        pytest.skip("clang is not installed (libFuzzer needs it): "
                    "apt-get install clang libclang-rt-14-dev")
    build_dir = tmp_path_factory.mktemp("fuzz-build")
    fuzz_run.build(build_dir, None if ALL else DEFAULT_C)
    return build_dir


@pytest.mark.parametrize("target", fuzz_run.C_TARGETS)
def test_libfuzzer_target_short_run(fuzz_build, target):
    if not (ALL or target in DEFAULT_C):
        pytest.skip("an FMU target outside the default set: GFINS_FUZZ_ALL=1 runs it")
    r = fuzz_run.run(target, fuzz_build, RUNS, None, 1, None)
    assert r["runs"] >= RUNS


@pytest.mark.parametrize("target", fuzz_run.PY_TARGETS)
def test_atheris_target_short_run(target, tmp_path):
    if importlib.util.find_spec("atheris") is None:
        pytest.skip("atheris is not installed (pip install atheris; wheels for CPython "
                    "<= 3.11 on Linux x86_64)")
    r = fuzz_run.run(target, tmp_path, RUNS, None, 1, None)
    assert r["runs"] >= RUNS
