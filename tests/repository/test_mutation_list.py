"""The mutation run's lists still fit the sources (mutation/README.md).

The C mutants (mutation/c_mutants.toml) name a line of the source by its exact text;
when the sources change, a mutant can silently stop applying. This runs in the default
suite (it reads text only, no build): every mutant's original text occurs exactly once
in its file, and the Python mutation configuration names modules and tests that exist.
"""
from __future__ import annotations

import importlib.util
import sys

from support.paths import ROOT


def _run_c():
    return _load("mutation_run_c", "run_c.py")


def _load(name, file):
    spec = importlib.util.spec_from_file_location(name, ROOT / "mutation" / file)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod          # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


def test_every_c_mutant_applies_exactly_once():
    run_c = _run_c()
    mutants = run_c.load_mutants()
    assert len(mutants) >= 40, "the C mutant list is short of the 40 the run promises"
    problems = run_c.check_list(mutants)
    assert not problems, ("C mutants that no longer fit the sources (update "
                          "mutation/c_mutants.toml):\n" + "\n".join(problems))
    # the list covers the core: at least one mutant in each module named in the README
    files = {m.file for m in mutants}
    for name in ("base/gf_math.h", "nav/gf_earth.c", "nav/gf_sins.c", "est/gf_kalman.c",
                 "gyrofree/gf_array.c", "gyrofree/gf9.c", "gyrofree/gf_gfins.c",
                 "gyrofree/gf_gfnav.c", "nav/gf_imu_error.c", "est/gf_ins_state.c",
                 "est/gf_ins_propagate.c", "est/gf_ins_update.c", "est/gf_ins_step.c",
                 "sim/gf_vehicle.c", "sim/gf_noise.c", "nav/gf_biquad.c", "sim/gf_rot.c",
                 "est/gf_syscal.c"):
        assert f"csrc/{name}" in files, f"no mutant in csrc/{name}"


def test_apply_refuses_ambiguous_and_missing_lines():
    run_c = _run_c()
    m = run_c.Mutant(id="x", file="f.c", original="a = 1;", replacement="a = 2;", why="")
    assert run_c.apply("b;\na = 1;\n", m) == "b;\na = 2;\n"
    for text in ("a = 1;\na = 1;\n", "b;\n"):   # twice, absent
        try:
            run_c.apply(text, m)
        except ValueError as exc:
            assert "exactly once" in str(exc)
        else:
            raise AssertionError(f"apply accepted {text!r}")


def test_python_mutation_config_names_existing_files():
    run_py = _load("mutation_run_py", "run_py.py")
    _, targets = run_py.targets()   # exits naming a function that is gone
    assert targets, "no targets for the Python mutation run"
    names = {t["name"] for t in targets}
    # issue 25: estimation/, calibration/ and io/ are in the run, each with its own tests
    for folder in ("gfins_fmi/estimation/", "gfins_fmi/calibration/", "gfins_fmi/io/"):
        assert any(t["module"].startswith(folder) for t in targets), f"no target in {folder}"
    for t in targets:
        assert (ROOT / t["module"]).is_file(), f"target {t['name']}: no module {t['module']}"
        assert t["ranges"], f"target {t['name']}: no functions selected"
        words = t["tests"].split()
        assert words, f"target {t['name']}: no tests"
        for word in words:
            path = word.split("::")[0]
            assert (ROOT / path).exists(), f"target {t['name']} runs a missing {path}"
            # a module's mutants are judged by the tests of its own domain folder
            domain = t["module"].split("/")[1].removesuffix(".py").lstrip("_")
            assert path.startswith(("tests/" + domain, "tests/lib")), (t["name"], path)
    assert len(names) == len(targets)
