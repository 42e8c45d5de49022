"""Monte-Carlo runs of the C core on any ``concurrent.futures.Executor``.

``run(task, n_runs, seed)`` calls ``task(k, rng)`` for k = 0..n_runs-1 with independent
generators (``numpy.random.SeedSequence(seed).spawn``), so results do not depend on the
executor or the number of workers; each task returns a dict of arrays, stacked along a
new first axis. The default executor is a thread pool with one worker per CPU: the C
calls release the GIL (cffi), so threads run the core in parallel. Pass any Executor
(e.g. a process pool, or a cluster's) to run elsewhere.
"""
from __future__ import annotations

import concurrent.futures as cf
import os
from typing import Callable

import numpy as np

__all__ = ["run"]


def run(task: Callable[[int, np.random.Generator], dict], n_runs: int, seed: int = 0,
        executor: cf.Executor | None = None, progress: bool = False,
        desc: str = "Monte Carlo") -> dict:
    """Run ``task`` n_runs times; returns {name: array (n_runs, ...)}.

    Raises
    ------
    ValueError
        n_runs < 1.
    """
    if not isinstance(n_runs, (int, np.integer)) or n_runs < 1:
        raise ValueError(f"n_runs must be an integer >= 1; got {n_runs!r}")
    seqs = np.random.SeedSequence(seed).spawn(int(n_runs))
    own = executor is None
    ex = executor or cf.ThreadPoolExecutor(max_workers=os.cpu_count() or 1)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=n_runs, desc=desc, unit="run")
    results: list = [None] * n_runs
    try:
        futures = {ex.submit(task, k, np.random.default_rng(s)): k for k, s in enumerate(seqs)}
        for fut in cf.as_completed(futures):
            results[futures[fut]] = fut.result()
            if bar:
                bar.update(1)
    finally:
        if bar:
            bar.close()
        if own:
            ex.shutdown()
    return {name: np.stack([r[name] for r in results]) for name in results[0]}
