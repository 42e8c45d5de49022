"""The Rauch–Tung–Striebel smoother with flat memory: :class:`StreamingSmoother`.

:meth:`IntegratedSolution.smooth <gfins_fmi.estimation.solution.IntegratedSolution.smooth>`
holds the whole forward solution and every epoch of the filter in memory (~4 kB per epoch
with 15 states, ~7.5 kB with 21; the epochs spill to memory-mapped files beyond 1 GiB, whose
touched pages still count in the resident set). This smoother keeps them on disk instead
and works in three passes of bounded size:

1. forward, a piece of the record at a time (:meth:`StreamingSmoother.run`): the
   navigator writes each piece's epochs into a buffer the size of the piece, which is
   appended to files (the last epoch stays in memory: an update at its time may still
   join it), and the rows the smoother corrects (time, attitude, velocity, position,
   sensor estimates, standstill) are appended to a file of rows;
2. backward, a block of epochs at a time from the end (:meth:`StreamingSmoother.smooth`):
   ``gf_ins_smooth_block`` from the smoothed error and covariance of the epoch after the
   block; the smoothed errors and the 1-sigma at the epochs written to files;
3. forward again, a chunk of rows at a time (:meth:`StreamingSmoother.solutions`):
   ``gf_ins_smooth_apply`` over the epochs that bracket the chunk, the 1-sigma
   interpolated between them.

The result is :func:`~gfins_fmi.estimation.solution.smooth`'s, bit for bit (one recursion
in C; a row between two epochs reads only those two). Disk: 8 (1 + 10 + n + n(n+1) + n²)
+ 8 (n + 9) bytes per epoch (n states; 7.7 kB with 21) and 224 bytes per row, in a
temporary folder removed by :meth:`~StreamingSmoother.close` (or when the smoother is
collected, or at exit).

Example
-------
>>> with StreamingSmoother(IntegratedNavigator(cfg, init)) as sm:   # doctest: +SKIP
...     for piece in pieces:                  # ImuRecords in time order
...         sm.run(piece, gnss_of(piece))     # the forward solution of the piece
...     sm.smooth()
...     for rows in sm.solutions(50_000):     # SmoothedSolution chunks in time order
...         write(rows)
"""
from __future__ import annotations

import pathlib
import shutil
import tempfile
import weakref
from typing import Iterator, Optional

import numpy as np

from gfins_fmi._lib import check_status, ffi, lib, ptr
from gfins_fmi.estimation.config import N_SENSORS
from gfins_fmi.estimation.measurements import INNOVATION_DTYPE
from gfins_fmi.estimation.navigator import IntegratedNavigator
from gfins_fmi.estimation.solution import IntegratedSolution, SmoothedSolution, epoch_std, smoothing_layout
from gfins_fmi.io.raw_floats import append_floats, read_floats

__all__ = ["StreamingSmoother", "epoch_bytes", "ROW_BYTES"]

#: the columns of the file of forward rows: t, q_bn (4), v (3), lat, lon, h, sensors, standstill
_ROW_WIDTH = 1 + 4 + 3 + 3 + N_SENSORS + 1
#: bytes of disk per forward row
ROW_BYTES = 8 * _ROW_WIDTH
#: smoothed errors and 1-sigma are written for each epoch too: n + 9 numbers


def _epoch_widths(n: int) -> dict:
    tri = n * (n + 1) // 2
    return {"t_s": 1, "nav": 10, "dx": n, "P_prior": tri, "P_post": tri, "Phi": n * n}


def epoch_bytes(n_states: int) -> int:
    """Bytes of disk per epoch with ``n_states`` states: the forward epoch (time, nominal,
    correction, prior and posterior covariance, transition) and its smoothed error and
    1-sigma."""
    return 8 * (sum(_epoch_widths(n_states).values()) + n_states + 9)


def _remove(folder: pathlib.Path, made: bool) -> None:
    if made:
        shutil.rmtree(folder, ignore_errors=True)


class _EpochSink:
    """The forward pass's epochs: a buffer the size of one run() call behind a
    ``gf_ins_epochs`` struct, appended to one file per field after each call; its last
    epoch stays in the buffer (a measurement update at its time joins it in the next
    call), written by :meth:`close`."""

    def __init__(self, n_states: int, folder: pathlib.Path):
        self.n = n_states
        self.widths = _epoch_widths(n_states)
        self.files = {k: open(folder / f"epochs_{k}.f8", "wb") for k in self.widths}
        self.arrays: dict = {}
        self.c = ffi.new("gf_ins_epochs *")
        self.c.count = 0
        self.written = 0      # epochs in the files
        self.started = False
        self.closed = False
        # the C struct wants a sensors row too: one row, never read back (rows hold them)
        self._sensors = None

    def _allocate(self, capacity: int) -> None:
        keep = int(self.c.count)
        new = {k: np.empty((capacity, w)) for k, w in self.widths.items()}
        for k, a in self.arrays.items():
            new[k][:keep] = a[:keep]
        self.arrays = new
        sens = np.empty((capacity, N_SENSORS))
        if self._sensors is not None:
            sens[:keep] = self._sensors[:keep]
        self._sensors = sens
        self.c.capacity = capacity
        for k in self.widths:
            setattr(self.c, k, ptr(self.arrays[k], self.arrays[k].size))
        self.c.sensors = ptr(self._sensors, self._sensors.size)

    def reserve(self, f, room: int):
        """The struct, with room for ``room`` more epochs; the first call records the
        filter's state as the first epoch (``gf_ins_epochs_begin``)."""
        if self.closed:
            raise ValueError("the forward pass is over (smooth() was called): no more runs")
        need = int(self.c.count) + int(room) + (0 if self.started else 1)
        if not self.arrays or need > int(self.c.capacity):
            self._allocate(need)
        if not self.started:
            if int(f.n_imu) != 0:
                raise ValueError("the streaming smoother starts with the navigator: give it a navigator "
                                 "that has not run yet")
            check_status(lib.gf_ins_epochs_begin(f, self.c), "gf_ins_epochs_begin")
            self.started = True
        return self.c

    def _write(self, lo: int, hi: int) -> None:
        for k, fh in self.files.items():
            append_floats(fh, self.arrays[k][lo:hi])
        self.written += hi - lo

    def flush(self) -> None:
        """After a run() call: every epoch but the last to the files."""
        count = int(self.c.count)
        if count > 1:
            self._write(0, count - 1)
            for a in (*self.arrays.values(), self._sensors):
                a[0] = a[count - 1]
            self.c.count = 1

    def close(self) -> None:
        """The end of the forward pass: the last epoch too; the files closed."""
        if self.closed:
            return
        if int(self.c.count):
            self._write(0, int(self.c.count))
            self.c.count = 0
        for fh in self.files.values():
            fh.close()
        self.arrays, self._sensors, self.closed = {}, None, True


class StreamingSmoother:
    """The RTS smoother of an :class:`IntegratedNavigator` with memory that does not grow
    with the record (see the module's text).

    Parameters
    ----------
    navigator : IntegratedNavigator
        A navigator that has not run yet; :meth:`run` runs it.
    folder : path-like, optional
        Where the smoother's temporary folder is made (default: the system's temporary
        folder). It needs :func:`epoch_bytes` per epoch and :data:`ROW_BYTES` per row
        (about 0.47 GB per hour at 200 Hz, 21 states and a 0.1 s propagation interval).
    block_epochs : int
        Epochs per backward block (memory ~ 8 (n(n+1) + n²) bytes each: 16 MB for 2048
        epochs of 21 states).

    Attributes
    ----------
    folder : pathlib.Path
        The temporary folder (removed by :meth:`close`).
    n_epochs, n_rows : int
        Epochs and rows stored so far.
    """

    def __init__(self, navigator: IntegratedNavigator, folder=None, *, block_epochs: int = 2048):
        if not isinstance(navigator, IntegratedNavigator):
            raise TypeError("navigator must be an IntegratedNavigator")
        if isinstance(block_epochs, bool) or not isinstance(block_epochs, (int, np.integer)) or block_epochs < 1:
            raise ValueError(f"block_epochs must be an integer >= 1; got {block_epochs!r}")
        if folder is not None and not pathlib.Path(folder).is_dir():
            raise ValueError(f"folder {folder} is not a folder: give an existing folder for the smoother's "
                             "temporary files")
        self.navigator = navigator
        self.config = navigator.config
        self.n_states = navigator.n_states
        self.block_epochs = int(block_epochs)
        self.folder = pathlib.Path(tempfile.mkdtemp(prefix="gfins_smoother_", dir=folder))
        self._cleanup = weakref.finalize(self, _remove, self.folder, True)
        self._sink = _EpochSink(self.n_states, self.folder)
        self._rows = open(self.folder / "rows.f8", "wb")
        self.n_rows = 0
        self._smoothed = False

    @property
    def n_epochs(self) -> int:
        return self._sink.written + int(self._sink.c.count)

    @property
    def bytes_on_disk(self) -> int:
        """Bytes of the smoother's files so far."""
        return sum(p.stat().st_size for p in self.folder.iterdir() if p.is_file())

    # ---- 1. forward -----------------------------------------------------------------
    def run(self, imu, gnss=None, baro=None, odometer=None, **kwargs) -> IntegratedSolution:
        """The forward pass over the next piece of the record, its epochs and rows stored.

        Parameters
        ----------
        imu, gnss, baro, odometer, **kwargs
            As :meth:`IntegratedNavigator.run` (not ``smoother``): the pieces in time
            order, each with the measurements of its own span (after the filter's time,
            up to the piece's last sample).

        Returns
        -------
        IntegratedSolution
            The piece's forward solution (``epochs`` None: they are on disk).

        Raises
        ------
        FilterError
            As :meth:`IntegratedNavigator.run`; it ends the forward pass (the solution
            before it cannot be smoothed here).
        """
        if self._smoothed or self._rows.closed:
            raise ValueError("smooth() was called: the forward pass is over")
        if kwargs.get("smoother"):
            raise ValueError("smoother=True holds the epochs in memory; the StreamingSmoother stores them")
        try:
            sol = self.navigator.run(imu, gnss, baro, odometer, epoch_sink=self._sink, **kwargs)
        except Exception:
            self._rows.close()
            raise
        self._append_rows(sol)
        return sol

    def _append_rows(self, sol: IntegratedSolution) -> None:
        n = len(sol)
        if n == 0:
            return
        rows = np.empty((n, _ROW_WIDTH))
        rows[:, 0] = sol.t_s
        rows[:, 1:5] = sol.q_bn
        rows[:, 5:8] = sol.v_n_m_s
        rows[:, 8], rows[:, 9], rows[:, 10] = sol.lat_rad, sol.lon_rad, sol.h_m
        rows[:, 11:11 + N_SENSORS] = sol.sensors
        rows[:, -1] = sol.standstill
        append_floats(self._rows, rows)
        self.n_rows += n

    # ---- 2. backward ----------------------------------------------------------------
    def _read(self, name: str, width: int, lo: int, hi: int) -> np.ndarray:
        with open(self.folder / name, "rb") as fh:
            fh.seek(8 * width * lo)
            a = read_floats(fh, width * (hi - lo))
        if len(a) != width * (hi - lo):
            raise OSError(f"{self.folder / name}: {len(a) // width} of {hi - lo} rows read from row {lo} "
                          "(the smoother's file was cut: was the folder cleaned while it ran?)")
        return a.reshape(hi - lo, width)

    def smooth(self, progress: bool = False) -> None:
        """The backward pass, a block of ``block_epochs`` at a time from the end; ends the
        forward pass.

        Parameters
        ----------
        progress : bool
            A bar over the epochs (tqdm).

        Raises
        ------
        ValueError
            Nothing run yet, a failed forward pass, or called twice.
        RuntimeError
            ``gf_ins_smooth_block`` refused a block (a prior covariance not positive
            definite), with the epochs named.
        """
        if self._smoothed:
            raise ValueError("smooth() was already called")
        if self._rows.closed:
            raise ValueError("the forward pass failed: there is nothing whole to smooth")
        self._sink.close()
        self._rows.close()
        E, n = self.n_epochs, self.n_states
        if E == 0 or self.n_rows == 0:
            raise ValueError("no epochs: run() the record before smooth()")
        tri = n * (n + 1) // 2
        w = self._sink.widths
        xs_f = open(self.folder / "xs.f8", "wb")
        std_f = open(self.folder / "std.f8", "wb")
        bar = None
        if progress:
            from tqdm import tqdm   # lazy: tqdm only with a progress bar
            bar = tqdm(total=E, unit="epoch", unit_scale=True, desc="smoother, backward")
        try:
            xs_f.truncate(8 * n * E)
            std_f.truncate(8 * 9 * E)
            # the record's last epoch: x^s = 0, P^s = P+ (gf_ins_smooth's start)
            x_next = np.zeros(n)
            P_next = self._read("epochs_P_post.f8", tri, E - 1, E)[0]
            nav_last = self._read("epochs_nav.f8", 10, E - 1, E)
            self._put(xs_f, x_next[None], E - 1, n)
            self._put(std_f, epoch_std(P_next[None], nav_last, n), E - 1, 9)
            if bar:
                bar.update(1)
            b = E - 1
            while b > 0:
                a = max(0, b - self.block_epochs)
                m = b - a + 1
                blk = {k: np.ascontiguousarray(self._read(f"epochs_{k}.f8", w[k], a, b + 1))
                       for k in ("t_s", "dx", "P_prior", "P_post", "Phi")}
                xs = np.empty((m, n))
                Ps = np.empty((m, tri))
                xs[-1], Ps[-1] = x_next, P_next
                c = ffi.new("gf_ins_epochs *")
                c.capacity = c.count = m
                for k, arr in blk.items():
                    setattr(c, k, ptr(arr, arr.size))
                st = lib.gf_ins_smooth_block(n, c, ptr(xs, xs.size), ptr(Ps, Ps.size))
                check_status(st, f"gf_ins_smooth_block (epochs {a} to {b} of {E}: a prior covariance is not "
                             "positive definite)")
                nav = self._read("epochs_nav.f8", 10, a, b)
                self._put(xs_f, xs[:-1], a, n)
                self._put(std_f, epoch_std(Ps[:-1], nav, n), a, 9)
                x_next, P_next = xs[0].copy(), Ps[0].copy()
                if bar:
                    bar.update(m - 1)
                b = a
        finally:
            xs_f.close()
            std_f.close()
            if bar:
                bar.close()
        self._smoothed = True

    @staticmethod
    def _put(fh, arr: np.ndarray, row: int, width: int) -> None:
        fh.seek(8 * width * row)
        append_floats(fh, arr)

    # ---- 3. the smoothed rows ---------------------------------------------------------
    def solutions(self, rows: int = 48_000, progress: bool = False) -> Iterator[SmoothedSolution]:
        """The smoothed solution a chunk of rows at a time, in time order (after
        :meth:`smooth`).

        Parameters
        ----------
        rows : int
            Rows per chunk (the memory of the pass: ~1 kB a row).
        progress : bool
            A bar over the rows (tqdm).

        Yields
        ------
        SmoothedSolution
            The rows of :func:`~gfins_fmi.estimation.solution.smooth`'s result, bit for
            bit (``innovations`` empty: the forward solution's log is the record of the
            updates; ``epochs``, ``epoch_t_s`` and ``epoch_std`` None).
        """
        if not self._smoothed:
            raise ValueError("call smooth() before solutions()")
        if isinstance(rows, bool) or not isinstance(rows, (int, np.integer)) or rows < 1:
            raise ValueError(f"rows must be an integer >= 1; got {rows!r}")
        n, E = self.n_states, self.n_epochs
        f = smoothing_layout(self.config, n)
        files = {k: open(self.folder / name, "rb") for k, name in
                 (("t", "epochs_t_s.f8"), ("xs", "xs.f8"), ("dx", "epochs_dx.f8"), ("std", "std.f8"))}
        widths = {"t": 1, "xs": n, "dx": n, "std": 9}
        win = {k: np.empty((0, wd)) for k, wd in widths.items()}
        read = 0          # epochs read into the window so far
        no_innovations = np.zeros(0, INNOVATION_DTYPE)
        bar = None
        if progress:
            from tqdm import tqdm   # lazy: tqdm only with a progress bar
            bar = tqdm(total=self.n_rows, unit="row", unit_scale=True, desc="smoother, applied")
        try:
            with open(self.folder / "rows.f8", "rb") as rf:
                while True:
                    blk = read_floats(rf, rows * _ROW_WIDTH)
                    if len(blk) == 0:
                        return
                    blk = blk.reshape(-1, _ROW_WIDTH)
                    t = np.ascontiguousarray(blk[:, 0])
                    t_last = float(t[-1])
                    # the window: from the last epoch at or before the chunk's first row
                    # (earlier ones change nothing: the C walk and np.interp pass them) to
                    # the first epoch after its last row (1 ms: beyond the C core's 1e-9 s)
                    et = win["t"][:, 0]
                    drop = max(0, int(np.searchsorted(et, t[0], side="right")) - 1)
                    win = {k: v[drop:] for k, v in win.items()}
                    while read < E and (len(win["t"]) == 0 or win["t"][-1, 0] <= t_last + 1e-3):
                        m = min(self.block_epochs, E - read)
                        new = {k: read_floats(files[k], m * widths[k]) for k in widths}
                        if any(len(v) != m * widths[k] for k, v in new.items()):
                            raise OSError(f"{self.folder}: the smoother's epoch files were cut at epoch {read}")
                        new = {k: v.reshape(m, widths[k]) for k, v in new.items()}
                        win = {k: np.concatenate([win[k], new[k]]) for k in widths}
                        read += m
                    yield self._apply(f, win, blk, t, no_innovations)
                    if bar:
                        bar.update(len(t))
        finally:
            for fh in files.values():
                fh.close()
            if bar:
                bar.close()

    def _apply(self, f, win: dict, blk: np.ndarray, t: np.ndarray, no_innovations) -> SmoothedSolution:
        n = self.n_states
        nr = len(t)
        q = np.ascontiguousarray(blk[:, 1:5])
        v = np.ascontiguousarray(blk[:, 5:8])
        pos = np.ascontiguousarray(blk[:, 8:11])
        sens = np.ascontiguousarray(blk[:, 11:11 + N_SENSORS])
        et = np.ascontiguousarray(win["t"][:, 0])
        xs = np.ascontiguousarray(win["xs"])
        dx = np.ascontiguousarray(win["dx"])
        E = len(et)
        check_status(lib.gf_ins_smooth_apply(f, E, ptr(et, E), ptr(xs, E * n), ptr(dx, E * n), nr,
                                             ptr(t, nr), ptr(q, 4 * nr), ptr(v, 3 * nr),
                                             ptr(pos, 3 * nr), ptr(sens, N_SENSORS * nr)),
                     "gf_ins_smooth_apply")
        estd = win["std"]
        std = np.column_stack([np.interp(t, et, estd[:, i]) for i in range(9)])
        return SmoothedSolution(t, q, v, pos[:, 0].copy(), pos[:, 1].copy(), pos[:, 2].copy(), std, sens,
                                blk[:, -1] != 0.0, no_innovations, self.config)

    # ---- the end ----------------------------------------------------------------------
    def close(self) -> None:
        """Remove the temporary folder (also when the smoother is collected, or at exit)."""
        for fh in self._sink.files.values():
            fh.close()
        self._rows.close()
        self._cleanup()

    def __enter__(self) -> "StreamingSmoother":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
