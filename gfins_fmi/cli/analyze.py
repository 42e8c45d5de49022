"""``gfins analyze``: error growth, python-control predictions against a Monte Carlo of
the C core (:mod:`gfins_fmi.analysis.error_report`), as a markdown report with figures."""
from __future__ import annotations

import time

from gfins_fmi.analysis.error_report import CONFIGS, write_report
from gfins_fmi.analysis.montecarlo import executor

__all__ = ["run"]


def run(args) -> int:
    t0 = time.perf_counter()
    configs = args.config or list(CONFIGS)
    with executor(args.scheduler, args.workers) as ex:
        path = write_report(args.out, configs, runs=args.runs, seed=args.seed, executor=ex,
                            progress=not args.quiet)
    print(f"report -> {path} ({time.perf_counter() - t0:.1f} s)")
    return 0
