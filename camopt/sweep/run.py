"""Sweep execution: every cell not yet done, inline, in a fork-based process pool or on
Dask, the archive updated after each finished cell (an interruption loses no finished
cell, and ``--resume`` runs only the missing ones)."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from camopt.archive.sweeps import write_sweep
from camopt.driver import prepare, run_repeat, validate
from camopt.errors import ConfigError
from camopt.perf import tune_allocator
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


def _local(cells: list[CellSpec], jobs: int, done: Callable[[CellResult], None]) -> None:
    if jobs <= 1:
        for cell in cells:
            done(run_cell(cell))
        return
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("fork"),
                               initializer=tune_allocator)
    try:
        pending = {pool.submit(run_cell, c) for c in cells}
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(fut.result())
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _dask(cells: list[CellSpec], scheduler: str, done: Callable[[CellResult], None]) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--executor", "dask",
                          "needs the 'distributed' package: pip install 'camopt[dask]'") from None
    with Client(scheduler, timeout="20s") as client:
        client.run(tune_allocator)
        futures = client.map(run_cell, cells, pure=False)
        for fut in as_completed(futures):
            done(fut.result())


def run_sweep(spec: SweepSpec, path: Path, results: dict[tuple[int, int], CellResult],
              jobs: int = 1, executor: str = "local", scheduler: str | None = None,
              progress: Callable[[int, int], None] | None = None) -> dict:
    """Run every cell not yet in ``results``, rewriting the archive after each one."""
    cells = [c for c in spec.cells() if c.key not in results]
    total = len(results) + len(cells)
    write_sweep(path, spec, results, total)
    if progress:
        progress(len(results), total)

    def done(r: CellResult) -> None:
        results[r.key] = r
        write_sweep(path, spec, results, total)
        if progress:
            progress(len(results), total)

    try:
        if executor == "dask":
            if not scheduler:
                raise ConfigError("--scheduler", "", "give the Dask scheduler's address")
            _dask(cells, scheduler, done)
        else:
            _local(cells, jobs, done)
    except KeyboardInterrupt:
        raise SweepInterrupted(f"{len(results)} of {total} cells done") from None
    return results
