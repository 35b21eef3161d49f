"""Sweep execution: every cell not yet done, inline, in a fork-based process pool or on
Dask, the archive updated after each finished cell (an interruption loses no finished
cell, and ``--resume`` runs only the missing ones)."""

from __future__ import annotations

import signal
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from camopt.archive.sweeps import write_sweep
from camopt.driver import prepare, run_repeat, validate
from camopt.errors import ConfigError, SolverError
from camopt.perf import die_with_parent, tune_allocator
from camopt.stats import succeeded
from camopt.sweep.spec import CellResult, CellSpec, SweepSpec


def run_cell(cell: CellSpec) -> CellResult:
    """Run one cell (a top-level function: process pools and Dask pickle it by name)."""
    cfg = validate(cell.data, cell.source)
    problem, solver_cls = prepare(cfg)
    child = np.random.SeedSequence(cell.entropy, spawn_key=(cell.seed,))
    rec = run_repeat(problem, solver_cls, cfg, child, cell.seed, 1)
    target = cfg.run.target
    h = rec.history
    ok = h["best_violation"] == 0
    if target is not None:
        ok &= h["best_objective"] <= target
    success = bool(succeeded([rec.fun], [rec.feasible], target)[0])
    return CellResult(
        point=cell.point, seed=cell.seed, objective=rec.fun, feasible=rec.feasible,
        success=success, nfev=rec.nfev, nit=rec.nit, wall_s=rec.wall_s,
        converged_nit=rec.converged_nit,
        nfev_to_target=int(h["nfev"][np.argmax(ok)]) if ok.any() else -1,
        x=rec.x.tolist(),
        history={k: np.asarray(v).tolist() for k, v in h.items()},
    )


# ---- execution ------------------------------------------------------------------------
class SweepInterrupted(Exception):
    """Raised when a sweep stops early; the archive holds every finished cell."""


def _worker_start() -> None:
    """Pool worker set-up: die with the parent (a killed sweep leaves no worker blocked
    forever), leave Ctrl-C to the parent (which stops the pool), tune the allocator."""
    die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    tune_allocator()


def _local(cells: list[CellSpec], jobs: int, done: Callable[[CellResult], None]) -> None:
    if jobs <= 1:
        for cell in cells:
            done(run_cell(cell))
        return
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("fork"),
                               initializer=_worker_start)
    finished_cleanly = False
    try:
        pending = {pool.submit(run_cell, c) for c in cells}
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(fut.result())
        finished_cleanly = True
    finally:
        if not finished_cleanly:  # interrupted or failed: running cells are not waited for
            for proc in list(getattr(pool, "_processes", {}).values()):
                proc.kill()
        pool.shutdown(wait=True, cancel_futures=True)


def _dask(cells: list[CellSpec], scheduler: str, done: Callable[[CellResult], None]) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--executor", "dask",
                          "needs the 'distributed' package: pip install 'camopt[dask]'") from None
    try:
        client = Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ConfigError("--scheduler", scheduler,
                          f"cannot reach the Dask scheduler: {_first_line(exc)}") from None
    try:
        with client:
            client.run(tune_allocator)
            futures = client.map(run_cell, cells, pure=False)
            for fut in as_completed(futures):
                done(fut.result())
    except (OSError, TimeoutError) as exc:  # the scheduler or its workers went away
        raise SolverError(f"--scheduler: {scheduler}: lost the Dask cluster: "
                          f"{_first_line(exc)}; finish with --resume") from None


def _first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0]


def run_sweep(spec: SweepSpec, path: Path, results: dict[tuple[int, int], CellResult],
              jobs: int = 1, executor: str = "local", scheduler: str | None = None,
              progress: Callable[[int, int], None] | None = None,
              replace: bool = True) -> dict:
    """Run every cell not yet in ``results``, rewriting the archive after each one
    (``replace=False``: the first write never replaces an existing file). ``results``
    holds exactly the cells the archive holds, also when interrupted mid-write."""
    if executor == "dask" and not scheduler:
        raise ConfigError("--scheduler", "", "give the Dask scheduler's address")
    cells = [c for c in spec.cells() if c.key not in results]
    total = len(results) + len(cells)
    write_sweep(path, spec, results, total, replace=replace)
    if progress:
        progress(len(results), total)

    def done(r: CellResult) -> None:
        write_sweep(path, spec, {**results, r.key: r}, total)
        results[r.key] = r  # only once stored: an interruption reports what is stored
        if progress:
            progress(len(results), total)

    try:
        if executor == "dask":
            assert scheduler is not None
            _dask(cells, scheduler, done)
        else:
            _local(cells, jobs, done)
    except KeyboardInterrupt:
        raise SweepInterrupted(f"{len(results)} of {total} cells done") from None
    return results
