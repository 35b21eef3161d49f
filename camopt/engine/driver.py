"""The one loop every run goes through: ask -> evaluate -> tell -> record -> stop?

Repeats get independent generators from ``SeedSequence(seed).spawn(repeats)``, so
any repeat can be re-run alone from the archived entropy and spawn key.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

import numpy as np

from camopt.config import LoadedConfig
from camopt.core import batch
from camopt.core.capabilities import Stochastic
from camopt.core.documents import RobustCheck
from camopt.core.perf import fork_pool, kill_pool
from camopt.core.problem import Problem, deb_best
from camopt.core.record import Repeat, RunRecord, nfev_to_target, seed_id
from camopt.core.stats import succeeded
from camopt.engine import interrupts, robust
from camopt.engine.interrupts import deferred

# what a run needs before its loop, in a module of its own (``camopt validate`` imports it
# without the loop's pools, records and statistics): re-exported as the driver's API
from camopt.engine.setup import (  # noqa: F401
    build_solver,
    load,
    prepare,
    solver_options,
    validate,
)
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers import Solver, StopReason
from camopt.solvers.base import Budget


@dataclass(frozen=True)
class Progress:
    """What a progress callback sees after every iteration."""

    repeat: int
    repeats: int
    iteration: int
    max_iterations: int | None
    best_objective: float
    objective_name: str = "objective"  # the problem's (a robust run's: yield_margin)
    nfev: int = 0
    max_nfev: int | None = None
    """The evaluation budget: ``run.max_evaluations`` or the solver's ``evaluations``."""
    elapsed_s: float = 0.0
    max_seconds: float | None = None
    feasible: bool = True
    """Whether the best design so far is feasible; else ``worst`` names the constraint it
    violates most."""
    worst: str = ""

    @property
    def fraction(self) -> float | None:
        """This repeat's share done on its binding budget (iterations, evaluations or
        seconds: whichever is nearest its end); None when no budget is known."""
        shares = [self.iteration / self.max_iterations if self.max_iterations else None,
                  self.nfev / self.max_nfev if self.max_nfev else None,
                  self.elapsed_s / self.max_seconds if self.max_seconds else None]
        known = [x for x in shares if x is not None]
        return min(1.0, max(known)) if known else None

    @property
    def best_text(self) -> str:
        """``best objective_j 0.0123`` or ``infeasible, worst: rod_travel``."""
        if not self.feasible:
            return f"infeasible, worst: {self.worst or '-'}"
        return f"best {self.objective_name} {self.best_objective:.6g}"


def run_repeat(problem: Problem, solver_cls: type[Solver], config: LoadedConfig,
               child: np.random.SeedSequence, index: int, repeats: int,
               callback: Callable[[Progress], None] | None = None, jobs: int = 1
               ) -> Repeat:
    """Run one repeat of the solver to its stop reason, or to the run's own limits
    (``run.max_evaluations``, ``run.max_seconds``), whichever comes first; ``jobs``
    worker processes are lent to the solver (multi-start solvers spread their starts)."""
    start = time.perf_counter()
    stochastic = problem if isinstance(problem, Stochastic) else None
    if stochastic is not None:
        stochastic.reseed(robust.repeat_seed(child, 0))
    solver = build_solver(problem, solver_cls, config, np.random.default_rng(child))
    solver.jobs = jobs
    max_nfev, max_s = config.run.max_evaluations, config.run.max_seconds
    # the same limits for a stage that runs many evaluations in one iteration (a polish)
    solver.budget = Budget(max_nfev, None if max_s is None else start + max_s)
    nfev, best_f, mean_f, best_v = [], [], [], []
    while (reason := _stop(solver, start, max_nfev, max_s)) is None:
        if stochastic is not None:
            stochastic.new_generation()  # common random numbers: one set per generation
        interrupts.check()
        X = solver.ask()
        ev = batch.evaluate(problem, X)  # a population is one chunk; given designs, many
        solver.tell(X, ev)
        _, bev = solver.best()
        pop_f = solver.population_objectives()
        pop_f = ev.f if pop_f is None else pop_f
        finite = pop_f[np.isfinite(pop_f)]
        nfev.append(solver.nfev)
        best_f.append(float(bev.f[0]))
        best_v.append(float(bev.violation[0]))
        mean_f.append(float(finite.mean()) if finite.size else np.inf)
        if callback:
            g = np.asarray(bev.g, dtype=float).reshape(-1)
            feasible = bool(bev.feasible[0])
            worst = (problem.constraint_names[int(np.nanargmax(g))]
                     if not feasible and g.size and np.isfinite(g).any() else "")
            callback(Progress(index, repeats, solver.nit, solver.max_iterations(), best_f[-1],
                              problem.objective_name, solver.nfev,
                              max_nfev or getattr(solver.options, "evaluations", None),
                              time.perf_counter() - start, max_s, feasible, worst))
    x, bev = solver.best()
    if stochastic is not None:  # the solver's best and the finalists on fresh draws
        x, bev = stochastic.select(x, robust.repeat_seed(child, 1))
    history = {"nfev": np.array(nfev, dtype=np.int64), "best_objective": np.array(best_f),
               "mean_objective": np.array(mean_f), "best_violation": np.array(best_v)}
    fun, feasible, target = float(bev.f[0]), bool(bev.feasible[0]), config.run.target
    return Repeat(
        x=x, fun=fun, success=bool(succeeded([fun], [feasible], target)[0]),
        message=reason.value, nfev=solver.nfev, nit=solver.nit,
        index=index, spawn_key=tuple(child.spawn_key),
        seed=seed_id(child),
        feasible=feasible, violation=float(bev.violation[0]),
        converged_nit=converged_iteration(np.array(best_f), np.array(best_v)),
        nfev_to_target=nfev_to_target(history, target),
        wall_s=time.perf_counter() - start, history=history, g=bev.g[0],
        notes=(*solver.notes(), *(stochastic.notes if stochastic else ())),
        table=solver.table(),
        nominal_x=None if stochastic is None else stochastic.nominal_design(),
    )


def _stop(solver: Solver, start: float, max_nfev: int | None, max_s: float | None
          ) -> StopReason | None:
    """The solver's own stop reason, else the run's limits (checked between iterations)."""
    reason = solver.stop_reason()
    if reason is None and solver.nit > 0:
        if max_nfev is not None and solver.nfev >= max_nfev:
            return StopReason.MAX_EVALUATIONS
        if max_s is not None and time.perf_counter() - start >= max_s:
            return StopReason.MAX_SECONDS
    return reason


CONVERGENCE_TOL = 1e-6


def converged_iteration(best_f: Floats, best_v: Floats, tol: float = CONVERGENCE_TOL) -> int:
    """First iteration (1-based) from which the best objective stays within ``tol`` of its
    final value with the final violation."""
    if best_f.size == 0:
        return 0
    with np.errstate(invalid="ignore"):  # inf - inf: equal infinities count as close
        near = (best_f == best_f[-1]) | (np.abs(best_f - best_f[-1]) <= tol)
    close = near & (best_v <= best_v[-1])
    far = np.flatnonzero(~close)
    return int(far[-1] + 2) if far.size else 1


def best_repeat(records: list[Repeat]) -> Repeat:
    """The best repeat by Deb's rules (least violation, then lowest objective; the first
    of equals)."""
    return records[deb_best([r.fun for r in records], [r.violation for r in records])]


_REPEATS: tuple | None = None  # what forked workers of execute(jobs > 1) run


def _repeat_in_worker(i: int) -> Repeat:
    assert _REPEATS is not None
    problem, solver_cls, config, children = _REPEATS
    return run_repeat(problem, solver_cls, config, children[i], i, len(children))


def _parallel_repeats(problem: Problem, solver_cls: type[Solver], config: LoadedConfig,
                      children: list[np.random.SeedSequence], jobs: int,
                      callback: Callable[[Progress], None] | None,
                      finished: list[Repeat]) -> None:
    """Repeats in ``jobs`` forked workers, appended to ``finished`` as they end (so an
    interruption keeps those); each repeat is independent (its own child seed), so the
    records equal a sequential run's but for wall times and order."""
    global _REPEATS
    _REPEATS = (problem, solver_cls, config, children)
    pool = fork_pool(min(jobs, len(children)))
    futures: list[Any] = []
    try:
        futures = [pool.submit(_repeat_in_worker, i) for i in range(len(children))]
        for fut in as_completed(futures):
            rec = fut.result()
            finished.append(rec)
            if callback:
                callback(Progress(len(finished) - 1, len(children), rec.nit, rec.nit, rec.fun,
                                  problem.objective_name))
    except BrokenProcessPool:  # a worker was killed (OOM killer, kill): keep what finished
        kept = {r.index for r in finished}
        for fut in futures:
            if fut.done() and not fut.cancelled() and fut.exception() is None \
                    and fut.result().index not in kept:
                finished.append(fut.result())
        kill_pool(pool)
        raise
    except BaseException:
        kill_pool(pool)
        raise
    finally:
        _REPEATS = None
    pool.shutdown(wait=True)


def execute(config: LoadedConfig, seed: int | None = None, repeats: int | None = None,
            callback: Callable[[Progress], None] | None = None, jobs: int = 1,
            check_progress: batch.RowsDone | None = None) -> RunRecord:
    """Run a validated config: every repeat, then the best design's metrics and analysis.
    ``seed`` and ``repeats`` override the config's (prefer setting ``run.seed`` and
    ``run.repeats`` in the config, so the archive records the config as run). ``jobs``
    worker processes run the repeats side by side, or a single repeat's independent
    starts (multi-start solvers); results do not depend on it.

    A KeyboardInterrupt (Ctrl-C, or SIGTERM turned into one by the CLI) after at least one
    finished repeat ends the run early: the record holds the finished repeats and
    ``interrupted`` is set, so the caller can keep them. Before any repeat finished it
    propagates. ``check_progress`` is told the rows done of a robust run's final check
    (:func:`camopt.engine.robust.check`) after each chunk."""
    problem, solver_cls = prepare(config)
    seed = config.run.seed if seed is None else seed
    repeats = config.run.repeats if repeats is None else repeats
    children = np.random.SeedSequence(seed).spawn(repeats)
    records: list[Repeat] = []
    interrupted, failure = False, None
    try:
        if jobs > 1 and repeats > 1:
            _parallel_repeats(problem, solver_cls, config, children, jobs, callback, records)
        else:
            for i, child in enumerate(children):
                records.append(run_repeat(problem, solver_cls, config, child, i, repeats,
                                          callback, jobs))
    except KeyboardInterrupt:
        if not records:
            raise
        interrupts.handled()
        interrupted = True
    except BrokenProcessPool:
        failure = "a worker process died (killed, or out of memory)"
        if not records:
            raise SolverError(f"{config.path}: --jobs: {failure} before any repeat "
                              "finished; nothing written") from None
        interrupted = True
    with deferred() as signals:  # finished repeats are kept whatever Ctrl-C comes now
        records.sort(key=lambda r: r.index)
        best = best_repeat(records)
        record = RunRecord(
            config, seed, records, best, dict(problem.metrics(best.x)),
            dict(problem.analysis(best.x)), problem.names, problem.scale,
            problem.constraint_names, problem.objective_name, interrupted,
            _robust_check(problem, records, best, seed, check_progress), failure, problem,
            dict(problem.findings(best.x)))
    record.interrupted |= bool(signals)
    return record


def _robust_check(problem: Problem, records: list[Repeat], best: Repeat, seed: int,
                  progress: batch.RowsDone | None = None) -> RobustCheck | None:
    """Stochastic (robust) runs: the problem's final check of the best design and of the
    best nominally feasible design the repeats saw (``progress`` told the rows done);
    None otherwise."""
    if not isinstance(problem, Stochastic):
        return None
    return problem.final_check(best.x, [r.nominal_x for r in records
                                        if r.nominal_x is not None], seed, progress)
