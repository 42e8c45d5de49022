#!/usr/bin/env python3
"""Python mutation run with cosmic-ray over the targets of mutation/cosmic-ray.toml: each
``[[gfins-mutation.target]]`` names a module, the functions (or ``Class.method``) of it to
mutate and the test command that judges them (the tests of the matching folder), and runs
as its own cosmic-ray session.

Usage (from the repository root, in the dev venv with the `mutation` extra):
    nice -n 5 python mutation/run_py.py                        # every target
    nice -n 5 python mutation/run_py.py --target io-rtklib     # some of them
    python mutation/run_py.py --rerun-survivors --target ...   # after adding tests
    python mutation/run_py.py --report-only                    # report the sessions
    nice -n 5 python mutation/run_py.py --sample 50 --seed 25 --target ...   # a sample

The run never edits the checkout: the tracked tree is copied into --work (default under
the system temporary directory) at the start, with the installed package's compiled parts
(the cffi module and the FMUs; so the checkout can be edited and rebuilt meanwhile), and the tests run with ``python -S`` and the copy
first on PYTHONPATH (so an editable install of the checkout cannot redirect the import);
cosmic-ray mutates the copy in place. Sessions (``<work>/<target>.sqlite``) persist for
--rerun-survivors and --report-only. Results: mutation/results_py.json (per target: the
counts and the survivors) and mutation/results_py.md.

The functions are turned into line ranges here (ast), so the selection follows the
sources as they change; cosmic-ray's own line filter takes those ranges.

--sample N runs a uniform random sample of N of a target's mutants (after the operator and
line filters; random.Random(seed) over the mutants in source order, so the same
sources and seed give the same sample); the others are marked skipped with the note "not in the sample"
and counted apart (``sampled_out``), so the report states the sample it rests on.
"""
from __future__ import annotations

import argparse
import ast
import json
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
CONFIG = HERE / "cosmic-ray.toml"


def function_lines(path: Path, names: list[str]) -> list[str]:
    """'first-last' line ranges of the bodies of the named top-level functions or classes
    of a module, or of ``Class.method``: from the first statement (the docstring) to the
    end, so the signature with its annotations (never evaluated under ``from __future__
    import annotations``: mutants there are equivalent) and the decorators are left out."""
    tree = ast.parse(path.read_text())
    found = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            found[node.name] = node
            if isinstance(node, ast.ClassDef):
                for sub in node.body:
                    if isinstance(sub, ast.FunctionDef):
                        found[f"{node.name}.{sub.name}"] = sub
    missing = [n for n in names if n not in found]
    if missing:
        raise SystemExit(f"{path}: no function {missing} (update {CONFIG.name})")
    ranges = []
    for n in names:
        node = found[n]
        ranges.append(f"{node.body[0].lineno}-{node.end_lineno}")
    return ranges


def targets() -> tuple[dict, list[dict]]:
    """(the cosmic-ray section, the targets with their line ranges)."""
    with open(CONFIG, "rb") as fh:
        cfg = tomllib.load(fh)
    out = []
    for t in cfg["gfins-mutation"]["target"]:
        out.append(dict(t, ranges=function_lines(ROOT / t["module"], t["functions"])))
    names = [t["name"] for t in out]
    if len(set(names)) != len(names):
        raise SystemExit(f"{CONFIG.name}: duplicate target names {names}")
    return cfg["cosmic-ray"], out


def copy_tree(dst: Path) -> Path:
    """The tracked tree in dst/src with the installed compiled parts linked in; returns
    the PYTHONPATH the tests run with."""
    src = dst / "src"
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout.split("\n")
    for f in files:
        if not f or f.startswith("mutation/") or not (ROOT / f).is_file():
            continue
        d = src / f
        if d.is_file() and d.read_bytes() == (ROOT / f).read_bytes():
            continue
        d.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, d)
    purelib, platlib = sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]
    installed = Path(platlib) / "gfins_fmi"
    built = sorted(installed.glob("_core*.so")) + [installed / "fmus"]
    if not built[0].name.startswith("_core") or not built[-1].is_dir():
        raise SystemExit(f"no compiled gfins_fmi in {installed}: pip install -e '.[test,mutation]'")
    # copied, not linked: a rebuild of the checkout during the run cannot change them
    for b in built:
        dest = src / "gfins_fmi" / b.name
        if dest.is_symlink() or dest.is_file():
            dest.unlink()
        elif dest.is_dir():
            shutil.rmtree(dest)
        if b.is_dir():
            shutil.copytree(b, dest)
        else:
            shutil.copy2(b, dest)
    # the package through a folder of its own: tests/conftest.py takes the tree's root off
    # sys.path (the tests exercise the installed package, never the source folder)
    pkg = dst / "pypkg"
    pkg.mkdir(exist_ok=True)
    if not (pkg / "gfins_fmi").is_symlink():
        (pkg / "gfins_fmi").symlink_to(src / "gfins_fmi")
    return os.pathsep.join([str(pkg), purelib, platlib])


def write_session_config(path: Path, cr: dict, t: dict, pythonpath: str) -> None:
    ops = cr["filters"]["operators-filter"]["exclude-operators"]
    # the tests of the copy, one process, stopping at the first failure
    command = (f"env PYTHONPATH={pythonpath} {sys.executable} -S -m pytest -x -q "
               f"-p no:cacheprovider -o addopts= {t['tests']}")
    text = [
        "[cosmic-ray]",
        f"module-path = {json.dumps(t['module'])}",
        f"timeout = {float(cr['timeout'])}",
        "excluded-modules = []",
        f"test-command = {json.dumps(command)}",
        "[cosmic-ray.distributor]",
        'name = "local"',
        "[cosmic-ray.filters.operators-filter]",
        "exclude-operators = [" + ", ".join(json.dumps(o) for o in ops) + "]",
        "[cosmic-ray.filters.line-filter.lines]",
        f"{json.dumps(t['module'])} = [" + ", ".join(json.dumps(r) for r in t["ranges"]) + "]",
    ]
    path.write_text("\n".join(text) + "\n")


SAMPLED_OUT = "not in the sample"


def sample_session(session: Path, n: int, seed: int) -> tuple[int, int]:
    """Keep a random sample of n of the session's pending mutants, mark the rest skipped
    (note SAMPLED_OUT); returns (kept, pending before)."""
    import random
    import sqlite3
    with sqlite3.connect(session) as db:
        # in source order (job ids are random): the same sources give the same sample
        pending = [r[0] for r in db.execute(
            "SELECT job_id FROM mutation_specs WHERE job_id NOT IN "
            "(SELECT job_id FROM work_results) ORDER BY module_path, start_pos_row, "
            "start_pos_col, operator_name, occurrence")]
        keep = set(random.Random(seed).sample(pending, min(n, len(pending))))
        db.executemany("INSERT INTO work_results (worker_outcome, output, test_outcome, diff, "
                       "job_id) VALUES ('SKIPPED', ?, NULL, NULL, ?)",
                       [(SAMPLED_OUT, j) for j in pending if j not in keep])
    return len(keep), len(pending)


def sh(*cmd: str, cwd: Path) -> None:
    print("$", " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=cwd, check=True)


def session_report(session: Path, src: Path, t: dict) -> dict:
    dump = subprocess.run(["cosmic-ray", "dump", str(session)], cwd=src, capture_output=True,
                          text=True, check=True).stdout
    rows = []
    for line in dump.splitlines():
        item, result = json.loads(line)
        m = item["mutations"][0]
        outcome = "pending" if result is None else (
            "sampled-out" if result.get("output") == SAMPLED_OUT else
            "skipped" if result["worker_outcome"] == "skipped" else
            result["test_outcome"] if result["worker_outcome"] == "normal" else
            result["worker_outcome"])
        rows.append(dict(job=item["job_id"], line=m["start_pos"][0], operator=m["operator_name"],
                         occurrence=m["occurrence"], outcome=outcome,
                         diff=(result or {}).get("diff") or ""))
    # sessions made before the ranges started at the bodies: their signature mutants
    # (annotations, never evaluated) are counted as excluded
    inside = [tuple(map(int, r.split("-"))) for r in t["ranges"]]
    for r in rows:
        if not any(a <= r["line"] <= b for a, b in inside):
            r["outcome"] = "skipped"
    run = [r for r in rows if r["outcome"] not in ("skipped", "pending", "sampled-out")]
    survived = [r for r in run if r["outcome"] == "survived"]
    return dict(module=t["module"], functions=t["functions"], tests=t["tests"],
                lines=t["ranges"], generated=len(rows),
                skipped=sum(r["outcome"] == "skipped" for r in rows),
                sampled_out=sum(r["outcome"] == "sampled-out" for r in rows),
                pending=sum(r["outcome"] == "pending" for r in rows), run=len(run),
                killed=len(run) - len(survived), survived_count=len(survived),
                kill_rate=round((len(run) - len(survived)) / len(run), 4) if run else None,
                date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                survived=survived)


def head_commit() -> str:
    """The checkout's commit (+ "-dirty" with changes to tracked files outside mutation/):
    the sources copied."""
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", ".", ":!mutation"],
                           cwd=ROOT).returncode != 0
    return head + ("-dirty" if dirty else "")


def write_results(results: dict, commit: str) -> None:
    machine = f"{platform.machine()} {platform.system()}, {os.cpu_count()} cores"
    (HERE / "results_py.json").write_text(json.dumps(dict(machine=machine, commit=commit,
                                                          targets=results), indent=1) + "\n")
    run = sum(r["run"] for r in results.values())
    killed = sum(r["killed"] for r in results.values())
    md = [f"# Python mutation run ({machine}; the sources of each target: its commit)", "",
          f"cosmic-ray, {len(results)} targets: {run} mutants run, {killed} killed, "
          f"{run - killed} survived" + (f" (kill rate {100 * killed / run:.1f} %)" if run else ""),
          "", "| target | module | run | of | killed | survived | kill rate | tests | date | sources |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for name, r in results.items():
        rate = f"{100 * r['kill_rate']:.1f} %" if r["kill_rate"] is not None else "-"
        of = r["run"] + r.get("sampled_out", 0) + r.get("pending", 0)
        md.append(f"| {name} | {r['module']} | {r['run']} | {of} | {r['killed']} | {r['survived_count']} "
                  f"| {rate} | {r['tests']} | {r['date']} | {r.get('commit', '?')} |")
    md += ["", "Survivors (the reason for each is in mutation/README.md):", ""]
    for name, r in results.items():
        for s in r["survived"]:
            body = [ln for ln in s["diff"].splitlines() if ln.startswith(("+", "-"))
                    and not ln.startswith(("+++", "---"))]
            md.append(f"- {name}, {r['module']} line {s['line']}, {s['operator']}: "
                      f"`{' / '.join(body)[:200]}`")
    (HERE / "results_py.md").write_text("\n".join(md) + "\n")
    print(f"{len(results)} targets: {run} run, {killed} killed, {run - killed} survived", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--work", type=Path, default=Path(tempfile.gettempdir()) / "gfins_mutation_py")
    ap.add_argument("--target", nargs="*", help="target names (default: all)")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--sample", type=int, default=0,
                    help="run a random sample of this many mutants of each target (0: all)")
    ap.add_argument("--seed", type=int, default=25, help="the sample's seed")
    ap.add_argument("--rerun-survivors", action="store_true",
                    help="run the survivors of the sessions again (after adding tests)")
    args = ap.parse_args(argv)
    cr, all_targets = targets()
    chosen = [t for t in all_targets if not args.target or t["name"] in args.target]
    unknown = set(args.target or []) - {t["name"] for t in all_targets}
    if unknown:
        print(f"unknown targets {sorted(unknown)}", file=sys.stderr)
        return 2
    args.work.mkdir(parents=True, exist_ok=True)
    commit = head_commit()          # the sources as copied now
    pythonpath = copy_tree(args.work)
    src = args.work / "src"
    old = {}
    if (HERE / "results_py.json").is_file():
        old = json.loads((HERE / "results_py.json").read_text()).get("targets", {})
    results = {t["name"]: old[t["name"]] for t in all_targets if t["name"] in old}
    for t in chosen:
        session = args.work / f"{t['name']}.sqlite"
        cfg = args.work / f"{t['name']}.toml"
        write_session_config(cfg, cr, t, pythonpath)
        if args.rerun_survivors:
            import sqlite3
            with sqlite3.connect(session) as db:
                n = db.execute("DELETE FROM work_results WHERE test_outcome = 'SURVIVED'").rowcount
            print(f"{t['name']}: {n} survivors to run again", flush=True)
            sh("cosmic-ray", "exec", str(cfg), str(session), cwd=src)
        elif not args.report_only:
            sh("cosmic-ray", "init", str(cfg), str(session), "--force", cwd=src)
            sh("cr-filter-operators", str(session), str(cfg), cwd=src)
            sh("cr-filter-lines", "--config", str(cfg), str(session), cwd=src)
            if args.sample:
                kept, of = sample_session(session, args.sample, args.seed)
                print(f"{t['name']}: a sample of {kept} of {of} mutants (seed {args.seed})",
                      flush=True)
            sh("cosmic-ray", "baseline", str(cfg), cwd=src)
            sh("cosmic-ray", "exec", str(cfg), str(session), cwd=src)
        if session.is_file():
            results[t["name"]] = session_report(session, src, t)
            if not args.report_only:
                results[t["name"]]["commit"] = commit
            else:
                results[t["name"]]["commit"] = old.get(t["name"], {}).get("commit", "?")
            r = results[t["name"]]
            print(f"{t['name']}: {r['run']} run, {r['killed']} killed, {r['survived_count']} "
                  f"survived", flush=True)
    order = [t["name"] for t in all_targets]
    write_results({k: results[k] for k in order if k in results}, commit)
    return 0


if __name__ == "__main__":
    sys.exit(main())
