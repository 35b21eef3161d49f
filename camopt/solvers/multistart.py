"""Shared machinery of the local solvers that scipy already provides (root, Nelder-Mead).

Each ask() runs one complete local solve from one start, inside scipy, and returns its
end point; the driver then evaluates that point like any other candidate. Starts are
``x0`` or the case's initial design (``Problem.initial_x``) and uniform draws within the
bounds from the run's generator. Distinct end points are clustered in coordinates
normalised by the bounds.

With ``jobs`` > 1 (``camopt run --jobs``) the starts' local solves run at the first ask in
forked worker processes, and the end points are handed out one per ask as before, so the
run (histories included) is the same whatever the worker count.

A start counts only when it *converged inside the bounds* (the local solver's own
success test and every variable within its bounds). Any other end point is a last
iterate, not a design: it is never the best, and when no start converged the repeat's
best is reported infeasible (objective +inf) with a note saying so.

A local solve runs under the run's budget: every call scipy makes of the
start's function goes through a :class:`Meter` that counts it against
``run.max_evaluations`` (one evaluation kept for the driver's evaluation of the end
point) and ``run.max_seconds``; once either is spent the meter raises out of scipy, the
start ends unconverged on the best point it evaluated and the repeat stops with the
run's limit as its reason. With ``run.max_evaluations`` set, the starts run in order in
this process whatever ``jobs`` is (a start's share of the budget is what the starts
before it left). Without a limit reached the meter changes nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypedDict, cast

import numpy as np

from camopt.config.models import SolverOptions
from camopt.core.documents import Row
from camopt.core.perf import fork_pool, kill_pool
from camopt.core.problem import Evaluation, Problem
from camopt.mechanics import Bools, Floats
from camopt.solvers.base import Budget, Solver, StopReason, best_index

_SOLVING: MultiStart | None = None  # the solver whose starts forked workers solve


class StartRecord(TypedDict, total=False):
    """A local solve's record, one per start (the table's columns beside the design):
    whether it converged (``success``) inside the bounds (``in_bounds``), the local
    solver's ``message`` and evaluations (``nfev``), where the run's budget stopped it
    (``stopped``), and what a solver adds (``residual_max``, ``jacobian_cond``: a root
    finder's largest residual and its Jacobian's condition number)."""

    success: bool
    message: str
    nfev: int
    in_bounds: bool
    stopped: StopReason
    residual_max: float
    jacobian_cond: float


def _solve_start(i: int) -> tuple[Floats, StartRecord]:
    assert _SOLVING is not None
    return _SOLVING.solve_within_budget(_SOLVING.starts[i])


class BudgetSpent(Exception):
    """Raised by a :class:`Meter` out of a scipy solve when the run's budget is spent
    (control flow inside :meth:`MultiStart.solve_within_budget`, never seen outside)."""

    def __init__(self, reason: StopReason) -> None:
        super().__init__(reason.value)
        self.reason = reason


class Meter:
    """Counts a local solve's function calls against ``budget`` (``used`` evaluations
    already spent by the run) and keeps the point whose value scored least
    (``score``: the value's badness, e.g. the penalised objective or the largest
    residual); a call that would pass the budget, or any once the time is spent, raises
    :class:`BudgetSpent` instead of being made."""

    def __init__(self, budget: Budget, used: int) -> None:
        self.budget, self.used = budget, used
        self.count = 0
        self.best: tuple[Floats, float] | None = None

    def wrap(self, fun: Callable[[Floats], Any], score: Callable[[Any], float]
             ) -> Callable[[Floats], Any]:
        """``fun`` (of the bounds-normalised variables) with each call counted."""
        def metered(u: Floats) -> Any:
            reason = self.budget.spent(self.used + self.count + 1)
            if reason is not None:
                raise BudgetSpent(reason)
            value = fun(u)
            self.count += 1
            badness = float(score(value))
            badness = np.inf if badness != badness else badness  # NaN: worst
            if self.best is None or badness < self.best[1]:
                self.best = (np.array(u, dtype=float), badness)
            return value
        return metered


class MultiStartOptions(SolverOptions):
    """What every multi-start solver's options hold (each sets its own defaults)."""

    starts: int
    x0: dict[str, float] | None
    distinct_tol: float


class MultiStart(Solver):
    """Base of solvers that run one scipy local solve per start."""

    integers = False
    options: MultiStartOptions

    def __init__(self, problem: Problem, options: MultiStartOptions,
                 rng: np.random.Generator) -> None:
        super().__init__(problem, options, rng)
        self.lo, self.hi = problem.lower, problem.upper
        self.starts = self._starts()
        self.results: list[StartRecord] = []
        self.X: list[Floats] = []
        self.ev: Evaluation | None = None
        self._solved: list[tuple[Floats, StartRecord]] | None = None
        self.meter: Meter | None = None
        """The running start's meter (None: no run limit set)."""
        self.stopped: StopReason | None = None
        """The run's limit that stopped a start's local solve, if one did."""

    def _starts(self) -> Floats:
        n = self.options.starts
        first = []
        initial = self.problem.initial_x()
        if self.options.x0 is not None:
            first.append(self.problem.from_display(self.options.x0))
        elif initial is not None:
            first.append(np.asarray(initial, dtype=float))
        rand = self.problem.sample(self.rng, max(n - len(first), 0))
        return np.vstack([*(f[None, :] for f in first), rand])[:n]

    def max_iterations(self) -> int:
        return len(self.starts)

    def local_solve(self, x0: Floats) -> tuple[Floats, StartRecord]:  # pragma: no cover
        """One scipy local solve from ``x0``: its end point and a record (success, nfev,
        ...). The function handed to scipy goes through :meth:`metered`."""
        raise NotImplementedError

    def metered(self, fun: Callable[[Floats], Any], score: Callable[[Any], float]
                ) -> Callable[[Floats], Any]:
        """``fun`` as a local solve hands it to scipy: counted by the running start's
        :class:`Meter` (unchanged when the run sets no limit)."""
        return fun if self.meter is None else self.meter.wrap(fun, score)

    def stopped_record(self, x: Floats) -> StartRecord:
        """A stopped start's record beyond success, message and nfev (subclasses add
        what their table shows of every start)."""
        return {}

    def solve_within_budget(self, x0: Floats) -> tuple[Floats, StartRecord]:
        """:meth:`local_solve` under the run's budget (:attr:`Solver.budget`): unchanged
        while it holds; once spent, the best point the solve evaluated (unconverged,
        never a design) with a record saying where it stopped (``stopped``: the limit)."""
        budget = self.budget
        if budget.max_nfev is None and budget.deadline is None:
            return self.local_solve(x0)
        self.meter = Meter(Budget(None if budget.max_nfev is None else budget.max_nfev - 1,
                                  budget.deadline), self.nfev)
        try:
            return self.local_solve(x0)
        except BudgetSpent as stop:
            meter = self.meter
            x = (np.asarray(x0, dtype=float) if meter.best is None
                 else self.problem.from_unit(meter.best[0]))
            return x, {"success": False, **self.stopped_record(x),
                       "message": f"stopped: {stop.reason.value} after {meter.count} "
                       "evaluations; the best point it evaluated", "nfev": meter.count,
                       "stopped": stop.reason}
        finally:
            self.meter = None

    def _solve_all(self) -> list[tuple[Floats, StartRecord]]:
        """Every start's local solve in ``jobs`` forked workers, in start order."""
        global _SOLVING
        _SOLVING = self
        pool = fork_pool(min(self.jobs, len(self.starts)))
        try:
            solved = list(pool.map(_solve_start, range(len(self.starts))))
        except BaseException:
            kill_pool(pool)
            raise
        finally:
            _SOLVING = None
        pool.shutdown(wait=True)
        return solved

    def ask(self) -> Floats:
        parallel = self.jobs > 1 and len(self.starts) > 1 and self.budget.max_nfev is None
        if parallel and self._solved is None:
            self._solved = self._solve_all()
        if self._solved is not None:
            x, info = self._solved[self.nit]
        else:
            x, info = self.solve_within_budget(self.starts[self.nit])
        self.stopped = info.pop("stopped", None) or self.stopped
        info.setdefault("in_bounds", bool(np.all((x >= self.lo) & (x <= self.hi))))
        self.results.append(info)
        self.nfev += info.pop("nfev", 0)
        return x[None, :]

    def tell(self, X: Floats, ev: Evaluation) -> None:
        self.nfev += len(X)
        self.nit += 1
        self.X.append(X[0])
        self.ev = ev if self.ev is None else Evaluation.concat([self.ev, ev])

    def converged(self) -> Bools:
        """Which starts converged inside the bounds (the only end points that are designs)."""
        return np.array([bool(r["success"]) and bool(r["in_bounds"]) for r in self.results],
                        dtype=bool)

    def best(self) -> tuple[Floats, Evaluation]:
        """The best converged start by Deb's rules; with none, the first start's end point
        with objective +inf (infeasible by construction: it is not a solution)."""
        assert self.ev is not None
        ok = np.flatnonzero(self.converged())
        if ok.size:
            i = int(ok[best_index(self.ev.take(ok))])
            return self.X[i].copy(), self.ev.take(i)
        ev = self.ev.take(0)
        return self.X[0].copy(), Evaluation(np.full(1, np.inf), ev.g, ev.extras)

    def stop_reason(self) -> StopReason | None:
        if self.stopped is not None:
            return self.stopped
        return StopReason.EXHAUSTED if self.nit >= len(self.starts) else None

    def reached(self) -> Bools:
        """Which starts count as having reached an optimum (subclasses refine; never one
        that did not converge inside the bounds)."""
        return self.converged()

    def clusters(self) -> Floats:
        """Cluster id of each end point that reached an optimum (-1 for the others)."""
        ids = np.full(len(self.X), -1)
        centres: list[Floats] = []
        ok = self.reached()
        for i, x in enumerate(self.X):
            if not ok[i]:
                continue
            u = self.problem.to_unit(x)
            for j, centre in enumerate(centres):
                if np.max(np.abs(u - centre)) <= self.options.distinct_tol:
                    ids[i] = j
                    break
            else:
                centres.append(u)
                ids[i] = len(centres) - 1
        return ids

    def table(self) -> list[Row]:
        assert self.ev is not None
        ids = self.clusters()
        conv = self.converged()
        rows = []
        for i, (x, r) in enumerate(zip(self.X, self.results)):
            row: Row = {"start": i, "cluster": int(ids[i])}
            row.update({f"start_{k}": v for k, v in
                        self.problem.to_display(self.starts[i]).items()})
            row.update(self.problem.to_display(x))
            row[self.problem.objective_name] = float(self.ev.f[i])
            row.update(cast(Row, r))  # scalars: StopReason is a str
            row["converged"] = bool(conv[i])
            row["feasible"] = bool(self.ev.feasible[i] and conv[i])
            rows.append(row)
        return rows

    def convergence_notes(self) -> list[str]:
        """Plain lines on starts that did not converge inside the bounds (none if all did),
        and on a start the run's budget stopped."""
        stopped = [f"start {i} {r['message']}" for i, r in enumerate(self.results)
                   if str(r.get("message", "")).startswith("stopped: run.")]
        return self._unconverged_notes() + stopped

    def _unconverged_notes(self) -> list[str]:
        failed = [r for r in self.results if not r["success"]]
        outside = [r for r in self.results if r["success"] and not r["in_bounds"]]
        if len(failed) + len(outside) == 0:
            return []
        tail = (f"{len(failed)} did not converge, {len(outside)} converged outside the "
                f"bounds")
        if not self.converged().any():
            return [f"no start converged inside the bounds ({tail}): no solution; the design "
                    f"shown is start 0's end point, infeasible by construction"]
        return [f"{len(failed) + len(outside)} of {len(self.results)} starts discarded "
                f"({tail})"]

    def distinct_summary(self, what: str, missed: str) -> str:
        """One line: how many distinct end points the starts reached, and their spread."""
        ids = self.clusters()
        found = len(set(ids[ids >= 0].tolist()))
        text = f"{found} distinct {what} from {len(self.X)} starts"
        failed = int(np.sum(ids < 0))
        if failed:
            text += f" ({failed} {missed})"
        if found > 1:
            ends = np.array([x for x, i in zip(self.X, ids) if i >= 0])
            spread = ", ".join(
                f"{v.name} {lo * v.scale:.4g}..{hi * v.scale:.4g}"
                for v, lo, hi in zip(self.problem.variables, ends.min(0), ends.max(0)))
            text += f": not unique ({spread})"
        return text
