"""Sweep execution: every cell not yet done, inline, in a fork-based process pool or on
Dask, each finished cell stored at once (:class:`camopt.archive.sweeps.SweepWriter`: an
interruption loses no finished cell, and ``--resume`` runs only the missing ones).

Tiny cells are sent to workers in batches sized so a batch takes about ``BATCH_SECONDS``
(measured on the results so far), which keeps the scheduling cost per cell small, and
never more than a share of the cells left, so the workers finish together; a kill loses
at most the batches running. The parent prepares the grid points' problems before it
forks the workers, which inherit them (a worker prepares only a point it lacks).

dask.distributed is imported where used: it is an optional dependency (``--scheduler``)."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, CancelledError, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Protocol

import numpy as np

from camopt.config import LoadedConfig
from camopt.config.sweep_spec import MAX_CELLS, CellSpec, SweepSpec
from camopt.core.perf import fork_pool, kill_pool, pin_blas_threads, tune_allocator
from camopt.core.problem import Problem
from camopt.core.record import Repeat
from camopt.engine import interrupts
from camopt.engine.driver import run_repeat
from camopt.engine.interrupts import deferred
from camopt.engine.setup import prepare, validate
from camopt.errors import CamoptError, ConfigError, SolverError
from camopt.solvers import Solver

BATCH_SECONDS = 0.2
MAX_BATCH = 256
TAIL_SHARES = 4  # a batch is at most 1 / (TAIL_SHARES x workers) of the cells left
WORKERS_PER_CORE = 2  # local workers at most per usable core (see ``workers``)
CONNECT_TIMEOUT = "20s"  # reaching a Dask scheduler
LOST_SECONDS = 60.0  # a Dask cluster without scheduler or workers this long is lost
LOST_CHECKS = 3  # ...and seen so on this many checks in a row (never on one observation)
POLL_SECONDS = 1.0  # how often a Dask sweep checks its cluster while waiting
FETCH_SECONDS = 5.0  # fetching a finished batch longer than this: its worker died meanwhile
_PREPARED: OrderedDict[str, tuple[LoadedConfig, Problem, type[Solver]]] = OrderedDict()
_PREPARED_MAX = 64  # grid points whose problems a process keeps


def validate_spec(spec: SweepSpec) -> list[LoadedConfig]:
    """Validate every grid point's config now, so a bad grid fails before any work."""
    n_cells = math.prod(len(v) for _, v in spec.grid) * (spec.seeds[1] - spec.seeds[0])
    if n_cells > MAX_CELLS:
        raise ConfigError("--grid", "cells", f"{n_cells} grid points x seeds; at most "
                          f"{MAX_CELLS} cells in one sweep (every cell is held in "
                          "memory)")
    return [_prepared(spec.point_data(point), spec.source, tuple(point))[0]
            for point in spec.points()]


def _prepared(data: dict, source: str, grid: tuple[str, ...] = ()
              ) -> tuple[LoadedConfig, Problem, type[Solver]]:
    """The validated config, problem and solver class of a grid point, built once per
    process (cells of one point share them; problems hold no run state): validating the
    spec builds them in the parent, whose forked workers inherit them."""
    key = json.dumps([source, data], sort_keys=True, default=str)
    hit = _PREPARED.get(key)
    if hit is None:
        cfg = validate(data, source, grid)
        problem, solver_cls = prepare(cfg)
        hit = _PREPARED[key] = (cfg, problem, solver_cls)
        if len(_PREPARED) > _PREPARED_MAX:
            _PREPARED.popitem(last=False)
    return hit


def run_cells(cells: list[CellSpec]) -> tuple[list[Repeat], float]:
    """Run a batch of cells; their results and the batch's wall time (s)."""
    t0 = time.perf_counter()
    results = list(_run_each(cells))
    return results, time.perf_counter() - t0


def _run_each(cells: list[CellSpec]) -> Iterator[Repeat]:
    """Each cell's result in turn. The cells of a grid point share one data dict (also
    once unpickled), so its problem is looked up once, not once per cell (the look-up
    serialises the config: ~2 % of a tiny cell)."""
    by_data: dict[int, tuple[LoadedConfig, Problem, type[Solver]]] = {}
    for cell in cells:  # ``cells`` keeps every data dict alive: an id stays unique
        prepared = by_data.get(id(cell.data))
        if prepared is None:
            prepared = by_data[id(cell.data)] = _prepared(cell.data, cell.source)
        yield run_cell(cell, prepared)


def run_cell(cell: CellSpec, prepared: tuple[LoadedConfig, Problem, type[Solver]] | None
             = None) -> Repeat:
    """Run one cell (a top-level function: process pools and Dask pickle it by name);
    ``prepared``: its grid point's config, problem and solver class if the caller has
    them."""
    cfg, problem, solver_cls = prepared or _prepared(cell.data, cell.source)
    child = np.random.SeedSequence(cell.entropy, spawn_key=(cell.seed,))
    rec = run_repeat(problem, solver_cls, cfg, child, cell.seed, 1)
    # the solver's table stays behind: a sweep stores none, and it can be large
    return dataclasses.replace(rec, point=cell.point, table=[])


# ---- execution ------------------------------------------------------------------------
class SweepInterrupted(Exception):
    """Raised when a sweep stops early; the archive holds every finished cell."""


def batch_size(seconds_per_cell: float, left: int | None = None, jobs: int = 1) -> int:
    """Cells per batch so that a batch takes about BATCH_SECONDS, and with ``left`` cells
    still to send to ``jobs`` workers at most a ``1 / (TAIL_SHARES * jobs)`` share of them
    (guided self-scheduling): batches shrink towards the end, so no worker is still busy
    with a long batch while the others wait (the end of a sweep of tiny cells)."""
    size = int(min(MAX_BATCH, max(1, BATCH_SECONDS / max(seconds_per_cell, 1e-9))))
    if left is not None:
        size = min(size, max(1, left // (TAIL_SHARES * jobs)))
    return size


def workers(jobs: int, cells: int) -> int:
    """Worker processes a local sweep starts for ``--jobs`` and ``cells`` cells to run: never
    more than the cells, nor more than ``WORKERS_PER_CORE`` x the usable cores (cells are
    CPU-bound: more processes only share the cores and add memory)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(1, min(jobs, cells, WORKERS_PER_CORE * cores))


def _prepare_here(cells: list[CellSpec]) -> None:
    """Prepare the problems of the cells' grid points (as many as the cache keeps) in this
    process, before it forks its workers: they inherit them, so no worker spends its
    first cell's time validating, building and importing what the parent already has."""
    firsts = {c.point: c for c in reversed(cells)}  # the first cell of every point
    for cell in sorted(firsts.values(), key=lambda c: c.point)[:_PREPARED_MAX]:
        _prepared(cell.data, cell.source)


def _local(cells: list[CellSpec], jobs: int, done: Callable[[Repeat], None]) -> None:
    jobs = workers(jobs, len(cells))
    if jobs <= 1:
        for result in _run_each(cells):
            done(result)
        return
    _prepare_here(cells)
    pool = fork_pool(jobs)
    finished_cleanly = False
    queue, size = deque(cells), 1  # single cells until the first batch is timed
    timed_cells, timed_seconds = 0, 0.0
    pending: set = set()
    try:
        while queue or pending:
            interrupts.check()
            while queue and len(pending) < 2 * jobs:
                if timed_cells:
                    size = batch_size(timed_seconds / timed_cells, len(queue), jobs)
                batch = [queue.popleft() for _ in range(min(size, len(queue)))]
                pending.add(pool.submit(run_cells, batch))
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in sorted(finished, key=lambda f: f.exception() is not None):
                try:  # the batches that finished are stored before a broken one is reported
                    results, seconds = fut.result()
                except BrokenProcessPool:
                    raise SolverError("--jobs: a worker process died (killed, or out of "
                                      "memory); the finished cells are kept") from None
                for r in results:
                    done(r)
                timed_cells += len(results)  # the mean over every batch: one slow batch
                timed_seconds += seconds     # (a busy host) does not swing the size
        finished_cleanly = True
    finally:
        if finished_cleanly:
            pool.shutdown(wait=True)
        else:  # interrupted or failed: running cells are not waited for
            kill_pool(pool)


def _connect(scheduler: str):
    """A Dask client of ``scheduler``; an unreachable or malformed address is bad input
    (checked before the sweep archive is created, so a refused sweep leaves nothing)."""
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError("--executor", "dask",
                          "needs the 'distributed' package: pip install 'camopt[dask]'") from None
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ConfigError("--scheduler", scheduler,
                          f"cannot reach the Dask scheduler: {_first_line(exc)}") from None


def _dask(client, cells: list[CellSpec], scheduler: str,
          done: Callable[[Repeat], None]) -> None:
    """Run ``cells`` on the cluster, storing each batch's cells as it finishes. A batch
    whose worker died (running it, or holding its finished result) is run again elsewhere
    (same seeds, same result); a cluster left without workers, or without its scheduler,
    for ``LOST_SECONDS`` and ``LOST_CHECKS`` checks in a row ends the sweep with one error
    (the finished cells are stored: ``--resume`` finishes it)."""
    from distributed import wait as dask_wait

    def lost(why: str) -> SolverError:
        return SolverError(f"--scheduler: {scheduler}: lost the Dask cluster ({why}); finish "
                           "with --resume")

    try:
        client.run(pin_blas_threads)
        client.run(tune_allocator)
        n_workers = max(1, len(client.scheduler_info().get("workers", {})))
        # batches of cells without timing them first (tasks are spread at once): about
        # 16 batches per worker keeps every worker busy and the scheduler's work small
        size = min(MAX_BATCH, max(1, -(-len(cells) // (16 * n_workers))))
        batches = [cells[i:i + size] for i in range(0, len(cells), size)]
        pending = set(client.map(run_cells, batches, pure=False, retries=2))
        healthy, strikes = time.monotonic(), 0
        while pending:
            try:
                finished, pending = dask_wait(pending, timeout=POLL_SECONDS,
                                              return_when="FIRST_COMPLETED")
            except TimeoutError:  # nothing finished within POLL_SECONDS
                finished = set()
            stored = _store_finished(finished, pending, done)
            if stored is None:
                raise lost("a batch was cancelled")
            trouble = None if stored else _cluster_trouble(client)
            if trouble is None:
                healthy, strikes = time.monotonic(), 0
            else:
                strikes += 1
                if strikes >= LOST_CHECKS and time.monotonic() - healthy > LOST_SECONDS:
                    raise lost(f"{trouble} for {LOST_SECONDS:g} s")
    except CamoptError:
        raise
    except (OSError, TimeoutError, CancelledError) as exc:  # scheduler or workers gone
        raise SolverError(f"--scheduler: {scheduler}: lost the Dask cluster: "
                          f"{_first_line(exc)}; finish with --resume") from None
    except Exception as exc:
        if type(exc).__module__.split(".")[0] not in ("distributed", "tornado", "dask"):
            raise  # a task's own error (a bug): not the cluster's
        raise SolverError(f"--scheduler: {scheduler}: lost the Dask cluster: "
                          f"{type(exc).__name__}: {_first_line(exc)}; finish with "
                          "--resume") from None
    finally:
        with contextlib.suppress(Exception):
            client.close(timeout=5)


def _store_finished(finished: set, pending: set, done: Callable[[Repeat], None]) -> int | None:
    """Store the cells of the ``finished`` batches; the number stored, None if a batch was
    cancelled. A batch whose result is gone (its worker died after finishing it: Dask
    marks it lost and runs it again) or cannot be fetched within ``FETCH_SECONDS`` goes
    back to ``pending``, with the batches not yet looked at: waiting for it without a
    bound would wait forever on a cluster left without workers."""
    stored = 0
    order = list(finished)
    for i, fut in enumerate(order):
        if fut.status == "error":  # the task's own error (a bug): raise it
            fut.result()
        if fut.status == "cancelled":
            return None
        try:
            if fut.status != "finished":
                raise TimeoutError
            results = fut.result(timeout=FETCH_SECONDS)[0]
        except TimeoutError:
            pending.update(order[i:])
            break
        for r in results:
            done(r)
        stored += 1
    return stored


def _cluster_trouble(client) -> str | None:
    """What is wrong with the cluster (the client not connected, no worker), None if
    nothing is. The workers are asked of the scheduler itself, each time (one RPC):
    ``client.scheduler_info()`` returns the client's cached copy, which a background
    refresh replaces with one that lists no workers, so read at the wrong moment it said
    "no worker" while workers ran. A scheduler slow to answer counts as alive while the
    client is connected: a dead one disconnects it."""
    if client.status != "running":
        return f"client {client.status}"
    try:
        threads = client.nthreads(callback_timeout=10)
    except Exception:  # busy or going away: the client's status tells which, next time
        return None
    return None if threads else "no worker"


def _first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0]


class CellStore(Protocol):
    """Where a running sweep's finished cells go, as emcee hands its sampler a backend:
    :class:`camopt.archive.sweeps.SweepWriter` (an HDF5 archive and its journal), or an
    in-memory store in tests. :meth:`add` puts the cell into the ``results`` mapping the
    store was opened with once it is stored."""

    def add(self, result: Repeat) -> None: ...

    def close(self) -> None: ...


def run_sweep(spec: SweepSpec, results: dict[tuple[int, int], Repeat],
              open_store: Callable[[int], CellStore], jobs: int = 1,
              executor: str = "local", scheduler: str | None = None,
              progress: Callable[[int, int], None] | None = None) -> dict:
    """Run every cell not yet in ``results``, storing each as it finishes in the store
    ``open_store(total cells)`` returns (opened once the cluster, if any, answered).
    ``results`` holds exactly the cells the store holds, also when interrupted
    mid-write."""
    if executor == "dask" and not scheduler:
        raise ConfigError("--scheduler", "", "give the Dask scheduler's address")
    cells = [c for c in spec.cells() if c.key not in results]
    total = len(results) + len(cells)
    client = _connect(scheduler) if executor == "dask" and scheduler else None
    try:
        writer = open_store(total)
    except BaseException:
        if client is not None:
            client.close()
        raise
    if progress:
        progress(len(results), total)

    def done(r: Repeat) -> None:
        writer.add(r)  # adds r to results once stored
        if progress:
            progress(len(results), total)
        interrupts.check()

    try:
        if client is not None:
            assert scheduler is not None
            _dask(client, cells, scheduler, done)
        else:
            _local(cells, jobs, done)
    except KeyboardInterrupt:
        interrupts.handled()
        with deferred():  # a second Ctrl-C does not stop the final snapshot
            writer.close()
        raise SweepInterrupted(f"{len(results)} of {total} cells done") from None
    except BaseException:  # the journal already holds every finished cell; a snapshot
        with contextlib.suppress(CamoptError, OSError), deferred():  # is a bonus
            writer.close()
        raise
    with deferred():
        writer.close()
    return results
