"""The interruption and concurrency study of ``gfins integrate`` (issue 21), run in a
process of its own by tests/cli/test_interrupts.py (signals go to this process, not to
pytest's):

    python tests/support/interrupts.py FOLDER IMU GNSS INITIAL POINTS PAIRS SEED [MODE]

In FOLDER, an "old" set of outputs (integrate --grade tactical --smooth) is made, and the
"new" set (--grade consumer --smooth) once to know its hashes. Then POINTS times the new
run is started in this process (``gfins_fmi.cli.main``) and SIGINT or SIGTERM is
sent to it (each in turn for each phase) at a random point of one of its phases — reading the records, the filter, the
smoother, writing and committing the set. A point is a Python-level event (a call or a
return, Python or C: ``sys.setprofile``) counted from the run's start: a reference run
counts the events of each phase (wrappers around each phase's entry point mark them),
and the signal is sent at the event drawn, where the run really is (a timer could not
aim: the whole run takes a fraction of a second, most of it in a few C calls, during
which a signal waits anyway). After
each: the folder must hold exactly the old set or exactly the new set (sha256 of every
file) and nothing else (no temporary, no partial file); the old set is put back when the
new one won. Then PAIRS times two ``gfins integrate`` processes (old and new options)
are started together, staggered at random, on the same outputs: both must succeed and
the folder must hold one whole set.

MODE "whole" (default) runs the whole-record path, whose phases follow one another;
"chunks" the path every run takes by default, in chunks of 1200 samples (the record is
several chunks): its reading, filtering, writing and smoothing interleave chunk by chunk,
so the points are aimed at the four quarters of the run's events instead of at phases
(the phase hit is still reported), and the smoother's working folder must be gone too.

Prints one JSON object: the outcomes (phase hit, exit status, which set), and the
failures (an empty list when every check held).
"""
from __future__ import annotations

import hashlib
import json
import os
import pathlib
import random
import signal
import subprocess
import sys
import time


def _hashes(folder: pathlib.Path) -> dict:
    """sha256 of every file; in the effective configuration (sol.config.json) the folder's
    own path is replaced by a placeholder, so that sets in two folders compare."""
    out = {}
    for p in sorted(folder.iterdir()):
        data = p.read_bytes()
        if p.name.endswith(".config.json"):
            data = data.replace(str(folder).encode(), b"<folder>")
        out[p.name] = hashlib.sha256(data).hexdigest()
    return out


def main(argv: list[str]) -> int:
    folder, imu, gnss, initial = pathlib.Path(argv[0]), argv[1], argv[2], argv[3]
    points, pairs, seed = int(argv[4]), int(argv[5]), int(argv[6])
    mode = argv[7] if len(argv) > 7 else "whole"
    rng = random.Random(seed)

    import gfins_fmi.cli.integrate as integrate
    from gfins_fmi.cli import main as gfins
    from gfins_fmi.estimation.navigator import IntegratedNavigator
    from gfins_fmi.estimation.solution import IntegratedSolution
    from gfins_fmi.io.output_set import OutputSet

    out = folder / "run"
    out.mkdir()
    base = ["integrate", imu, gnss, str(out / "sol.csv"), "--imu-format", "csv", "--gnss-format", "csv",
            initial, "--smooth"]
    old_args, new_args = base + ["--grade", "tactical"], base + ["--grade", "consumer"]

    # the phases, marked by wrappers around their entry points; the events counted
    state = {"phase": "start", "marks": [], "n": 0, "fire": -1, "sig": None, "hit": None}

    def mark(name):
        state["phase"] = name
        state["marks"].append((name, state["n"]))

    def wrap(owner, attr, name):
        inner = getattr(owner, attr)

        def wrapper(*a, **k):
            mark(name)
            return inner(*a, **k)
        setattr(owner, attr, wrapper)

    if mode == "whole":
        # the whole-record run's phases (read, filter, write, smoother, write, commit) follow
        # one another
        integrate._streamed = lambda args: False
        wrap(integrate, "read_imu", "read")
        wrap(IntegratedSolution, "smooth", "smoother")
    else:
        # in chunks they interleave: several chunks (a multiple of every --subsamples)
        import gfins_fmi.cli.integrate_stream as stream
        from gfins_fmi.estimation.smoother_stream import StreamingSmoother
        integrate.STREAM_CHUNK = stream.STREAM_CHUNK = 1200
        wrap(StreamingSmoother, "smooth", "smoother")
    wrap(IntegratedNavigator, "run", "filter")
    wrap(OutputSet, "write_table", "write")
    wrap(OutputSet, "commit", "commit")

    def count(frame, event, arg):
        state["n"] += 1
        if state["n"] == state["fire"]:
            state["hit"] = state["phase"]
            os.kill(os.getpid(), state["sig"])

    def run(args, fire=-1, sig=None) -> int:
        state.update(phase="start", marks=[], n=0, fire=fire, sig=sig, hit=None)
        sys.setprofile(count)
        try:
            return gfins(args)
        finally:
            sys.setprofile(None)
            state["marks"].append(("end", state["n"]))

    def late(signum, frame):         # a signal after main() returned (main's own handler is off)
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, late)
    failures = []
    quiet = open(os.devnull, "w")
    sys.stdout = quiet                              # the commands' summaries
    assert run(new_args) == 0
    new = _hashes(out)
    assert run(old_args) == 0
    old = _hashes(out)
    assert run(new_args) == 0 and _hashes(out) == new
    marks = state["marks"]                           # (phase, events before it) of a whole run
    assert run(old_args) == 0 and _hashes(out) == old
    if set(new) != set(old) or any(new[k] == old[k] for k in new):
        failures.append(f"the two sets are not told apart by their hashes: {sorted(new)}")
    at = {}
    for name, n in marks:
        at.setdefault(name, []).append(n)
    if mode == "whole":
        # read -> filter -> write (solution, log) -> smoother -> write (smoothed) -> commit -> end
        windows = {"read": (at["read"][0], at["filter"][0]), "filter": (at["filter"][0], at["write"][0]),
                   "smoother": (at["smoother"][0], at["write"][-1]),
                   "write": (at["write"][-1], at["end"][0])}
    else:
        if len(at["filter"]) < 3:
            failures.append(f"the run in chunks filtered {len(at['filter'])} chunks: not several")
        q = [at["end"][0] * i // 4 for i in range(5)]
        windows = {f"quarter {i + 1}": (q[i], q[i + 1]) for i in range(4)}
    outcomes = []
    for k in range(points):
        target = list(windows)[k % len(windows)]
        a, b = windows[target]
        fire = rng.randrange(a + 1, b)
        sig = signal.SIGINT if (k // len(windows)) % 2 == 0 else signal.SIGTERM   # both, each phase
        try:
            rc = run(new_args, fire, sig)
        except KeyboardInterrupt:                     # delivered after main() returned
            rc = "after"
        got = _hashes(out)
        which = "new" if got == new else "old" if got == old else "MIX"
        hit = state["hit"]
        if which == "MIX":
            failures.append(f"point {k} ({target}, event {fire}, {sig.name}, hit {hit}): the folder "
                            f"holds neither set: {sorted(got)}")
        if which == "new" and rc not in (0, 130, 143, "after"):
            failures.append(f"point {k}: exit {rc} with the new set in place")
        if hit is not None and rc == 0:
            failures.append(f"point {k} ({target}, event {fire}, {sig.name}, hit {hit}): the signal "
                            "came during the run, yet it ran to its end (the signal was lost)")
        if which == "old" and rc not in (130, 143):
            failures.append(f"point {k} ({target}, event {fire}, hit {hit}): exit {rc} but the old set "
                            "is in place")
        outcomes.append({"aimed": target, "event": fire, "hit": hit, "signal": sig.name, "exit": rc,
                         "set": which})
        if which != "old":
            assert run(old_args) == 0 and _hashes(out) == old
    sys.stdout = sys.__stdout__
    ref = {name: v for name, v in at.items()}

    pair_outcomes = []
    exe = [sys.executable, "-c", "import sys; from gfins_fmi.cli import main; sys.exit(main(sys.argv[1:]))"]
    for j in range(pairs):
        d = folder / f"pair{j}"
        d.mkdir()
        args = [[a.replace(str(out), str(d)) for a in x] for x in (old_args, new_args)]
        if j % 2:
            args.reverse()
        procs = []
        for x in args:
            procs.append(subprocess.Popen(exe + x, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE))
            time.sleep(rng.uniform(0.0, 0.5))
        codes = []
        for p in procs:
            _, err = p.communicate(timeout=600)
            codes.append(p.returncode)
            if p.returncode != 0:
                failures.append(f"pair {j}: a run failed ({p.returncode}): {err.decode()[-300:]}")
        got = _hashes(d)
        which = "new" if got == new else "old" if got == old else "MIX"
        if which == "MIX":
            failures.append(f"pair {j}: the folder holds neither set: {sorted(got)}")
        pair_outcomes.append({"exits": codes, "set": which})
    print(json.dumps({"reference_events": ref, "points": outcomes, "pairs": pair_outcomes,
                      "failures": failures}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
