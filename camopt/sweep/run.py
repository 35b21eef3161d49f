"""Sweep execution: every cell not yet done, inline, in a fork-based process pool or on
Dask, each finished cell stored at once (:class:`camopt.archive.sweeps.SweepWriter`: an
interruption loses no finished cell, and ``--resume`` runs only the missing ones).

Tiny cells are sent to workers in batches sized so a batch takes about ``BATCH_SECONDS``
(measured on the first results), which keeps the scheduling cost per cell small; a kill
loses at most the batches running. A worker prepares each grid point's problem once."""

from __future__ import annotations

import json
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, wait
from pathlib import Path

import numpy as np

from camopt.archive.sweeps import SweepWriter
from camopt.config import LoadedConfig
from camopt.driver import prepare, run_repeat, validate
from camopt.errors import ConfigError, SolverError
from camopt.perf import fork_pool, kill_pool, tune_allocator
from camopt.problem import Problem
from camopt.solvers import Solver
from camopt.stats import succeeded
from camopt.sweep.spec import CellResult, CellSpec, SweepSpec

BATCH_SECONDS = 0.2
MAX_BATCH = 256
_PREPARED: OrderedDict[str, tuple[LoadedConfig, Problem, type[Solver]]] = OrderedDict()


def _prepared(cell: CellSpec) -> tuple[LoadedConfig, Problem, type[Solver]]:
    """The validated config, problem and solver class of a cell's grid point, built once
    per process (cells of one point share them; problems hold no run state)."""
    key = json.dumps([cell.source, cell.data], sort_keys=True, default=str)
    hit = _PREPARED.get(key)
    if hit is None:
        cfg = validate(cell.data, cell.source)
        problem, solver_cls = prepare(cfg)
        hit = _PREPARED[key] = (cfg, problem, solver_cls)
        if len(_PREPARED) > 64:
            _PREPARED.popitem(last=False)
    return hit


def run_cells(cells: list[CellSpec]) -> tuple[list[CellResult], float]:
    """Run a batch of cells; their results and the batch's wall time (s)."""
    t0 = time.perf_counter()
    results = [run_cell(c) for c in cells]
    return results, time.perf_counter() - t0


def run_cell(cell: CellSpec) -> CellResult:
    """Run one cell (a top-level function: process pools and Dask pickle it by name)."""
    cfg, problem, solver_cls = _prepared(cell)
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


def batch_size(seconds_per_cell: float) -> int:
    """Cells per batch so that a batch takes about BATCH_SECONDS."""
    return int(min(MAX_BATCH, max(1, BATCH_SECONDS / max(seconds_per_cell, 1e-9))))


def _local(cells: list[CellSpec], jobs: int, done: Callable[[CellResult], None]) -> None:
    if jobs <= 1:
        for cell in cells:
            done(run_cell(cell))
        return
    pool = fork_pool(jobs)
    finished_cleanly = False
    queue, size = deque(cells), 1  # single cells until the first batch is timed
    pending: set = set()
    try:
        while queue or pending:
            while queue and len(pending) < 2 * jobs:
                batch = [queue.popleft() for _ in range(min(size, len(queue)))]
                pending.add(pool.submit(run_cells, batch))
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                results, seconds = fut.result()
                for r in results:
                    done(r)
                size = batch_size(seconds / len(results))
        finished_cleanly = True
    finally:
        if finished_cleanly:
            pool.shutdown(wait=True)
        else:  # interrupted or failed: running cells are not waited for
            kill_pool(pool)


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
            workers = max(1, len(client.scheduler_info().get("workers", {})))
            # batches of cells without timing them first (tasks are spread at once): about
            # 16 batches per worker keeps every worker busy and the scheduler's work small
            size = min(MAX_BATCH, max(1, -(-len(cells) // (16 * workers))))
            batches = [cells[i:i + size] for i in range(0, len(cells), size)]
            # a batch whose worker died is run again elsewhere (same seeds, same result)
            futures = client.map(run_cells, batches, pure=False, retries=2)
            for fut in as_completed(futures):
                for r in fut.result()[0]:
                    done(r)
    except (OSError, TimeoutError) as exc:  # the scheduler or its workers went away
        raise SolverError(f"--scheduler: {scheduler}: lost the Dask cluster: "
                          f"{_first_line(exc)}; finish with --resume") from None


def _first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0]


def run_sweep(spec: SweepSpec, path: Path, results: dict[tuple[int, int], CellResult],
              jobs: int = 1, executor: str = "local", scheduler: str | None = None,
              progress: Callable[[int, int], None] | None = None,
              replace: bool = True) -> dict:
    """Run every cell not yet in ``results``, storing each as it finishes
    (``replace=False``: the first write never replaces an existing file). ``results``
    holds exactly the cells the archive holds, also when interrupted mid-write."""
    if executor == "dask" and not scheduler:
        raise ConfigError("--scheduler", "", "give the Dask scheduler's address")
    cells = [c for c in spec.cells() if c.key not in results]
    total = len(results) + len(cells)
    writer = SweepWriter(path, spec, results, total, replace=replace)
    if progress:
        progress(len(results), total)

    def done(r: CellResult) -> None:
        writer.add(r)  # adds r to results once stored
        if progress:
            progress(len(results), total)

    try:
        if executor == "dask":
            assert scheduler is not None
            _dask(cells, scheduler, done)
        else:
            _local(cells, jobs, done)
    except KeyboardInterrupt:
        writer.close()
        raise SweepInterrupted(f"{len(results)} of {total} cells done") from None
    writer.close()
    return results
