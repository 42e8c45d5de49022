"""A run's set of output files, in one place (docs/io.md, "A run's outputs"): every command
and every API writer that produces more than one file goes through an :class:`OutputSet`.

* **Inputs are never outputs.** :meth:`OutputSet.claim` refuses an output that is an input
  of the run, compared as files (device and inode), so a symbolic or hard link to the
  recording is refused like its own name; and an output whose folder does not exist or
  cannot be written, before anything runs.
* **All or nothing.** Every file is written to a unique temporary beside its destination
  (:mod:`gfins_fmi.io.temporaries`) and :meth:`OutputSet.commit` renames the whole set
  into place only when the run has succeeded: under a lock on the folder (two runs on the
  same outputs commit one after the other, never interleaved), with SIGINT and SIGTERM
  held back until the renames are done (then delivered), and with the previous files kept aside until
  then, so a failing rename puts them back. Files of the set that this run does not
  produce (``--smooth`` left out this time) are removed in the same step: the folder
  holds the previous set or the new one, never a mix.
* **Clearly partial.** When a run fails after writing some of its tables, the tables go
  to ``<stem>.partial<suffix>`` instead (:meth:`OutputSet.keep_partial`), stamped with
  where and why it stopped (a CSV's first line); the destinations stay as they were.
  A run that ends either way removes the partial files an earlier run of the same
  outputs left.
* **Interrupts leave nothing behind**: the temporaries are removed when the set is
  left, collected or the interpreter exits; those of a process killed outright are
  removed by the next run on the same outputs.

Use::

    with OutputSet([imu_path, gnss_path]) as outs:
        outs.claim(sol_path); outs.claim(log_path)          # checked before the run
        ...                                                  # the long run
        outs.write_table(sol_path, names, columns)
        outs.write_table(log_path, names2, columns2)
        outs.commit()                                        # both appear together
"""
from __future__ import annotations

import contextlib
import os
import pathlib
import secrets
import signal
import threading
import weakref
from typing import Sequence

from gfins_fmi.io.table_writer import TableWriter
from gfins_fmi.io.temporaries import (mark_partial, partial_path, remove_temporary,
                                      sweep_temporaries, temporary_beside)

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: commits are not serialised
    fcntl = None

__all__ = ["OutputSet", "OutputError", "signals_held"]


class OutputError(ValueError):
    """An output that cannot be written as asked: it is an input of the run, its folder
    is missing or not writable, it is a folder, or it is named twice."""


class _Member:
    """One file of the set: its destination, its writer (a table) and its finished
    temporary, with the finalizer that removes that temporary."""

    def __init__(self, dest: pathlib.Path):
        self.dest = dest
        self.writer: TableWriter | None = None
        self.tmp: pathlib.Path | None = None
        self.remove = None
        self.format: str | None = None

    @property
    def finished(self) -> bool:
        return self.tmp is not None


def _key(path: pathlib.Path) -> str:
    return os.path.normcase(os.path.abspath(path))


def _folder(path: pathlib.Path) -> pathlib.Path:
    return path.parent if str(path.parent) else pathlib.Path(".")


def _names(paths) -> str:
    return ", ".join(str(p) for p in paths)


@contextlib.contextmanager
def signals_held():
    """SIGINT and SIGTERM held back while a set is renamed into place (or a run's working
    files are removed, gfins_fmi/cli/integrate.py): recorded by a
    handler of ours and handed to the previous handlers when the block ends (a Python
    handler, not a signal mask: a mask is the calling thread's, and a signal sent to the
    process may be delivered to another thread, e.g. one of polars' pool, whose Python
    handler then runs in the main thread all the same). A no-op off the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []

    def hold(signum, frame):
        pending.append(signum)

    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            # the old handler first: signal.signal() runs the handlers of pending signals
            # before it returns, so an interrupt there must find it recorded (the study
            # of tests/cli/test_interrupts.py found SIGINT left held forever that way)
            previous[sig] = signal.getsignal(sig)
            signal.signal(sig, hold)
        yield
    finally:
        _restore(previous)
        for sig in dict.fromkeys(pending):            # each one once, in order of arrival
            handler = previous[sig]
            if callable(handler):
                handler(sig, None)                    # KeyboardInterrupt, the CLI's Terminated
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), sig)             # its default action, now


def _restore(previous: dict) -> None:
    """Put every handler back, even when a signal arrives meanwhile (its exception is
    raised once all are back)."""
    raised = None
    for sig, handler in previous.items():
        while True:
            try:
                if handler is not None:
                    signal.signal(sig, handler)
                break
            except BaseException as exc:              # a pending signal's handler raised
                raised = raised or exc
                if signal.getsignal(sig) == handler:
                    break
    if raised is not None:
        raise raised


@contextlib.contextmanager
def _folders_locked(folders):
    """An exclusive lock (``flock``) on each folder, in a fixed order: the commits of
    concurrent runs into one folder follow one another."""
    fds = []
    try:
        for folder in sorted({_key(f) for f in folders}):
            if fcntl is None:
                break
            try:
                fd = os.open(folder, os.O_RDONLY)
            except OSError:      # pragma: no cover - a folder that cannot be opened: no lock
                continue
            fds.append(fd)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX)
            except OSError:      # pragma: no cover - a file system without flock
                pass
        yield
    finally:
        for fd in fds:
            os.close(fd)         # releases the lock


def _aside(dest: pathlib.Path) -> pathlib.Path:
    """A name for the previous file of ``dest`` while the set is renamed (the pattern of
    a temporary, so that a run killed in between leaves nothing the next run keeps)."""
    return dest.with_name(f"{dest.stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp{dest.suffix}")


def _replace_all(moves, removes) -> None:
    """Rename every (temporary, destination) of ``moves`` and remove ``removes``, or,
    when one step fails, put every destination back as it was."""
    kept = []            # (destination, its previous file kept aside)
    placed = []
    try:
        for dest in [d for _, d in moves] + list(removes):
            if os.path.lexists(dest):
                old = _aside(dest)
                try:
                    os.link(dest, old, follow_symlinks=False)   # dest stays in place meanwhile
                except (OSError, NotImplementedError):
                    os.replace(dest, old)                        # no hard links here
                kept.append((dest, old))
        for tmp, dest in moves:
            os.replace(tmp, dest)
            placed.append(dest)
        for dest in removes:
            dest.unlink(missing_ok=True)
    except BaseException:
        had = {_key(d) for d, _ in kept}
        for dest in placed:
            if _key(dest) not in had:
                dest.unlink(missing_ok=True)
        for dest, old in kept:
            if os.path.lexists(dest) and os.path.samestat(os.lstat(dest), os.lstat(old)):
                old.unlink()      # never replaced: renaming a hard link onto itself does nothing
            else:
                os.replace(old, dest)
        raise
    for _, old in kept:
        old.unlink(missing_ok=True)


class OutputSet:
    """The files one run writes, put in place together (see the module's text).

    Parameters
    ----------
    inputs : sequence of path-like or None
        The run's input files (None entries are skipped); no output may be one of them.
    """

    def __init__(self, inputs: Sequence = ()):
        self._inputs = []
        for p in inputs:
            if p is None:
                continue
            p = pathlib.Path(p)
            try:
                st = os.stat(p)
            except OSError:      # a missing input is its reader's error to report
                continue
            self._inputs.append((p, st.st_dev, st.st_ino))
        self._members: dict[str, _Member] = {}
        self._stale: dict[str, pathlib.Path] = {}
        self._made: list[pathlib.Path] = []
        #: the finalizers of every temporary made for the set (registered before the file
        #: exists): discard() calls them all, whatever point an interrupt came at
        self.temporaries: list = []
        self.state = "open"
        #: what the run left: the destinations written (commit) or the partial tables
        self.written: list[pathlib.Path] = []
        self.partial: list[pathlib.Path] = []
        self.removed: list[pathlib.Path] = []

    # ---- claiming -------------------------------------------------------------------
    def _check(self, p: pathlib.Path) -> None:
        if p.is_dir():
            raise OutputError(f"{p} is a folder: give a file name for the output")
        folder = _folder(p)
        if not folder.is_dir():
            raise OutputError(f"{p}: its folder {folder} does not exist: create it, or give an "
                              "output path in an existing folder")
        if not os.access(folder, os.W_OK | os.X_OK):
            raise OutputError(f"{p}: its folder {folder} is not writable (permission denied): "
                              "give an output path in a folder you can write to")
        for cand in (p, partial_path(p)):
            try:
                st = os.stat(cand)
            except OSError:
                continue
            for q, dev, ino in self._inputs:
                if (st.st_dev, st.st_ino) != (dev, ino):
                    continue
                if _key(cand) == _key(q):
                    how = "the same path"
                elif os.path.islink(cand) or os.path.islink(q):
                    how = "a symbolic link to the same file"
                else:
                    how = "the same file under another name: a hard link"
                what = "output" if cand is p else "partial output of"
                raise OutputError(f"the {what} {p} is the input {q} ({how}): writing it would "
                                  "replace the recording; give another output name")

    def claim(self, path, *, produced: bool = True) -> pathlib.Path:
        """Make ``path`` a file of this run, checked now (before the run): not an input
        (by device and inode), not a folder, in a writable folder, not named twice. With
        ``produced=False`` the file belongs to the set but this run does not write it: an
        existing one (a previous run's) is removed at :meth:`commit`. Temporaries of it
        left by killed processes are removed."""
        p = pathlib.Path(path)
        key = _key(p)
        if key in self._members or key in self._stale:
            if produced and key in self._members:
                return p
            raise OutputError(f"{p} is named twice among the outputs of this run")
        self._check(p)
        sweep_temporaries(p)
        if produced:
            self._members[key] = _Member(p)
        else:
            self._stale[key] = p
        return p

    def claim_folder(self, folder) -> pathlib.Path:
        """A folder for outputs (figures), made now if missing (and removed again if the
        run writes nothing into it)."""
        folder = pathlib.Path(folder)
        if folder.exists() and not folder.is_dir():
            raise OutputError(f"{folder} is a file: give a folder for the figures")
        if not folder.exists():
            top = folder
            while not top.parent.exists() and top.parent != top:
                top = top.parent
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise OutputError(f"{folder}: cannot make the folder ({exc.strerror}): give a "
                                  "folder you can write to") from None
            self._made.append(top)
        if not os.access(folder, os.W_OK | os.X_OK):
            raise OutputError(f"{folder} is not writable (permission denied): give a folder you "
                              "can write to")
        return folder

    def _member(self, path) -> _Member:
        p = self.claim(path)
        m = self._members[_key(p)]
        if m.writer is not None or m.finished:
            raise OutputError(f"{p} is written twice in this run")
        return m

    # ---- writing --------------------------------------------------------------------
    def table(self, path, names, dtypes=None, **kwargs) -> TableWriter:
        """A :class:`~gfins_fmi.io.table_writer.TableWriter` of this set: its
        ``commit()`` finishes the table; the set renames it with the others."""
        if self.state != "open":
            raise ValueError(f"the outputs are already {self.state}")
        m = self._member(path)
        m.writer = TableWriter(m.dest, names, dtypes, output_set=self, **kwargs)
        m.format = m.writer.format
        return m.writer

    def finished(self, writer: TableWriter) -> None:
        """Called by a table of the set when it is complete (its ``commit``)."""
        m = self._members[_key(writer.path)]
        m.tmp = writer.temporary
        m.remove = weakref.finalize(self, remove_temporary, m.tmp)
        self.temporaries.append(m.remove)
        writer.release()

    def write_table(self, path, names, columns, dtypes=None, **kwargs) -> None:
        """A whole table at once (see :meth:`table`)."""
        with self.table(path, names, dtypes, **kwargs) as w:
            w.write(columns)
            w.commit()

    def file(self, path) -> pathlib.Path:
        """The temporary to write ``path``'s content to (any writer: JSON, text, a figure;
        the suffix is kept, so matplotlib infers the format); renamed at commit."""
        if self.state != "open":
            raise ValueError(f"the outputs are already {self.state}")
        m = self._member(path)
        m.tmp, m.remove = temporary_beside(m.dest, self, self.temporaries)
        return m.tmp

    def write_text(self, path, text: str) -> None:
        """A text file of the set (UTF-8)."""
        self.file(path).write_text(text, encoding="utf-8")

    def drop(self, path) -> None:
        """A file of the set that the run will not finish after all (a stage that failed
        half way through writing it): what was written is removed, and at :meth:`commit`
        the file counts as one this run did not write (an earlier one is removed)."""
        m = self._members.get(_key(pathlib.Path(path)))
        if m is None:
            return
        if m.writer is not None:
            m.writer.discard()
            m.writer = None
        if m.remove is not None:
            m.remove()
        m.tmp = m.remove = None

    # ---- ending ---------------------------------------------------------------------
    def _folders(self):
        return [_folder(m.dest) for m in self._members.values()] + \
               [_folder(p) for p in self._stale.values()]

    def commit(self) -> list[pathlib.Path]:
        """Put the whole set in place: every file written is renamed to its destination,
        the set's files this run did not write and earlier partial files are removed;
        all of it or, on a failure, none. Returns the destinations written."""
        if self.state != "open":
            raise ValueError(f"the outputs are already {self.state}")
        open_tables = [m.dest for m in self._members.values() if m.writer is not None and not m.finished]
        if open_tables:
            raise ValueError(f"{_names(open_tables)}: not finished (TableWriter.commit) before "
                             "the set's commit")
        moves = [(m.tmp, m.dest) for m in self._members.values() if m.finished]
        stale = [m.dest for m in self._members.values() if not m.finished] + list(self._stale.values())
        removes = [p for p in stale if os.path.lexists(p)]
        removes += [partial_path(p) for p in [m.dest for m in self._members.values()] + stale
                    if os.path.lexists(partial_path(p))]
        with signals_held(), _folders_locked(self._folders()):
            _replace_all(moves, removes)
            for remove in self.temporaries:
                remove.detach()
            self.state = "committed"
        self.written = [d for _, d in moves]
        self.removed = [p for p in removes]
        self._drop_made_folders()
        return self.written

    def keep_partial(self, reason: str) -> list[pathlib.Path]:
        """The run failed after writing some rows: every table of the set goes to its
        partial name (``sol.csv`` -> ``sol.partial.csv``), stamped with ``reason`` (where
        and why the run stopped: the CSV's first line), and so does every other file
        already finished (the run's configuration: ``sol.config.partial.json``), while the
        destinations stay as they were. Nothing is kept when no table has a row. Returns
        the partial files."""
        if self.state != "open":
            return []
        tables = [m for m in self._members.values() if m.writer is not None]
        if not any(m.writer.rows for m in tables):
            self.discard()
            return []
        for m in tables:
            if not m.finished:
                m.writer.finish()
                self.finished(m.writer)
            mark_partial(m.tmp, m.format, reason)
        tables += [m for m in self._members.values() if m.writer is None and m.finished]
        moves = [(m.tmp, partial_path(m.dest)) for m in tables]
        kept = {_key(d) for _, d in moves}
        others = [m.dest for m in self._members.values()] + list(self._stale.values())
        removes = [partial_path(p) for p in others
                   if _key(partial_path(p)) not in kept and os.path.lexists(partial_path(p))]
        with signals_held(), _folders_locked(self._folders()):
            _replace_all(moves, removes)
            for m in tables:
                m.remove.detach()
            self.state = "partial"
        self.partial = [d for _, d in moves]
        self._discard_files()
        self._drop_made_folders()
        return self.partial

    def _discard_files(self) -> None:
        for m in self._members.values():
            if m.writer is not None and not m.finished:
                m.writer.discard()
        for remove in self.temporaries:   # every other temporary (a removed one is no-op)
            remove()

    def _drop_made_folders(self) -> None:
        for top in reversed(self._made):
            for folder in sorted((p for p in [top, *top.rglob("*")] if p.is_dir()),
                                 key=lambda p: len(p.parts), reverse=True):
                with contextlib.suppress(OSError):
                    folder.rmdir()           # only empty ones
        self._made = []

    def discard(self) -> None:
        """Drop everything written; every destination stays as it was."""
        if self.state == "open":
            self.state = "discarded"
            self._discard_files()
            self._drop_made_folders()

    def outcome(self) -> str:
        """What the run left, for messages: the destinations left as they were, the
        partial files."""
        dests = [m.dest for m in self._members.values()]
        if self.state == "committed":
            return f"written: {_names(self.written)}" if self.written else ""
        there = [d for d in dests if d.exists()]
        missing = [d for d in dests if not d.exists()]
        left = "; ".join(x for x in (
            f"{_names(there)} left as {'it was' if len(there) == 1 else 'they were'}" if there else "",
            f"{_names(missing)} not written" if missing else "") if x)
        if self.state == "partial":
            return f"the rows written before it are in {_names(self.partial)}; {left}"
        return left

    def __enter__(self) -> "OutputSet":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self.state != "open":
            return
        if exc is None or isinstance(exc, KeyboardInterrupt) or not isinstance(exc, Exception):
            self.discard()
        else:
            try:
                self.keep_partial(f"stopped by an error: {exc}")
            except Exception:     # already failing (a full disk?): drop what was written
                self.discard()
        if exc is not None and (self.state == "partial" or isinstance(exc, KeyboardInterrupt)):
            # for the message: the partial files, or (an interrupt) what was left as it was
            with contextlib.suppress(AttributeError, TypeError):
                exc.gfins_outputs = self.outcome()
