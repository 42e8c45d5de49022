#!/usr/bin/env python3
"""Mutation run over the C core: applies each single-line mutant of
mutation/c_mutants.toml to a private copy of the tree, rebuilds the C tests
incrementally and runs them with ctest.

A mutant of a Python file (``file`` under gfins_fmi/) is not built: it runs only in the
second stage below, with its own ``tests``.

Outcome of a mutant:
  killed      a C test failed (the names of the failing tests are recorded)
  compiler    the build failed (warnings are errors): killed by the compiler
  timeout     the tests did not finish within the per-mutant limit (counted as killed)
  survived    every C test passed: either an equivalent mutant or a test gap

Usage (from the repository root; needs cmake and ninja, e.g. from the test extra):
    nice -n 5 python mutation/run_c.py                   # every mutant
    python mutation/run_c.py --only sins-coriolis-sign kalman-x-sign
    python mutation/run_c.py --check                     # only check that the list applies

The working copy is never modified: the tree is copied (git ls-files) into --work
(default: a folder under the system temporary directory) once and built there
(Release, C tests only: GFINS_BUILD_PYTHON=OFF, GFINS_BUILD_FMUS=OFF; the FMU C tests
are included, they only need this Python for fmugen.py). Results go to --json and a
Markdown table to --markdown.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Mutant:
    id: str
    file: str
    original: str
    replacement: str
    why: str
    tests: str = ""     # pytest arguments of its Python stage (Python mutants: required)


def load_mutants(path: Path = HERE / "c_mutants.toml") -> list[Mutant]:
    """The mutant list, in file order."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    out = [Mutant(**m) for m in data["mutant"]]
    ids = [m.id for m in out]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise ValueError(f"{path}: duplicate mutant ids {dup}")
    return out


def apply(text: str, m: Mutant) -> str:
    """`text` with the mutant applied; ValueError unless `original` occurs exactly once
    (and on one line) and the replacement changes something."""
    n = text.count(m.original)
    if n != 1:
        raise ValueError(f"mutant {m.id}: '{m.original}' occurs {n} times in {m.file} "
                         "(must be exactly once: update the list)")
    if "\n" in m.original or "\n" in m.replacement:
        raise ValueError(f"mutant {m.id}: single-line mutants only")
    if m.original == m.replacement:
        raise ValueError(f"mutant {m.id}: the replacement equals the original")
    return text.replace(m.original, m.replacement, 1)


def check_list(mutants: list[Mutant], root: Path = ROOT) -> list[str]:
    """Problems with the list against the sources under `root` (empty: it applies)."""
    problems = []
    for m in mutants:
        p = root / m.file
        if not p.is_file():
            problems.append(f"mutant {m.id}: no file {m.file}")
            continue
        try:
            apply(p.read_text(), m)
        except ValueError as exc:
            problems.append(str(exc))
        if m.file.endswith(".py") and not m.tests:
            problems.append(f"mutant {m.id}: a Python mutant needs its tests (pytest arguments)")
        for word in m.tests.split():
            if word.startswith("tests/") and not (root / word.split("::")[0]).is_file():
                problems.append(f"mutant {m.id}: no test file {word.split('::')[0]}")
    return problems


def _run(cmd, timeout, cwd=None):
    """(returncode or None on timeout, output, seconds); the command runs in its own
    process group, killed whole on a timeout or an interruption."""
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=timeout)
        return p.returncode, out, time.monotonic() - t0
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        return None, out, time.monotonic() - t0
    except BaseException:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        raise


def copy_tree(dst: Path) -> None:
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout.split("\n")
    for f in files:
        # bench/ and examples/ too: some tests load a study or an example from there
        if not f or f.startswith(("mutation/", "docs/")):
            continue
        src = ROOT / f
        if not src.is_file():
            continue
        d = dst / f
        if d.is_file() and d.read_bytes() == src.read_bytes():
            continue
        d.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, d)


def failed_tests(log: str) -> list[str]:
    m = re.search(r"The following tests FAILED:\n(.*?)(?:\n\n|\Z)", log, re.S)
    if not m:
        return []
    return re.findall(r"- (\S+) \(", m.group(1))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mutants", type=Path, default=HERE / "c_mutants.toml")
    ap.add_argument("--only", nargs="*", help="mutant ids to run (default: all)")
    ap.add_argument("--work", type=Path, default=Path(tempfile.gettempdir()) / "gfins_mutation_c")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=0.0,
                    help="ctest limit per mutant, s (default: 4x the unmutated run, >= 60)")
    ap.add_argument("--budget", type=float, default=0.0,
                    help="stop starting new mutants after this many seconds (0: no limit)")
    ap.add_argument("--json", type=Path, default=HERE / "results_c.json")
    ap.add_argument("--markdown", type=Path, default=HERE / "results_c.md")
    ap.add_argument("--check", action="store_true", help="only check that the list applies")
    ap.add_argument("--pytest", default="",
                    help="second stage for a mutant the C tests let through: build the cffi "
                         "module from the mutated copy and run these pytest arguments "
                         "(e.g. 'tests/test_estimation.py -k ekf') against it")
    ap.add_argument("--reuse", action="store_true",
                    help="reuse the copy and build in --work from an earlier run (the copy is "
                         "refreshed file by file; only what changed is rebuilt)")
    args = ap.parse_args(argv)

    mutants = load_mutants(args.mutants)
    problems = check_list(mutants)
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 2
    if args.check:
        print(f"{len(mutants)} mutants apply cleanly to {ROOT}")
        return 0
    if args.only:
        unknown = set(args.only) - {m.id for m in mutants}
        if unknown:
            print(f"unknown mutant ids: {sorted(unknown)}", file=sys.stderr)
            return 2
        mutants = [m for m in mutants if m.id in args.only]
    # a header mutant rebuilds every object: those run last, within what budget is left
    mutants.sort(key=lambda m: m.file.endswith(".h"))
    cmake, ctest = shutil.which("cmake"), shutil.which("ctest")
    if not cmake or not ctest:
        print("cmake/ctest not on PATH (pip install '.[test]')", file=sys.stderr)
        return 2

    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # revert the file (finally) on kill
    src, bld = args.work / "src", args.work / "build"
    if src.exists() and not args.reuse:
        shutil.rmtree(src)
    copy_tree(src)
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    # -O1: the tests' results do not depend on it (-ffp-contract=off, no fast-math; the
    # portable and vector Kalman forms must agree bit for bit at any level) and each
    # rebuild takes a fraction of -O3's time; -O1 raises a false maybe-uninitialized warning
    # in gf_gfins.c (not at -O3), so that one warning is not an error here
    rc, log, _ = _run([cmake, "-S", str(src), "-B", str(bld), *gen, "-DCMAKE_BUILD_TYPE=Release",
                       "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG -Wno-maybe-uninitialized",
                       "-DGFINS_BUILD_TESTS=ON", "-DGFINS_BUILD_PYTHON=OFF",
                       "-DGFINS_BUILD_FMUS=OFF", f"-DPython_EXECUTABLE={sys.executable}"], 600)
    if rc != 0:
        print(log, file=sys.stderr)
        return 2
    build = [cmake, "--build", str(bld), "-j", str(args.jobs)]
    test = [ctest, "--test-dir", str(bld), "-j", str(args.jobs), "--stop-on-failure"]
    rc, log, t_build = _run(build, 1800)
    if rc != 0:
        print("the unmutated tree does not build:\n" + log[-4000:], file=sys.stderr)
        return 2
    rc, log, t_test = _run(test, 1800)
    if rc != 0:
        print("the unmutated tree fails its C tests:\n" + log[-4000:], file=sys.stderr)
        return 2
    py = None
    baseline_ok = {}          # Python-stage test selections that pass on the unmutated copy

    def python_tests(m):
        """The Python stage of mutant m (its own tests, else --pytest; "" for none), checked
        once per selection on the unmutated copy."""
        sel = m.tests or args.pytest
        if sel and sel not in baseline_ok:
            outcome, why, t_py = _python_stage(py, sel, 600.0)
            if outcome != "survived":
                raise SystemExit(f"the Python stage fails on the unmutated copy: {sel}: {why}")
            print(f"Python stage: {sel} ({t_py:.0f} s unmutated)", flush=True)
            baseline_ok[sel] = t_py
        return sel

    if args.pytest or any(m.tests for m in mutants):
        py = _python_stage_setup(args, cmake, gen, src)
        if py is None:
            return 2
    limit = args.timeout or max(60.0, 4.0 * t_test)
    print(f"baseline: build {t_build:.0f} s, ctest {t_test:.1f} s; limit per mutant {limit:.0f} s",
          flush=True)

    results = []
    t_start = time.monotonic()
    for i, m in enumerate(mutants):
        if args.budget and time.monotonic() - t_start > args.budget:
            print(f"budget reached: {len(mutants) - i} mutants not run", flush=True)
            break
        sel = python_tests(m) if py is not None else ""
        path = src / m.file
        original = path.read_text()
        path.write_text(apply(original, m))
        try:
            if m.file.endswith(".py"):           # nothing to build: the Python stage only
                tb = 0.0
                outcome, tests, tt = _python_stage(py, sel, limit)
            else:
                rc, log, tb = _run(build, 900)
                if rc != 0:
                    outcome, tests, tt = "compiler", [], 0.0
                    err = [ln for ln in log.splitlines() if "error" in ln][:1]
                    tests = [e.strip()[:160] for e in err]
                else:
                    rc, log, tt = _run([*test, "--timeout", str(int(limit))], limit + 60)
                    if rc is None or "Timeout" in log:
                        outcome, tests = "timeout", failed_tests(log)
                    elif rc != 0:
                        outcome, tests = "killed", failed_tests(log)
                    else:
                        outcome, tests = "survived", []
                        if sel:
                            outcome, tests, t_py = _python_stage(py, sel, limit)
                            tt += t_py
        finally:
            path.write_text(original)
        r = dict(id=m.id, file=m.file, outcome=outcome, by=tests, build_s=round(tb, 1),
                 test_s=round(tt, 1), why=m.why)
        results.append(r)
        print(f"[{i + 1}/{len(mutants)}] {m.id:32s} {outcome:9s} {' '.join(tests)[:80]}",
              flush=True)
    # leave the copy built as the unmutated tree
    _run(build, 1800)

    if args.only and args.json.exists():
        # a partial run (survivors after a new test, mutants the budget left out): merged
        # into the last full run's results, mutant by mutant
        new = {r["id"]: r for r in results}
        old = {r["id"]: r for r in json.loads(args.json.read_text())["results"]}
        old.update(new)
        order = [m.id for m in load_mutants(args.mutants)]
        results = [old[i] for i in order if i in old]
    write_results(results, args, len(load_mutants(args.mutants)))
    return 0


def _python_stage_setup(args, cmake, gen, src):
    """A second build of the copy with the cffi module and the FMUs; the package is imported
    from the copy (python -S: without the site hooks, so an editable install of the
    checkout cannot redirect the import; site-packages on PYTHONPATH for numpy & co)."""
    import sysconfig
    pybld = args.work / "pybuild"
    # the cffi module and the FMUs (tests/fmi runs them: a mutant of an FMU model is
    # judged by the Python FMU tests too)
    rc, log, _ = _run([cmake, "-S", str(src), "-B", str(pybld), *gen, "-DCMAKE_BUILD_TYPE=Release",
                       "-DCMAKE_C_FLAGS_RELEASE=-O1 -DNDEBUG -Wno-maybe-uninitialized",
                       "-DGFINS_BUILD_TESTS=OFF", "-DGFINS_BUILD_PYTHON=ON",
                       "-DGFINS_BUILD_FMUS=ON", f"-DPython_EXECUTABLE={sys.executable}"], 600)
    build = [cmake, "--build", str(pybld), "-j", str(args.jobs)]
    if rc == 0:
        rc, log, _ = _run(build, 1800)
    if rc != 0:
        print("the cffi module does not build in the copy:\n" + log[-4000:], file=sys.stderr)
        return None
    so = sorted(pybld.glob("_core*.so"))[0]
    for target, name in ((so, so.name), (pybld / "fmus", "fmus")):
        link = src / "gfins_fmi" / name
        if link.is_symlink() or link.exists():
            link.unlink()
        link.symlink_to(target)
    pkg = args.work / "pypkg"
    pkg.mkdir(exist_ok=True)
    if not (pkg / "gfins_fmi").exists():
        (pkg / "gfins_fmi").symlink_to(src / "gfins_fmi")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(pkg), sysconfig.get_paths()["purelib"],
                                                        sysconfig.get_paths()["platlib"]]))
    return dict(build=build, env=env, cwd=src)


def _python_stage(py, pytest_args, limit):
    rc, log, tb = _run(py["build"], 900)
    if rc != 0:
        return "compiler", [], tb
    # one process (-o addopts= drops pyproject's -n 2: under xdist -x ends with exit code
    # 2, "interrupted", like a crash), stopping at the first failure
    cmd = [sys.executable, "-S", "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
           "-o", "addopts=", *pytest_args.split()]
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, cwd=py["cwd"], env=py["env"], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, start_new_session=True)
    try:
        out, _ = p.communicate(timeout=10 * limit)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        return "timeout", ["python"], tb + time.monotonic() - t0
    dt = tb + time.monotonic() - t0
    if p.returncode == 0:
        return "survived", [], dt
    if p.returncode in (2, 3, 4, 5):   # interrupted, internal error, usage, no tests
        raise RuntimeError("the Python stage could not run its tests:\n" + out[-3000:])
    failed = re.findall(r"^FAILED (\S+)", out, re.M)   # failures, or a crash of the interpreter
    return "killed", ["py:" + (failed[0] if failed else f"pytest exit {p.returncode}")], dt


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                              capture_output=True, text=True).stdout.strip()
    except OSError:
        return "?"


def write_results(results, args, n_listed) -> None:
    counts = {k: sum(r["outcome"] == k for r in results)
              for k in ("killed", "compiler", "timeout", "survived")}
    counts["killed_by_python"] = sum(r["outcome"] == "killed" and any(b.startswith("py:") for b in r["by"])
                                     for r in results)
    n = len(results)
    dead = n - counts["survived"]
    meta = dict(date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), commit=_commit(),
                machine=f"{platform.machine()} {platform.system()}, {os.cpu_count()} cores",
                listed=n_listed, run=n, **counts,
                kill_rate=round(dead / n, 4) if n else None)
    args.json.write_text(json.dumps(dict(meta=meta, results=results), indent=1) + "\n")
    lines = [f"# C-core mutation run ({meta['date']}, commit {meta['commit']}, {meta['machine']})",
             "",
             f"{n} of {n_listed} mutants run: {counts['killed'] - counts['killed_by_python']} "
             f"killed by the C tests, {counts['killed_by_python']} by the Python stage, "
             f"{counts['compiler']} by the compiler, {counts['timeout']} by a timeout, "
             f"{counts['survived']} survived; kill rate {dead}/{n}"
             + (f" = {100 * dead / n:.1f} %" if n else ""),
             "", "| mutant | file | outcome | killed by | rationale |", "|---|---|---|---|---|"]
    for r in results:
        by = ", ".join(r["by"]).replace("|", "/")
        lines.append(f"| {r['id']} | {r['file']} | {r['outcome']} | {by} | {r['why']} |")
    args.markdown.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
