#!/usr/bin/env python3
"""Python mutation run with cosmic-ray over the functions listed in
mutation/cosmic-ray.toml (``[gfins-mutation] functions``), with that file's test command.

Usage (from the repository root, in the dev venv with the `mutation` extra):
    nice -n 5 python mutation/run_py.py              # init, filter, exec, report
    python mutation/run_py.py --report-only          # report an existing session

cosmic-ray edits the module in place while a mutant runs and restores it afterwards:
run it in a checkout you are not editing at the same time. The session database goes to
--session (default: under the system temporary directory); the results to
mutation/results_py.json and mutation/results_py.md.

The functions are turned into line ranges here (ast), so the selection follows the
sources as they change; cosmic-ray's own line filter takes those ranges.
"""
from __future__ import annotations

import argparse
import ast
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HERE = Path(__file__).resolve().parent
CONFIG = HERE / "cosmic-ray.toml"


def function_lines(path: Path, names: list[str]) -> list[str]:
    """'first-last' line ranges of the named top-level functions of a module."""
    tree = ast.parse(path.read_text())
    found = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    missing = [n for n in names if n not in found]
    if missing:
        raise SystemExit(f"{path}: no top-level function {missing} (update {CONFIG.name})")
    ranges = []
    for n in names:
        node = found[n]
        first = min([node.lineno] + [d.lineno for d in node.decorator_list])
        ranges.append(f"{first}-{node.end_lineno}")
    return ranges


def selection() -> tuple[dict, str, list[str]]:
    with open(CONFIG, "rb") as fh:
        cfg = tomllib.load(fh)
    sel = cfg["gfins-mutation"]
    module = sel["module"]
    return cfg, module, function_lines(ROOT / module, sel["functions"])


def write_session_config(path: Path) -> None:
    cfg, module, ranges = selection()
    cr = cfg["cosmic-ray"]
    ops = cr["filters"]["operators-filter"]["exclude-operators"]
    text = [
        "[cosmic-ray]",
        f"module-path = {json.dumps(module)}",
        f"timeout = {float(cr['timeout'])}",
        "excluded-modules = []",
        f"test-command = {json.dumps(cr['test-command'])}",
        "[cosmic-ray.distributor]",
        'name = "local"',
        "[cosmic-ray.filters.operators-filter]",
        "exclude-operators = [" + ", ".join(json.dumps(o) for o in ops) + "]",
        "[cosmic-ray.filters.line-filter.lines]",
        f"{json.dumps(module)} = [" + ", ".join(json.dumps(r) for r in ranges) + "]",
    ]
    path.write_text("\n".join(text) + "\n")


def sh(*cmd: str) -> None:
    print("$", " ".join(cmd), flush=True)
    subprocess.run(cmd, cwd=ROOT, check=True)


def report(session: Path) -> dict:
    dump = subprocess.run(["cosmic-ray", "dump", str(session)], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout
    rows = []
    for line in dump.splitlines():
        item, result = json.loads(line)
        m = item["mutations"][0]
        outcome = "pending" if result is None else (
            "skipped" if result["worker_outcome"] == "skipped" else
            result["test_outcome"] if result["worker_outcome"] == "normal" else
            result["worker_outcome"])
        rows.append(dict(job=item["job_id"], line=m["start_pos"][0], operator=m["operator_name"],
                         occurrence=m["occurrence"], outcome=outcome,
                         diff=(result or {}).get("diff") or ""))
    run = [r for r in rows if r["outcome"] not in ("skipped", "pending")]
    killed = [r for r in run if r["outcome"] != "survived"]
    survived = [r for r in run if r["outcome"] == "survived"]
    _, module, ranges = selection()
    meta = dict(date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
                commit=subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                      capture_output=True, text=True).stdout.strip(),
                machine=f"{platform.machine()} {platform.system()}, {os.cpu_count()} cores",
                module=module, lines=ranges, generated=len(rows),
                skipped=sum(r["outcome"] == "skipped" for r in rows),
                pending=sum(r["outcome"] == "pending" for r in rows),
                run=len(run), killed=len(killed), survived=len(survived),
                kill_rate=round(len(killed) / len(run), 4) if run else None)
    (HERE / "results_py.json").write_text(json.dumps(dict(meta=meta, survived=survived), indent=1)
                                          + "\n")
    md = [f"# Python mutation run ({meta['date']}, commit {meta['commit']}, {meta['machine']})",
          "", f"cosmic-ray over {module}, lines {', '.join(ranges)}: {len(rows)} mutants "
          f"generated, {meta['skipped']} excluded by the operator filter, {meta['pending']} not "
          f"run; {len(run)} run: {len(killed)} killed, {len(survived)} survived"
          + (f" (kill rate {100 * len(killed) / len(run):.1f} %)" if run else ""), "",
          "Survivors (the reason for each is in mutation/README.md):", ""]
    for r in survived:
        body = [ln for ln in r["diff"].splitlines() if ln.startswith(("+", "-"))
                and not ln.startswith(("+++", "---"))]
        md.append(f"- line {r['line']}, {r['operator']}: `{' / '.join(body)[:200]}`")
    (HERE / "results_py.md").write_text("\n".join(md) + "\n")
    print(f"{len(run)} run, {len(killed)} killed, {len(survived)} survived, "
          f"{meta['pending']} pending", flush=True)
    return meta


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--session", type=Path,
                    default=Path(tempfile.gettempdir()) / "gfins_mutation_py.sqlite")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--rerun-survivors", action="store_true",
                    help="run the survivors of the session again (after adding tests)")
    args = ap.parse_args(argv)
    if args.rerun_survivors:
        import sqlite3
        cfg = args.session.with_suffix(".toml")
        write_session_config(cfg)
        with sqlite3.connect(args.session) as db:
            n = db.execute("DELETE FROM work_results WHERE test_outcome = 'SURVIVED'").rowcount
        print(f"{n} survivors to run again", flush=True)
        sh("cosmic-ray", "exec", str(cfg), str(args.session))
    elif not args.report_only:
        cfg = args.session.with_suffix(".toml")
        write_session_config(cfg)
        sh("cosmic-ray", "init", str(cfg), str(args.session), "--force")
        sh("cr-filter-operators", str(args.session), str(cfg))
        sh("cr-filter-lines", "--config", str(cfg), str(args.session))
        sh("cosmic-ray", "baseline", str(cfg))
        sh("cosmic-ray", "exec", str(cfg), str(args.session))
    report(args.session)
    return 0


if __name__ == "__main__":
    sys.exit(main())
