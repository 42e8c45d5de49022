"""Monte Carlos of the core (gfins_fmi.analysis.montecarlo.run): the results do not depend
on the executor (threads, processes, a serial run) for one seed. The dask.distributed
executor: test_montecarlo_dask.py.
"""
from __future__ import annotations

import concurrent.futures as cf

import numpy as np
import pytest

from gfins_fmi.analysis import montecarlo as mc


def test_monte_carlo_results_do_not_depend_on_the_executor():
    def task(k, rng):
        return dict(x=rng.normal(size=3) + k)
    a = mc.run(task, 20, seed=5)
    with cf.ThreadPoolExecutor(max_workers=1) as ex:
        b = mc.run(task, 20, seed=5, executor=ex)
        c = mc.run(task, 20, seed=5, executor=ex, batch=7)     # 3 jobs of 7, 7, 6 runs
    assert np.array_equal(a["x"], b["x"]) and np.array_equal(a["x"], c["x"])
    with mc.executor(workers=3) as ex:                         # --workers 3: threads here
        assert isinstance(ex, cf.ThreadPoolExecutor) and ex._max_workers == 3
        assert np.array_equal(a["x"], mc.run(task, 20, seed=5, executor=ex)["x"])
    with pytest.raises(ValueError, match="n_runs must be an integer >= 1"):
        mc.run(task, 0)
    with pytest.raises(ValueError, match="batch must be an integer >= 1"):
        mc.run(task, 3, batch=0)
