"""``gfins integrate --smooth`` in chunks: the Rauch–Tung–Striebel smoother of a run read,
filtered and written a chunk at a time (:mod:`gfins_fmi.cli.integrate_stream`), with
memory that does not grow with the record
(:class:`~gfins_fmi.estimation.smoother_stream.StreamingSmoother`): the forward pass
stores its epochs and rows in a temporary folder beside the smoothed output
(``OUT.smoothed.<pid>-<random>.tmp.csv.d``; :func:`disk_note` says how much), the
backward pass runs over them in blocks from the end, and the smoothed solution is written
and scored a chunk at a time. The folder is removed on success, failure or Ctrl-C (a run
killed outright leaves it to the next run with the same output, which removes it).
The result is the whole-record smoother's, bit for bit.
"""
from __future__ import annotations

import pathlib
import sys

from gfins_fmi.cli.integrate_stream import Scores, solution_table
from gfins_fmi.cli.kfgins_config import KFGINS_COLUMNS, KFGINS_TEXT, kfgins_nav_columns
from gfins_fmi.estimation.smoother_stream import ROW_BYTES, StreamingSmoother, epoch_bytes
from gfins_fmi.io.temporaries import temporary_folder_beside

__all__ = ["open_smoother", "write_smoothed", "smoothed_path", "smoothed_table", "disk_note", "SMOOTH_BLOCK_EPOCHS"]

#: epochs per block of the backward pass (~16 MB of covariances and transitions with 21 states)
SMOOTH_BLOCK_EPOCHS = 2048


def smoothed_path(output: pathlib.Path) -> pathlib.Path:
    """Where the smoothed solution goes: beside the forward one, in its format
    (``OUT.smoothed.parquet`` for ``OUT.parquet``; with --kfgins-config
    ``KF_GINS_Navresult.smoothed.nav``, KF-GINS's navigation result)."""
    return output.with_suffix(".smoothed" + output.suffix)


def smoothed_table(sm, kfgins: bool, all_states: bool) -> tuple[list, list, dict]:
    """The smoothed solution's column names, columns and writer keywords: our table, or
    with --kfgins-config KF-GINS's ``.nav`` columns and number format (its plotting
    scripts read it as they read the forward one)."""
    if kfgins:
        return [f"c{i}" for i in range(KFGINS_COLUMNS["nav"])], kfgins_nav_columns(sm), KFGINS_TEXT
    names, cols = solution_table(sm, all_states)
    return names, cols, {}


def disk_note(n_states: int, propagation_interval_s: float, rate_hz: float = 200.0) -> str:
    """The smoother's disk use per hour of record, in words: epochs at the propagation
    interval (plus those of measurements between its instants) and rows at ``rate_hz``."""
    per_epoch = epoch_bytes(n_states)
    epochs_h = 3600.0 / propagation_interval_s if propagation_interval_s > 0 else 3600.0 * rate_hz
    rows_h = 3600.0 * rate_hz
    total = epochs_h * per_epoch + rows_h * ROW_BYTES
    return (f"{per_epoch / 1e3:.1f} kB per epoch ({n_states} states) x {epochs_h:.0f} epochs per hour "
            f"+ {ROW_BYTES} B per row x {rows_h:.0f} rows per hour = {total / 1e9:.2f} GB per hour of record "
            "(more with measurements between the propagation instants)")


def open_smoother(outs, nav, sm_path: pathlib.Path, progress: bool = False):
    """A StreamingSmoother of ``nav`` in a temporary folder beside ``sm_path`` (the
    outputs' disk), and the function that removes the folder (call it when done; it also
    runs when ``outs`` is collected or at exit). ``progress``: say where and how much."""
    folder, remove = temporary_folder_beside(sm_path, outs)
    if progress:
        print(f"gfins integrate: the smoother's epochs and rows go to {folder} (removed at the end): "
              f"{disk_note(nav.n_states, nav.config.propagation_interval_s)}", file=sys.stderr, flush=True)
    try:
        return StreamingSmoother(nav, folder, block_epochs=SMOOTH_BLOCK_EPOCHS), remove
    except BaseException:
        remove()
        raise


def write_smoothed(outs, smoother: StreamingSmoother, sm_path: pathlib.Path, scores: Scores,
                   all_states: bool, rows: int, progress: bool, kfgins: bool = False) -> int:
    """The backward pass, then the smoothed solution written to ``sm_path``
    (:func:`smoothed_table`: our table, or KF-GINS's ``.nav`` with ``kfgins``) and scored
    a chunk of ``rows`` at a time. Returns the rows written. On a failure the smoothed
    table is dropped from the set (the forward solution stays)."""
    writer = None
    n = 0
    try:
        smoother.smooth(progress=progress)
        for sm in smoother.solutions(rows, progress=progress):
            names, cols, kw = smoothed_table(sm, kfgins, all_states)
            if writer is None:
                writer = outs.table(sm_path, names, **kw)
            writer.write(cols)
            scores.add(sm)
            n += len(sm)
        if writer is not None:
            writer.commit()
    except BaseException:
        outs.drop(sm_path)
        raise
    return n
