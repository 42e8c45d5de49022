"""The names of a run's transient files, said once: the temporaries an output is written
to beside its destination (``<stem>.<pid>-<random>.tmp<suffix>``), their removal (at once,
when their owner is collected or the interpreter exits, and by a later run when the
process that made them was killed outright), and the partial tables a failed run keeps
(``<stem>.partial<suffix>``, stamped with where and why it stopped). Used by
:class:`~gfins_fmi.io.table_writer.TableWriter` and
:class:`~gfins_fmi.io.output_set.OutputSet` (docs/io.md, "A run's outputs")."""
from __future__ import annotations

import os
import pathlib
import re
import secrets
import shutil
import weakref
import zipfile

from gfins_fmi.io.tables import pyarrow_module

__all__ = ["PARTIAL_PREFIX", "temporary_beside", "temporary_folder_beside", "temporary_pattern", "remove_temporary",
           "sweep_temporaries", "partial_path", "mark_partial"]

#: bytes copied at a time when stamping a partial CSV table
_COPY_BYTES = 16 << 20

#: the first line of a partial CSV table (and the start of the reason kept in the
#: metadata of a partial Parquet file or the archive comment of a partial npz file)
PARTIAL_PREFIX = "partial: "


def _name_parts(path: pathlib.Path) -> tuple[str, str]:
    """(stem, suffix) of a file name: ``sol.csv`` -> (``sol``, ``.csv``); ``out`` ->
    (``out``, ``""``)."""
    return path.stem, path.suffix


def remove_temporary(tmp: pathlib.Path) -> None:
    """A temporary output and its side folder (npz), where they exist."""
    tmp.unlink(missing_ok=True)
    side = pathlib.Path(str(tmp) + ".d")
    if side.exists():
        shutil.rmtree(side, ignore_errors=True)


def temporary_pattern(path: pathlib.Path) -> re.Pattern:
    """The names of the temporaries of ``path``: ``<stem>.<pid>-<8 hex>.tmp<suffix>``."""
    stem, suffix = _name_parts(path)
    return re.compile(re.escape(stem) + r"\.(\d+)-[0-9a-f]{8}\.tmp" + re.escape(suffix) + r"(\.d)?$")


def temporary_beside(path: pathlib.Path, owner, registry: list | None = None
                     ) -> tuple[pathlib.Path, weakref.finalize]:
    """A new empty file beside ``path`` (same folder, so the final rename stays on one
    file system), ``<stem>.<pid>-<random>.tmp<suffix>`` (the suffix kept, so that a writer
    that infers the format from the name, such as matplotlib's, writes the right one),
    created with the process's umask like any output, and the finalizer that removes it.
    The finalizer is registered before the file exists: a Ctrl-C at any point after (even
    before the caller has entered its ``with`` block) leaves no temporary file once
    ``owner`` is collected or the interpreter exits; a commit detaches it. The process id
    in the name lets a later run remove what a killed one left (:func:`sweep_temporaries`).
    ``registry``: a list the finalizer is appended to before the file exists (an output
    set's, so that it can remove the temporary at once, whatever the point an interrupt
    came at)."""
    stem, suffix = _name_parts(path)
    for _ in range(100):
        tmp = path.with_name(f"{stem}.{os.getpid()}-{secrets.token_hex(4)}.tmp{suffix}")
        remove = weakref.finalize(owner, remove_temporary, tmp)
        if registry is not None:
            registry.append(remove)
        try:
            with open(tmp, "xb"):
                return tmp, remove
        except FileExistsError:
            remove.detach()
    raise FileExistsError(f"{path}: no free temporary name beside it")  # pragma: no cover


def temporary_folder_beside(path: pathlib.Path, owner) -> tuple[pathlib.Path, weakref.finalize]:
    """A new empty folder beside ``path`` for a run's working files (the smoother's epochs
    and rows), ``<stem>.<pid>-<random>.tmp<suffix>.d`` beside its placeholder file (one
    name: :func:`temporary_beside`), and the finalizer that removes both: call it when
    done; it also runs when ``owner`` is collected or the interpreter exits (a Ctrl-C
    included), and a run killed outright leaves them to the next run that claims ``path``
    (:func:`sweep_temporaries`)."""
    tmp, remove = temporary_beside(pathlib.Path(path), owner)
    side = pathlib.Path(str(tmp) + ".d")
    try:
        side.mkdir()
    except BaseException:
        remove()
        raise
    return side, remove


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):   # another user's process, or no way to tell
        return True
    return True


def sweep_temporaries(path: pathlib.Path) -> list[pathlib.Path]:
    """Remove the temporaries of ``path`` left by processes that no longer run (killed
    outright: SIGKILL, a power cut) and return them. A temporary of a running process,
    of this one or of one whose state cannot be known is left alone."""
    folder = path.parent if str(path.parent) else pathlib.Path(".")
    pattern = temporary_pattern(path)
    removed = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        m = pattern.match(name)
        if m and not _alive(int(m.group(1))):
            tmp = folder / name
            if m.group(2):
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


def partial_path(path) -> pathlib.Path:
    """Where the partial table of a failed run goes: ``sol.csv`` -> ``sol.partial.csv``
    (the suffix kept: the same format, readable by the same tools)."""
    path = pathlib.Path(path)
    stem, suffix = _name_parts(path)
    return path.with_name(f"{stem}.partial{suffix}")


def mark_partial(tmp: pathlib.Path, format: str, reason: str) -> None:
    """Stamp a finished table as partial, saying where and why the run stopped: CSV, a
    first line ``# partial: <reason>`` (the file copied once behind it); Parquet, the
    metadata key ``gfins_fmi.partial`` (and the first line of ``gfins_fmi.comments``);
    npz, the archive comment (``zipfile.ZipFile(path).comment``). Readers skip all
    three: the columns are those of the complete table."""
    reason = " ".join(str(reason).split())
    if format == "csv":
        stamped = tmp.with_name(tmp.name + ".stamp")
        try:
            with open(stamped, "xb") as out, open(tmp, "rb") as src:
                out.write(f"# {PARTIAL_PREFIX}{reason}\n".encode("utf-8"))
                shutil.copyfileobj(src, out, _COPY_BYTES)
            os.replace(stamped, tmp)
        finally:
            stamped.unlink(missing_ok=True)
    elif format == "npz":
        with zipfile.ZipFile(tmp, "a") as zf:
            zf.comment = (PARTIAL_PREFIX + reason).encode("utf-8")[:65535]
    else:
        _, pq = pyarrow_module()
        table = pq.read_table(tmp)
        meta = dict(table.schema.metadata or {})
        comments = meta.get(b"gfins_fmi.comments", b"").decode("utf-8")
        meta[b"gfins_fmi.partial"] = reason.encode("utf-8")
        meta[b"gfins_fmi.comments"] = "\n".join(
            [PARTIAL_PREFIX + reason] + ([comments] if comments else [])).encode("utf-8")
        stamped = tmp.with_name(tmp.name + ".stamp")
        try:
            pq.write_table(table.replace_schema_metadata(meta), str(stamped), compression="none",
                           use_dictionary=False)
            os.replace(stamped, tmp)
        finally:
            stamped.unlink(missing_ok=True)
