"""Monte-Carlo scaling on dask.distributed: the same workloads serially (one thread in
this process) and on a local cluster of 1 and 2 single-threaded worker processes (what
`dask scheduler` + `dask worker --nworkers N --nthreads 1` start), through
gfins_fmi.analysis.montecarlo.executor as the CLI uses it. Prints wall time, CPU time of this
process and of the workers, the load average before each run (the machine may be shared)
and whether the results equal the serial ones bit for bit.

    python bench/bench_montecarlo.py [--runs-sins 200] [--runs-qin 200] [--workers 1 2]
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import logging
import os
import time

import numpy as np


def _worker_cpu() -> float:
    """CPU seconds (user + system) of the worker process this runs in."""
    import psutil
    t = psutil.Process().cpu_times()
    return t.user + t.system


def _warm() -> None:
    """Import what the tasks use (a worker that ran tasks before has it loaded)."""
    import gfins_fmi.analysis.error_report  # noqa: F401
    import gfins_fmi.experiments.qin  # noqa: F401


def workloads(runs_sins: int, runs_qin: int) -> dict:
    from gfins_fmi.analysis import error_report
    from gfins_fmi.experiments import qin as reproduce
    return {
        f"gfins analyze --config sins --runs {runs_sins}":
            lambda ex: error_report.compare("sins", runs=runs_sins, executor=ex).simulated,
        f"gfins reproduce qin --runs {runs_qin} (Monte Carlo)":
            lambda ex: np.concatenate([a.ravel() for a in reproduce.run_qin(
                runs=runs_qin, progress=False, executor=ex).att_deg.values()]),
    }


def measure(fn, ex, client=None) -> dict:
    load = os.getloadavg()
    w0 = sum(client.run(_worker_cpu).values()) if client else 0.0
    c0, t0 = time.process_time(), time.perf_counter()
    out = fn(ex)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    workers = sum(client.run(_worker_cpu).values()) - w0 if client else 0.0
    return dict(out=out, wall=wall, cpu=cpu, workers=workers, load=load)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs-sins", type=int, default=200)
    ap.add_argument("--runs-qin", type=int, default=200)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    a = ap.parse_args(argv)
    from distributed import Client, LocalCluster

    from gfins_fmi.analysis import montecarlo
    jobs = workloads(a.runs_sins, a.runs_qin)
    for fn in workloads(2, 2).values():      # warm-up here: imports, python-control
        fn(None)
    print(f"{os.cpu_count()} logical CPUs; times in s; load = 1/5/15-min load average at the start")
    print("| workload | executor | wall | CPU here | CPU workers | = serial | load |")
    print("|---|---|---|---|---|---|---|")
    serial = {}
    for name, fn in jobs.items():
        with cf.ThreadPoolExecutor(1) as ex:
            r = measure(fn, ex)
        serial[name] = r["out"]
        print(f"| {name} | serial (1 thread, this process) | {r['wall']:.1f} | {r['cpu']:.1f} | - | - | "
              f"{'/'.join(f'{x:.1f}' for x in r['load'])} |", flush=True)
    for n in a.workers:
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                          silence_logs=logging.ERROR) as cluster, \
                Client(cluster.scheduler_address) as client:
            client.run(_warm)
            with montecarlo.executor(cluster.scheduler_address, workers=n) as ex:
                for name, fn in jobs.items():
                    r = measure(fn, ex, client)
                    same = np.array_equal(r["out"], serial[name])
                    print(f"| {name} | dask, {n} worker{'s' if n > 1 else ''} | {r['wall']:.1f} | "
                          f"{r['cpu']:.1f} | {r['workers']:.1f} | {'yes' if same else 'NO'} | "
                          f"{'/'.join(f'{x:.1f}' for x in r['load'])} |", flush=True)


if __name__ == "__main__":
    main()
