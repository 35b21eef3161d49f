"""Sweeps: jobs-independence, interruption and resume, executors, statistics, CI gate."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt.archive.sweeps import cell_row, load_sweep
from camopt.cli import app
from camopt.config import sweep_spec as sweep_mod
from camopt.core.stats import sweep_summary
from tests.conftest import CONFIGS

runner = CliRunner()
VCB = str(CONFIGS / "vcb.toml")
SMALL = ["--set", "solver.generations=25", "--set", "run.repeats=1"]
VOLATILE = {"wall_s", "wall_s_median"}


def sweep(tmp_path, name, *args):
    out = tmp_path / name
    r = runner.invoke(app, ["sweep", VCB, "--out", str(out), "--quiet", *SMALL, *args])
    assert r.exit_code == 0, r.output
    return out


def stable_summary(path):
    spec, results = load_sweep(path)
    rows = sweep_summary(spec, results.values())
    # as JSON text: NaN (no run reached the target) compares equal to itself
    return json.dumps([{k: v for k, v in row.items() if k not in VOLATILE} for row in rows],
                      sort_keys=True)


def cells(path):
    _, results = load_sweep(path)
    return {k: {f: v for f, v in cell_row(r).items() if f != "wall_s"}
            for k, r in results.items()}


def test_jobs_do_not_change_results(tmp_path):
    """A 3 x 5 sweep (populations x seeds) gives the same summary with 1 and 2 workers."""
    grid = ["--seeds", "0:5", "--grid", "solver.population=10,20,40"]
    a = sweep(tmp_path, "j1.h5", *grid, "--jobs", "1")
    b = sweep(tmp_path, "j2.h5", *grid, "--jobs", "2")
    sa, sb = stable_summary(a), stable_summary(b)
    rows = json.loads(sa)
    assert len(rows) == 3 and all(r["runs"] == 5 for r in rows)
    assert sa == sb
    assert cells(a) == cells(b)


def _start(tmp_path, out, *extra):
    cmd = [sys.executable, "-m", "camopt", "sweep", VCB, "--out", str(out), "--quiet",
           "--seeds", "0:8", "--grid", "solver.population=30,60", "--jobs", "1",
           "--set", "solver.generations=60", *extra]
    return subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _wait_for_cells(out, n, proc, timeout=60.0):
    """Poll the archive while it is being written: every read must succeed."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        if out.exists():
            spec, results = load_sweep(out)  # never half-written
            if len(results) >= n:
                return len(results)
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    raise AssertionError("sweep did not progress")


@pytest.mark.slow
def test_interrupt_kill_and_resume_equal_uninterrupted(tmp_path):
    out = tmp_path / "sweep.h5"
    proc = _start(tmp_path, out)
    _wait_for_cells(out, 2, proc)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert b"--resume" in err
    done_after_int = len(load_sweep(out)[1])
    assert done_after_int >= 2
    # resume, then SIGKILL mid-way: nothing finished is lost
    proc = subprocess.Popen([sys.executable, "-m", "camopt", "sweep", "--resume", str(out),
                             "--quiet", "--jobs", "1"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _wait_for_cells(out, done_after_int + 2, proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    done_after_kill = len(load_sweep(out)[1])
    assert done_after_kill >= done_after_int + 2
    r = runner.invoke(app, ["sweep", "--resume", str(out), "--quiet", "--jobs", "2"])
    assert r.exit_code == 0, r.output
    full = tmp_path / "full.h5"
    proc = _start(tmp_path, full)
    assert proc.wait(timeout=300) == 0
    assert cells(out) == cells(full)
    assert stable_summary(out) == stable_summary(full)


@pytest.mark.slow
def test_dask_local_cluster_matches_local_pool(tmp_path):
    """Issue #12: a sweep on a LocalCluster of 4 workers stores the same cells (but wall
    times) and summary as --jobs 1."""
    distributed = pytest.importorskip("distributed")
    grid = ["--seeds", "0:6", "--grid", "solver.population=10,20"]
    local = sweep(tmp_path, "local.h5", *grid, "--jobs", "1")
    with distributed.LocalCluster(n_workers=4, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=":0") as cluster:
        dask = sweep(tmp_path, "dask.h5", *grid, "--executor", "dask",
                     "--scheduler", cluster.scheduler_address)
    assert stable_summary(local) == stable_summary(dask)
    assert cells(local) == cells(dask)


@pytest.mark.slow
def test_compare_detects_population_difference_and_none_between_seeds(tmp_path):
    def run(name, *args):
        out = tmp_path / name
        r = runner.invoke(app, ["run", VCB, "--out", str(out), "--quiet",
                                "--set", "solver.generations=40", "--repeats", "8", *args])
        assert r.exit_code == 0, r.output
        return str(out)

    small = run("p10.h5", "--set", "solver.population=10")
    large = run("p100.h5", "--set", "solver.population=100")
    other_seed = run("p100b.h5", "--set", "solver.population=100", "--seed", "99")
    r = runner.invoke(app, ["compare", small, large, "--format", "json"])
    test = json.loads(r.stdout)["tests"][0]
    assert test["p_value"] < 0.05 and test["verdict"].startswith("B is better than A")
    r = runner.invoke(app, ["compare", large, other_seed, "--format", "json"])
    test = json.loads(r.stdout)["tests"][0]
    assert test["p_value"] >= 0.05 and test["verdict"].startswith("no significant")


def test_compare_ranks_sweep_points(tmp_path):
    out = sweep(tmp_path, "rank.h5", "--seeds", "0:6", "--grid", "solver.population=6,60",
                "--jobs", "1")
    r = runner.invoke(app, ["compare", str(out), "--format", "json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["ranking"][0]["label"] == "solver.population=60"
    assert "vs_best" in doc["ranking"][1]


def test_check_gate(tmp_path):
    ok = runner.invoke(app, ["sweep", VCB, "--quiet", "--out", str(tmp_path / "a.h5"),
                             "--seeds", "0:2", "--set", "solver.generations=150",
                             "--set", "solver.population=60", "--check", "--jobs", "1"])
    assert ok.exit_code == 0, ok.output
    bad = runner.invoke(app, ["sweep", VCB, "--quiet", "--out", str(tmp_path / "b.h5"),
                              "--seeds", "0:2", "--set", "solver.generations=3",
                              "--set", "solver.population=5", "--check", "--jobs", "1"])
    assert bad.exit_code == 1
    assert "check failed" in bad.stderr


def test_bad_grid_and_seeds(tmp_path):
    r = runner.invoke(app, ["sweep", VCB, "--grid", "solver.popsize=3", "--out",
                            str(tmp_path / "x.h5")])
    assert r.exit_code == 2 and "unknown key" in r.stderr
    assert not (tmp_path / "x.h5").exists()
    r = runner.invoke(app, ["sweep", VCB, "--seeds", "5:2"])
    assert r.exit_code == 2 and "--seeds" in r.stderr


def test_cell_seed_k_is_child_k_of_the_run_seed():
    """run_cell with seed k of run.seed = 7 draws from child k of SeedSequence(7), the same
    generator as repeat k of a run (one generation of DE: the best of its first sample)."""
    from camopt.engine.driver import prepare, validate
    from camopt.engine.sweep import run_cell
    from tests.engine.test_driver import _first_generation_best

    data = {"case": {"kind": "sphere"},
            "solver": {"name": "de_gr", "population": 12, "generations": 1},
            "run": {"seed": 7}}
    results = [run_cell(sweep_mod.CellSpec(data, "sphere.toml", 7, k, 0)) for k in (0, 3)]
    problem, _ = prepare(validate(data, "sphere.toml"))
    children = np.random.SeedSequence(7).spawn(4)
    for k, r in zip((0, 3), results):
        assert r.index == k and r.spawn_key == (k,)
        np.testing.assert_array_equal(r.x, _first_generation_best(problem, children[k], 12))


def test_cells_go_to_a_journal_and_snapshots_double(tmp_path, monkeypatch):
    """Issue #12: a finished cell costs one journal line; the HDF5 snapshot is rewritten
    only when the stored cells have doubled (from SNAPSHOT_MIN_CELLS on) and at the end
    (unless the last one holds every cell), so a sweep of n cells rewrites it O(log n)
    times, and no journal is left once the sweep is complete."""
    from camopt.archive import sweeps as store

    calls = []
    real = store.write_sweep
    monkeypatch.setattr(store, "write_sweep", lambda *a, **k: (calls.append(len(a[2])),
                                                               real(*a, **k)))
    monkeypatch.setattr(store, "SNAPSHOT_MIN_CELLS", 4)  # 64 in use: fewer cells here
    out = sweep(tmp_path, "s.h5", "--seeds", "0:32", "--set", "solver.generations=2",
                "--set", "solver.population=6", "--jobs", "1")
    assert calls == [0, 4, 8, 16, 32]  # the last one holds every cell: not written again
    assert not store.journal_path(out).exists()
    _, results = load_sweep(out)
    assert sorted(results) == [(0, s) for s in range(32)]


def test_batches_do_not_change_results(tmp_path):
    """Cells sent to pool workers in batches (sized from the first cells' time) give the
    same cells as one job running them one by one."""
    from camopt.engine import sweep as sweep_run

    assert sweep_run.batch_size(1e-4) == sweep_run.MAX_BATCH
    assert sweep_run.batch_size(10.0) == 1
    # near the end a batch is at most a 1 / (TAIL_SHARES x workers) share of what is left
    assert sweep_run.batch_size(1e-4, left=80, jobs=2) == 80 // (2 * sweep_run.TAIL_SHARES)
    assert sweep_run.batch_size(1e-4, left=3, jobs=2) == 1
    assert sweep_run.batch_size(0.05, left=10**6, jobs=2) == 4  # 0.2 s of 50 ms cells
    args = ["--seeds", "0:24", "--set", "solver.generations=2", "--set", "solver.population=6"]
    assert cells(sweep(tmp_path, "a.h5", *args, "--jobs", "1")) == \
        cells(sweep(tmp_path, "b.h5", *args, "--jobs", "2"))


def test_workers_inherit_the_parents_problems(tmp_path, monkeypatch):
    """The parent prepares every grid point's problem before it forks its workers, which
    inherit them: no worker validates or builds a problem (each did, per point, before).
    Forked workers inherit the patched ``prepare``; it records the process it ran in."""
    import os

    from camopt.engine import sweep as sweep_run

    log = tmp_path / "prepared-in"
    real = sweep_run.prepare

    def recording(cfg):
        with open(log, "a") as f:
            f.write(f"{os.getpid()}\n")
        return real(cfg)

    monkeypatch.setattr(sweep_run, "prepare", recording)
    monkeypatch.setattr(sweep_run, "_PREPARED", type(sweep_run._PREPARED)())  # none cached
    sweep(tmp_path, "s.h5", "--seeds", "0:4", "--grid", "solver.population=6,8",
          "--set", "solver.generations=2", "--jobs", "2")
    pids = log.read_text().split()
    assert len(pids) == 2 and set(pids) == {str(os.getpid())}, pids
