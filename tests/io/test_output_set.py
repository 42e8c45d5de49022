"""The output contract (gfins_fmi/io/output_set.py, issue 21): a run's files as one set.

Each test is a defect the issue lists, or a guarantee the contract states:

* an output that is an input (same path, a symbolic or a hard link: compared by inode)
  was written over the recording; now refused before anything runs;
* the files of a run appear together or not at all: a failing rename puts the previous
  set back, an interrupt during the renames is held until they are done;
* temporaries are unique (two runs never share one) and none is left; those of a process
  killed outright are removed by the next run on the same outputs;
* a failed run's tables go to ``<stem>.partial<suffix>`` with where and why it stopped
  (CSV: the first line; npz: the archive comment; Parquet: the metadata), the
  destinations untouched; files of the set this run does not produce are removed with
  its commit;
* two processes committing sets to the same names never leave a mix.

Truth: the bytes written, read back with numpy, zipfile and pyarrow, not with the code
under test.
"""
from __future__ import annotations

import os
import pathlib
import re
import signal
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from gfins_fmi.io.output_set import OutputError, OutputSet

TEMP = re.compile(r"\.\d+-[0-9a-f]{8}\.tmp")


def _names(folder) -> list[str]:
    return sorted(p.name for p in pathlib.Path(folder).iterdir())


def _write_set(folder: pathlib.Path, token: str, inputs=()) -> list[pathlib.Path]:
    """A set of three files, each of which names ``token``."""
    code = float(int.from_bytes(token.encode(), "little"))
    with OutputSet(inputs) as outs:
        outs.write_table(folder / "sol.csv", ["t_s", "x_m"], [np.arange(3.0), np.full(3, code)])
        outs.write_table(folder / "sol.innovations.csv", ["t_s"], [np.full(2, code)])
        outs.write_text(folder / "sol.config.json", f'{{"run": "{token}"}}\n')
        return outs.commit()


def _token(folder: pathlib.Path) -> str:
    """The token of the set in ``folder``; AssertionError when its files disagree."""
    token = (folder / "sol.config.json").read_text().split('"')[3]
    code = float(int.from_bytes(token.encode(), "little"))
    assert np.all(np.loadtxt(folder / "sol.csv", delimiter=",", skiprows=1)[:, 1] == code), "a mix"
    assert np.all(np.loadtxt(folder / "sol.innovations.csv", skiprows=1) == code), "a mix"
    return token


@pytest.mark.parametrize("how", ["same path", "symbolic link", "hard link", "partial name"])
def test_an_output_that_is_an_input_is_refused(how, tmp_path):
    """Before: `navigate rec.csv rec.csv` (or an output linked to the input) replaced the
    recording with a partial solution. Compared as files (device, inode), not names."""
    rec = tmp_path / "rec.csv"
    rec.write_bytes(b"1,2,3\n")
    out = {"same path": rec, "symbolic link": tmp_path / "link.csv",
           "hard link": tmp_path / "hard.csv", "partial name": tmp_path / "rec0.csv"}[how]
    if how == "symbolic link":
        out.symlink_to(rec)
    elif how == "hard link":
        os.link(rec, out)
    elif how == "partial name":        # rec0.partial.csv would be the partial output
        os.link(rec, tmp_path / "rec0.partial.csv")
    with pytest.raises(OutputError, match=r"is the input .*rec\.csv .*give another output name"):
        with OutputSet([rec]) as outs:
            outs.claim(out)
    assert rec.read_bytes() == b"1,2,3\n"


def test_folders_are_checked_before_the_run(tmp_path):
    """Before: a missing folder was reported after the run as "[Errno 2] ...
    sol.csv.1a2b3c4d.partial"; a folder given as the output is named as such."""
    with pytest.raises(OutputError, match=r"its folder .*nowhere does not exist: create it"):
        OutputSet().claim(tmp_path / "nowhere" / "sol.csv")
    with pytest.raises(OutputError, match=r"is a folder: give a file name"):
        OutputSet().claim(tmp_path)
    if os.geteuid() != 0:                          # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir(mode=0o500)
        with pytest.raises(OutputError, match=r"is not writable"):
            OutputSet().claim(ro / "sol.csv")
    outs = OutputSet()
    outs.claim(tmp_path / "a.csv")
    with pytest.raises(OutputError, match="named twice"):
        outs.claim(tmp_path / "a.csv", produced=False)


def test_files_appear_together_and_no_temporary_stays(tmp_path):
    with OutputSet() as outs:
        outs.write_table(tmp_path / "a.csv", ["x"], [np.arange(3.0)])
        outs.write_text(tmp_path / "b.json", "{}")
        names = _names(tmp_path)
        assert len(names) == 2 and all(TEMP.search(n) for n in names), names   # beside them
        assert outs.commit() == [tmp_path / "a.csv", tmp_path / "b.json"]
    assert _names(tmp_path) == ["a.csv", "b.json"]
    assert np.loadtxt(tmp_path / "a.csv", skiprows=1).tolist() == [0.0, 1.0, 2.0]
    with OutputSet() as outs:                      # left without a commit: nothing happens
        outs.write_text(tmp_path / "b.json", "new")
    assert _names(tmp_path) == ["a.csv", "b.json"] and (tmp_path / "b.json").read_text() == "{}"


def test_a_failing_rename_puts_the_previous_set_back(tmp_path, monkeypatch):
    _write_set(tmp_path, "old")
    before = {n: (tmp_path / n).read_bytes() for n in _names(tmp_path)}
    real, calls = os.replace, []

    def flaky(src, dst):
        calls.append(dst)
        if len(calls) == 2 and str(src).find(".tmp") > 0:   # the second file of the set
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(OSError, match="No space"):
        _write_set(tmp_path, "new")
    monkeypatch.setattr(os, "replace", real)
    assert {n: (tmp_path / n).read_bytes() for n in _names(tmp_path)} == before


def test_an_interrupt_during_the_renames_waits_for_them(tmp_path, monkeypatch):
    """SIGTERM (the CLI raises on it, as on Ctrl-C) arriving while the set is renamed is
    held until the last rename: the folder holds the whole new set, then the run stops."""
    class Stop(Exception):
        pass

    def handler(signum, frame):
        raise Stop()

    _write_set(tmp_path, "old")
    real = os.replace

    def signalling(src, dst):
        os.kill(os.getpid(), signal.SIGTERM)      # delivered now unless held
        return real(src, dst)

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        monkeypatch.setattr(os, "replace", signalling)
        with pytest.raises(Stop):
            _write_set(tmp_path, "new")
    finally:
        monkeypatch.setattr(os, "replace", real)
        signal.signal(signal.SIGTERM, previous)
    assert _names(tmp_path) == ["sol.config.json", "sol.csv", "sol.innovations.csv"]
    assert _token(tmp_path) == "new"


def test_partial_tables_say_where_and_why(tmp_path):
    pa = pytest.importorskip("pyarrow.parquet", reason="Parquet needs the optional pyarrow")
    for name in ("sol.csv", "sol.npz", "sol.parquet"):
        (tmp_path / name).write_bytes(b"previous")
    with OutputSet() as outs:
        for name in ("sol.csv", "sol.npz", "sol.parquet"):
            with outs.table(tmp_path / name, ["t_s", "x_m"]) as w:
                w.write([np.arange(4.0), np.arange(4.0) ** 2])
        kept = outs.keep_partial("stopped at input row 4 of rec.csv: a NaN")
        assert outs.outcome().startswith("the rows written before it are in ")
    assert kept == [tmp_path / "sol.partial.csv", tmp_path / "sol.partial.npz",
                    tmp_path / "sol.partial.parquet"]
    lines = (tmp_path / "sol.partial.csv").read_text().splitlines()
    assert lines[0] == "# partial: stopped at input row 4 of rec.csv: a NaN"
    assert lines[1] == "t_s,x_m" and np.loadtxt(lines[2:], delimiter=",").shape == (4, 2)
    with zipfile.ZipFile(tmp_path / "sol.partial.npz") as z:
        assert z.comment == b"partial: stopped at input row 4 of rec.csv: a NaN"
    with np.load(tmp_path / "sol.partial.npz") as z:
        assert z["x_m"].tolist() == [0.0, 1.0, 4.0, 9.0]
    meta = pa.read_schema(tmp_path / "sol.partial.parquet").metadata
    assert meta[b"gfins_fmi.partial"] == b"stopped at input row 4 of rec.csv: a NaN"
    for name in ("sol.csv", "sol.npz", "sol.parquet"):          # the destinations as they were
        assert (tmp_path / name).read_bytes() == b"previous"
    _names_before = _names(tmp_path)
    assert not any(TEMP.search(n) for n in _names_before)
    # the next run that succeeds removes the partial files of its outputs
    with OutputSet() as outs:
        for name in ("sol.csv", "sol.npz", "sol.parquet"):
            outs.write_table(tmp_path / name, ["t_s"], [np.arange(2.0)])
        outs.commit()
    assert _names(tmp_path) == ["sol.csv", "sol.npz", "sol.parquet"]


def test_files_of_the_set_not_produced_go_with_the_commit(tmp_path):
    """A run without --smooth after one with it: the old smoothed solution would sit
    beside a solution it does not belong to. It is removed with the commit (not before:
    a failed run leaves the previous set whole)."""
    for name in ("sol.csv", "sol.smoothed.csv"):
        (tmp_path / name).write_text("old\n")
    with OutputSet() as outs:
        outs.claim(tmp_path / "sol.smoothed.csv", produced=False)
        outs.write_text(tmp_path / "sol.csv", "new\n")
    assert _names(tmp_path) == ["sol.csv", "sol.smoothed.csv"]          # discarded: all kept
    with OutputSet() as outs:
        outs.claim(tmp_path / "sol.smoothed.csv", produced=False)
        outs.write_text(tmp_path / "sol.csv", "new\n")
        outs.commit()
    assert _names(tmp_path) == ["sol.csv"] and (tmp_path / "sol.csv").read_text() == "new\n"


def test_temporaries_of_a_killed_process_are_removed_by_the_next_run(tmp_path):
    """A process killed outright (SIGKILL) cannot clean up; the next run on the same
    outputs removes its temporaries (their names carry the process id), not those of a
    process still running."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    left = [tmp_path / f"sol.{dead.pid}-0123abcd.tmp.csv", tmp_path / f"sol.{dead.pid}-4567cdef.tmp.csv.d"]
    left[0].write_text("half a solution")
    left[1].mkdir()
    alive = tmp_path / f"sol.{os.getpid()}-89abcdef.tmp.csv"
    alive.write_text("a running writer's")
    OutputSet().claim(tmp_path / "sol.csv")
    assert _names(tmp_path) == [alive.name]


def test_a_stage_that_fails_half_way_drops_its_table_and_its_working_folder(tmp_path):
    """The smoother in chunks (issue 20) writes its table a chunk at a time and keeps its
    epochs in a working folder beside it: when it fails half way, OutputSet.drop removes
    what it wrote and the commit treats the table as not produced (an earlier one
    removed: it belongs to another solution); the working folder goes with its
    finalizer, and one a killed process left (files inside) goes with the next claim."""
    from gfins_fmi.io.temporaries import temporary_folder_beside, temporary_pattern
    sm = tmp_path / "sol.smoothed.csv"
    sm.write_text("old\n")
    with OutputSet() as outs:
        folder, remove = temporary_folder_beside(sm, outs)
        assert folder.is_dir() and temporary_pattern(sm).match(folder.name), folder.name
        (folder / "epochs_P_post.f8").write_bytes(b"\0" * 64)
        w = outs.table(sm, ["t_s", "x_m"])
        w.write([np.arange(3.0), np.zeros(3)])
        outs.drop(sm)
        outs.write_text(tmp_path / "sol.csv", "new\n")
        outs.commit()
        remove()
    assert _names(tmp_path) == ["sol.csv"], _names(tmp_path)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    left = tmp_path / f"sol.smoothed.{dead.pid}-0123abcd.tmp.csv.d"
    left.mkdir()
    (left / "rows.f8").write_bytes(b"\0" * 64)
    OutputSet().claim(sm)
    assert _names(tmp_path) == ["sol.csv"], _names(tmp_path)


#: a process committing ``rounds`` sets of three files, each naming the round
_COMMITTER = """
import pathlib, sys
import numpy as np
from gfins_fmi.io.output_set import OutputSet
folder, token, rounds = pathlib.Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
for i in range(rounds):
    tok = f"{token}{i}"
    code = float(int.from_bytes(tok.encode(), "little"))
    with OutputSet() as outs:
        outs.write_table(folder / "sol.csv", ["t_s", "x_m"], [np.arange(3.0), np.full(3, code)])
        outs.write_table(folder / "sol.innovations.csv", ["t_s"], [np.full(2, code)])
        outs.write_text(folder / "sol.config.json", '{"run": "%s"}\\n' % tok)
        outs.commit()
"""


def test_two_processes_on_the_same_outputs_never_mix(tmp_path):
    """Before: both runs wrote OUT.innovations.csv.part; in 2 of 24 staggered runs the log
    was corrupt. Now each has its own temporaries and the commits take turns (a lock on
    the folder): whatever the interleaving, the folder ends with one run's whole set."""
    for attempt in range(2):
        folder = tmp_path / f"a{attempt}"
        folder.mkdir()
        procs = [subprocess.Popen([sys.executable, "-c", _COMMITTER, str(folder), t, "15"],
                                  cwd=tmp_path, stderr=subprocess.PIPE) for t in "AB"]
        for p in procs:
            _, err = p.communicate(timeout=120)
            assert p.returncode == 0, err.decode()
        assert _names(folder) == ["sol.config.json", "sol.csv", "sol.innovations.csv"]
        tok = _token(folder)
        assert tok in ("A14", "B14"), tok      # the last commit of one of them, whole
