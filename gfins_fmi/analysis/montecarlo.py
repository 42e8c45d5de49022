"""Monte-Carlo runs of the C core on any ``concurrent.futures.Executor``.

``run(task, n_runs, seed)`` calls ``task(k, rng)`` for k = 0..n_runs-1 with independent
generators (``numpy.random.SeedSequence(seed).spawn``), so results do not depend on the
executor or the number of workers; each task returns a dict of arrays, stacked along a
new first axis. The default executor is a thread pool with one worker per CPU: the C
calls release the GIL (cffi), so threads run the core in parallel. Pass any Executor
(e.g. a process pool, or a cluster's) to run elsewhere; :func:`executor` gives the one a
command asked for: N local threads, or a dask.distributed cluster
(``Client(address).get_executor()``).

What a remote executor receives: the task (pickled with its closure, i.e. the arrays it
captured) and per job the run indices and their generators; it returns the task's
dicts. On a dask cluster the task is scattered once and each worker fetches it once;
other executors (a process pool) get it with every job, and ``batch`` runs go in one job.
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
from typing import Callable, Iterator

import numpy as np

from gfins_fmi._version import __version__

__all__ = ["run", "executor"]


def _batch(task: Callable, ks: list, rngs: list) -> list:
    """Run ``task`` for several runs in one job (executed where the executor runs it)."""
    return [task(k, rng) for k, rng in zip(ks, rngs)]


def _slots(ex: cf.Executor) -> int:
    """Worker threads behind an executor: a dask ClientExecutor's cluster, a pool's
    max_workers; 16 when it does not tell."""
    client = getattr(ex, "_client", None)         # distributed.cfexecutor.ClientExecutor
    if client is not None:
        with contextlib.suppress(Exception):
            return max(1, sum(client.nthreads().values()))
    n = getattr(ex, "_max_workers", None)          # concurrent.futures pools
    return n if isinstance(n, int) and n > 0 else 16


def run(task: Callable[[int, np.random.Generator], dict], n_runs: int, seed: int = 0,
        executor: cf.Executor | None = None, progress: bool = False,
        desc: str = "Monte Carlo", batch: int | None = None) -> dict:
    """Run ``task`` n_runs times; returns {name: array (n_runs, ...)}.

    Parameters
    ----------
    task : callable (k, rng) -> dict of arrays
        Run k with its own generator; must return the same names and shapes every run.
    n_runs : int
    seed : int
        Root of the runs' generators: the same seed gives the same results on any
        executor, with any number of workers and any ``batch``.
    executor : concurrent.futures.Executor, optional
        Default: a thread pool with one worker per CPU, shut down on return.
    progress : bool
        A tqdm bar counting finished runs.
    batch : int, optional
        Runs per submitted job. Default: 1 on a thread pool (nothing is copied);
        otherwise about four jobs per worker thread (a dask executor's cluster, a process
        pool's workers; 16 assumed for an executor that does not tell): few enough that
        scheduling costs nothing (and a process pool, which pickles the task with its
        captured arrays for every job, copies it a few times per worker), enough to
        balance uneven workers.

    Raises
    ------
    ValueError
        n_runs < 1 or batch < 1.
    """
    if isinstance(n_runs, bool) or not isinstance(n_runs, (int, np.integer)) or n_runs < 1:
        raise ValueError(f"n_runs must be an integer >= 1; got {n_runs!r}")
    n_runs = int(n_runs)
    if batch is None:
        batch = 1 if executor is None or isinstance(executor, cf.ThreadPoolExecutor) \
            else -(-n_runs // (4 * _slots(executor)))
    if isinstance(batch, bool) or not isinstance(batch, (int, np.integer)) or batch < 1:
        raise ValueError(f"batch must be an integer >= 1 (runs per job); got {batch!r}")
    seqs = np.random.SeedSequence(seed).spawn(n_runs)
    own = executor is None
    ex = executor or cf.ThreadPoolExecutor(max_workers=os.cpu_count() or 1)
    bar = None
    if progress:
        from tqdm import tqdm   # lazy: tqdm (~25 ms) only with a progress bar
        bar = tqdm(total=n_runs, desc=desc, unit="run")
    results: list = [None] * n_runs
    payload = task
    client = getattr(ex, "_client", None)    # a dask ClientExecutor: ship the task once,
    if client is not None:                   # each worker fetches it once, not per job
        payload = client.scatter(task, hash=False)
    try:
        futures = {}
        for k0 in range(0, n_runs, int(batch)):
            ks = list(range(k0, min(n_runs, k0 + int(batch))))
            rngs = [np.random.default_rng(seqs[k]) for k in ks]
            futures[ex.submit(_batch, payload, ks, rngs)] = ks
        for fut in cf.as_completed(futures):
            ks = futures[fut]
            for k, r in zip(ks, fut.result()):
                results[k] = r
            if bar:
                bar.update(len(ks))
    finally:
        if bar:
            bar.close()
        if own:
            ex.shutdown(cancel_futures=True)
    return {name: np.stack([r[name] for r in results]) for name in results[0]}


def _worker_version() -> str:
    """gfins_fmi's version where this runs (a dask worker)."""
    return __version__


@contextlib.contextmanager
def executor(scheduler: str | None = None, workers: int | None = None,
             timeout_s: float = 30.0) -> Iterator[cf.Executor | None]:
    """The executor a command's Monte Carlo runs on.

    Parameters
    ----------
    scheduler : str, optional
        Address of a dask.distributed scheduler (``tcp://host:8786``): the runs go to
        its workers through ``Client(scheduler).get_executor()``. Every worker must
        import the same gfins_fmi version (checked on connection).
    workers : int, optional
        Without a scheduler: a pool of this many threads on this machine. With a
        scheduler: wait until at least this many workers have joined (up to
        ``timeout_s``).
    timeout_s : float
        Time allowed to connect to the scheduler (and for the workers to join).

    Yields
    ------
    concurrent.futures.Executor or None
        None when neither is given (``run``'s default: one thread per CPU).

    Raises
    ------
    ImportError
        A scheduler was given but dask.distributed is not installed.
    ValueError
        workers < 1, or a cluster's workers run another gfins_fmi (or none).
    OSError
        The scheduler could not be reached within ``timeout_s``.
    """
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, (int, np.integer))
                                or workers < 1):
        raise ValueError(f"workers must be an integer >= 1; got {workers!r}")
    if scheduler is None:
        if workers is None:
            yield None
            return
        with cf.ThreadPoolExecutor(max_workers=int(workers)) as ex:
            yield ex
        return
    try:
        from distributed import Client   # lazy: dask.distributed: optional extra
    except ImportError as exc:
        raise ImportError("a dask scheduler needs dask.distributed: pip install 'gfins_fmi[dask]'"
                          ) from exc
    try:
        client = Client(scheduler, timeout=f"{timeout_s}s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise OSError(f"no dask scheduler answered at {scheduler!r} within {timeout_s:g} s "
                      f"({exc}); start one with 'dask scheduler' and its workers with "
                      f"'dask worker {scheduler}'") from exc
    try:
        if workers is not None:
            client.wait_for_workers(int(workers), timeout=timeout_s)
        versions = client.run(_worker_version, on_error="return")
        bad = {w: v for w, v in versions.items() if v != __version__}
        if not versions:
            raise ValueError(f"the dask scheduler at {scheduler!r} has no workers; start some "
                             f"with 'dask worker {scheduler}'")
        if bad:
            raise ValueError(f"dask workers without gfins_fmi {__version__} (install "
                             f"the same version on every worker): {bad}")
        ex = client.get_executor()
        try:
            yield ex
        finally:
            ex.shutdown(wait=True)
    finally:
        client.close()
