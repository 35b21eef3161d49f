"""A Dask sweep under faults (issue #23): a cluster without workers or without its
scheduler ends the sweep with one error in bounded time, and the archive resumes. The
cluster is real: a scheduler and nanny-less workers on 127.0.0.1 (a killed worker stays
dead), each a subprocess killed at the end."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from camopt import sweep as sweep_mod
from camopt.archive.sweeps import load_sweep
from camopt.errors import SolverError
from camopt.sweep import run as sweep_run
from tests.conftest import CONFIGS
from tests.helpers import load

distributed = pytest.importorskip("distributed")
DE = CONFIGS / "fast_switch_de.toml"


class Cluster:
    """A scheduler and ``workers`` nanny-less workers as subprocesses on 127.0.0.1."""

    def __init__(self, folder, workers: int) -> None:
        self.file = folder / "scheduler.json"
        self.procs: list[subprocess.Popen] = []
        self.scheduler = self._start("distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                     "--port", "0", "--no-dashboard")
        deadline = time.time() + 60
        while not self.file.exists():
            assert time.time() < deadline, "the scheduler did not start"
            time.sleep(0.1)
        time.sleep(0.2)  # the file is written whole, but give it a moment
        self.address = json.loads(self.file.read_text())["address"]
        self.workers = [self.add_worker() for _ in range(workers)]
        self.wait_for(workers)

    def _start(self, module: str, *args: str) -> subprocess.Popen:
        proc = subprocess.Popen([sys.executable, "-m", module, "--scheduler-file",
                                 str(self.file), *args], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        self.procs.append(proc)
        return proc

    def add_worker(self) -> subprocess.Popen:
        return self._start("distributed.cli.dask_worker", "--no-nanny", "--nthreads", "1",
                           "--host", "127.0.0.1", "--no-dashboard")

    def wait_for(self, n: int) -> None:
        with distributed.Client(self.address, timeout="30s") as client:
            client.wait_for_workers(n, timeout=90)

    def close(self) -> None:
        for proc in self.procs:
            proc.kill()
            proc.wait(timeout=10)


@pytest.fixture
def cluster(tmp_path):
    c = Cluster(tmp_path, 2)
    yield c
    c.close()


def spec(seeds: int) -> sweep_mod.SweepSpec:
    config = load(DE, "solver.generations=40", "solver.population=8")
    return sweep_mod.SweepSpec(config.effective(), str(DE), config.text, [], (0, seeds))


def killing(procs: list[subprocess.Popen], after: int):
    """A progress callback that SIGKILLs ``procs`` once ``after`` cells are stored."""
    def progress(done: int, total: int) -> None:
        if done >= after:
            for proc in procs:
                if proc.poll() is None:
                    proc.send_signal(signal.SIGKILL)
                    proc.wait(timeout=10)
    return progress


@pytest.mark.slow
def test_a_dask_sweep_ends_cleanly_and_resumably_without_workers_or_scheduler(
        cluster, tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_run, "LOST_SECONDS", 8.0)
    s = spec(10)
    inline = sweep_run.run_sweep(s, tmp_path / "inline.h5", {}, jobs=1)

    # every worker killed: one error within LOST_SECONDS, not a wait forever; resumable
    out = tmp_path / "no-workers.h5"
    t0 = time.monotonic()
    with pytest.raises(SolverError, match="lost the Dask cluster.*--resume"):
        sweep_run.run_sweep(s, out, {}, executor="dask", scheduler=cluster.address,
                            progress=killing(cluster.workers, 1))
    assert time.monotonic() - t0 < 60
    spec_back, done = load_sweep(out)
    assert 1 <= len(done) < 10
    finished = sweep_run.run_sweep(spec_back, out, done, jobs=1)
    assert {k: r.objective for k, r in finished.items()} == \
        {k: r.objective for k, r in inline.items()}

    # the scheduler killed mid-sweep: one error, no traceback, resumable
    cluster.workers.append(cluster.add_worker())
    cluster.wait_for(1)
    out = tmp_path / "no-scheduler.h5"
    t0 = time.monotonic()
    with pytest.raises(SolverError, match="lost the Dask cluster"):
        sweep_run.run_sweep(s, out, {}, executor="dask", scheduler=cluster.address,
                            progress=killing([cluster.scheduler], 1))
    assert time.monotonic() - t0 < 60
    assert 1 <= len(load_sweep(out)[1]) < 10
    assert not any(n.endswith((".tmp", ".lock")) for n in os.listdir(tmp_path))
