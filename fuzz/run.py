"""Build and run the fuzz targets of fuzz/ (see fuzz/README.md).

    python fuzz/run.py build [--build-dir DIR]
    python fuzz/run.py run TARGET... [--runs N] [--max-time S] [--seed K] [--corpus-dir DIR]
    python fuzz/run.py list

C targets (libFuzzer, clang, ASan + UBSan) are fuzz_<name> executables in
<build-dir>/fuzz/; Python targets (atheris) are fuzz/python/<target>.py. A run starts
from the committed seed corpus fuzz/corpus/<target>/ (copied into a work corpus, so the
committed one only changes by hand) and prints one summary line:
    <target>: <runs> runs in <s> s, coverage <cov> edges / <ft> features, corpus <n>; OK
A crash, a sanitizer report, an oracle failure or a hang (-timeout, 10 s per input)
makes the run fail; libFuzzer writes the input as <work>/crash-* (or timeout-*).
"""
from __future__ import annotations

import argparse
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
C_TARGETS = ["fuzz_sins", "fuzz_accel", "fuzz_filters", "fuzz_rotation", "fuzz_ins_fb", "fuzz_text",
             "fuzz_fmu_accel9", "fuzz_fmu_sins", "fuzz_fmu_gfnav_cube6", "fuzz_fmu_gfnav_qin9",
             "fuzz_fmu_gfnav_12", "fuzz_fmu_vehicle", "fuzz_fmu_ins_gnss", "fuzz_fmu_transfer_align",
             "fuzz_fmu_state_sins", "fuzz_fmu_state_gfnav_cube6", "fuzz_fmu_state_gfnav_qin9",
             "fuzz_fmu_state_gfnav_12", "fuzz_fmu_state_ins_gnss",
             "fuzz_fmu_state_transfer_align"]
PY_TARGETS = ["fuzz_io_readers"]
MAX_LEN = 2048      # bytes per input: enough for 40 FMI calls or a 16-sample record
TIMEOUT_S = 10      # an input that runs longer is a hang


def build(build_dir: pathlib.Path, targets: list[str] | None = None) -> None:
    """Configure and build the libFuzzer targets (all, or only ``targets``)."""
    cc = shutil.which("clang")
    if not cc:
        raise SystemExit("clang not found: apt-get install clang libclang-rt-14-dev")
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    env = dict(os.environ, CC=cc)
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build_dir), *gen,
                    "-DGFINS_BUILD_FUZZERS=ON", "-DGFINS_BUILD_TESTS=OFF",
                    "-DCMAKE_BUILD_TYPE=RelWithDebInfo", f"-DPython_EXECUTABLE={sys.executable}"],
                   check=True, env=env, stdout=subprocess.DEVNULL)
    only = ["--target", *targets] if targets else []
    subprocess.run(["cmake", "--build", str(build_dir), "-j", "2", *only], check=True, env=env,
                   stdout=subprocess.DEVNULL)


def run(target: str, build_dir: pathlib.Path, runs: int | None, max_time: int | None,
        seed: int, corpus_dir: pathlib.Path | None) -> dict:
    """One bounded run; returns the figures (raises RuntimeError on a finding)."""
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"{target}-"))
    corpus = corpus_dir / target if corpus_dir else work / "corpus"
    corpus.mkdir(parents=True, exist_ok=True)
    seeds = HERE / "corpus" / target
    if seeds.is_dir():
        for f in seeds.iterdir():
            shutil.copy(f, corpus / f.name)
    opts = [f"-seed={seed}", f"-max_len={MAX_LEN}", f"-timeout={TIMEOUT_S}", "-rss_limit_mb=4096",
            f"-artifact_prefix={work}/", "-print_final_stats=1"]
    if runs is not None:
        opts.append(f"-runs={runs}")
    if max_time is not None:
        opts.append(f"-max_total_time={max_time}")
    if target in PY_TARGETS:
        cmd = [sys.executable, str(HERE / "python" / f"{target}.py"), *opts, str(corpus)]
    else:
        cmd = [str(build_dir / "fuzz" / target), *opts, str(corpus)]
    env = dict(os.environ, ASAN_OPTIONS="abort_on_error=1:detect_leaks=1",
               UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    log = proc.stdout + proc.stderr
    (work / "log.txt").write_text(log)
    m = re.findall(r"#(\d+)\s+DONE\s+cov: (\d+) ft: (\d+) corp: (\d+)", log)
    done = re.search(r"Done (\d+) runs in (\d+) second", log)
    if proc.returncode != 0 or not done:
        tail = "\n".join(log.splitlines()[-40:])
        raise RuntimeError(f"{target}: finding (exit {proc.returncode}); input and log in {work}\n{tail}")
    runs_done, secs = int(done.group(1)), int(done.group(2))
    cov = m[-1] if m else ("?", "?", "?", "?")
    shutil.rmtree(work) if corpus_dir else None
    return {"target": target, "runs": runs_done, "seconds": secs, "cov": cov[1], "ft": cov[2],
            "corpus": cov[3]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("command", choices=["build", "run", "list"])
    p.add_argument("targets", nargs="*")
    p.add_argument("--build-dir", type=pathlib.Path, default=ROOT / "build" / "fuzz")
    p.add_argument("--runs", type=int)
    p.add_argument("--max-time", type=int)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--corpus-dir", type=pathlib.Path,
                   help="keep each target's grown corpus in DIR/<target> (default: a temporary one)")
    a = p.parse_args(argv)
    if a.command == "list":
        print("\n".join(C_TARGETS + PY_TARGETS))
        return 0
    if a.command == "build":
        build(a.build_dir)
        return 0
    status = 0
    for t in a.targets or C_TARGETS + PY_TARGETS:
        try:
            r = run(t, a.build_dir, a.runs, a.max_time, a.seed, a.corpus_dir)
            print(f"{t}: {r['runs']} runs in {r['seconds']} s, coverage {r['cov']} edges / "
                  f"{r['ft']} features, corpus {r['corpus']}; OK", flush=True)
        except RuntimeError as exc:
            print(exc, flush=True)
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
