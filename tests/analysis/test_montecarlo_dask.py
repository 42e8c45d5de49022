"""Monte Carlo on dask.distributed: a LocalCluster with one worker *process* stands for a
cluster (the tasks cross a process boundary, pickled with the arrays they captured, as
they would to another machine). The truth is the serial run of the same code with the
same seed: every run draws from its own generator, spawned from the seed, so the
results must be equal bit for bit whatever executes them."""
from __future__ import annotations

import concurrent.futures as cf
import logging
import sys

import numpy as np
import pytest

try:
    import distributed
except ImportError as exc:
    pytest.skip(f"dask.distributed is not importable ({exc}); pip install 'gfins_fmi[dask]' "
                "(the test extra installs it)", allow_module_level=True)

from gfins_fmi.analysis import error_report
from gfins_fmi.analysis import montecarlo as mc
from gfins_fmi.experiments import qin as R
from gfins_fmi.cli import main  # noqa: E402


@pytest.fixture(scope="module")
def scheduler():
    """Address of a local scheduler with one single-threaded worker process."""
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=logging.ERROR) as cluster:
        yield cluster.scheduler_address


def test_dask_runs_equal_the_serial_runs(scheduler):
    """error_report's gyro-free scenario (9 accelerometers) and the Qin reproduction, on the
    cluster (through montecarlo.executor, as the CLI does) and serially."""
    with cf.ThreadPoolExecutor(1) as serial:
        a = error_report.compare("qin9", runs=6, seed=3, executor=serial)
        qa = R.run_qin(runs=3, seed=5, progress=False, executor=serial)
    with mc.executor(scheduler, workers=1) as ex:
        b = error_report.compare("qin9", runs=6, seed=3, executor=ex)
        qb = R.run_qin(runs=3, seed=5, progress=False, executor=ex)
        # several runs per job (the default for a cluster is four jobs per worker thread)
        c = mc.run(lambda k, rng: dict(x=rng.normal(size=2) + k), 10, seed=1, executor=ex, batch=4)
    assert np.array_equal(a.simulated, b.simulated)
    for name in qa.att_deg:
        for field in ("att_deg", "pos_m", "rate_rms"):
            assert np.array_equal(getattr(qa, field)[name], getattr(qb, field)[name]), (name, field)
    assert np.array_equal(c["x"], mc.run(lambda k, rng: dict(x=rng.normal(size=2) + k), 10, seed=1)["x"])


def test_cli_scheduler_option(scheduler, tmp_path, capsys):
    """gfins analyze / gfins reproduce qin --scheduler ADDRESS write what the local run
    writes (report and table text compared)."""
    out = tmp_path / "dask"
    assert main(["analyze", "--config", "qin9", "--runs", "4", "--seed", "2", "--quiet",
                 "--scheduler", scheduler, "--out", str(out)]) == 0
    local = error_report.write_report(tmp_path / "local", ["qin9"], runs=4, seed=2, progress=False)
    assert (out / "report.md").read_text() == local.read_text()
    assert main(["reproduce", "qin", "--runs", "2", "--seed", "9", "--scheduler", scheduler,
                 "--out", str(out)]) == 0
    table = R.qin_table(R.run_qin(runs=2, seed=9, progress=False))
    # the file holds the Monte-Carlo table, then the navigator's own error (no random part)
    assert (out / "qin_table.md").read_text().startswith(table + "\n\n")


def test_executor_refusals(monkeypatch, capsys):
    """Unreachable scheduler, missing dask, bad worker count: errors that say what to do."""
    with pytest.raises(OSError, match="no dask scheduler answered at 'tcp://127.0.0.1:9'"):
        with mc.executor("tcp://127.0.0.1:9", timeout_s=1.0):
            pass
    with pytest.raises(ValueError, match="workers must be an integer >= 1"):
        with mc.executor(workers=0):
            pass
    monkeypatch.setitem(sys.modules, "distributed", None)      # as if not installed
    with pytest.raises(ImportError, match=r"pip install 'gfins_fmi\[dask\]'"):
        with mc.executor("tcp://127.0.0.1:9"):
            pass
    assert main(["analyze", "--config", "qin9", "--runs", "2", "--scheduler", "tcp://127.0.0.1:9"]) == 2
    assert "gfins_fmi[dask]" in capsys.readouterr().err
