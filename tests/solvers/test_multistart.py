"""The multi-start local solvers (simplex, newton_pp) under the run's budget (issue #37):
a scipy solve inside one ``ask()`` is stopped by ``run.max_evaluations`` and
``run.max_seconds``, and a budget not reached changes nothing."""

from __future__ import annotations

import time

import numpy as np
import pytest

from camopt.config import RunSection
from camopt.engine.driver import run_repeat
from camopt.solvers import get_solver
from camopt.solvers.base import Budget, StopReason
from tests.solvers.test_local_solvers import Circle, LineFit


class _Cfg:
    path = "test.toml"

    def __init__(self, name: str, run: RunSection | None = None, **opts):
        self.run = run or RunSection()
        self.solver = get_solver(name).Options(**opts)


CASES = {"simplex": (LineFit, {"starts": 3}), "newton_pp": (Circle, {"starts": 4})}


def _repeat(name: str, run: RunSection | None = None, jobs: int = 1):
    problem_cls, opts = CASES[name]
    return run_repeat(problem_cls(), get_solver(name), _Cfg(name, run, **opts),
                      np.random.SeedSequence(2), 0, 1, jobs=jobs)


@pytest.mark.parametrize("name", ["simplex", "newton_pp"])
def test_run_max_evaluations_stops_a_local_solve_within_budget(name):
    """One start alone spends more than the limit; under it the repeat spends at most the
    limit (the meter keeps one evaluation for the stopped start's end point, which the
    driver evaluates: the brief allowed one population more), stops for the run's limit
    and says which start it stopped."""
    free = _repeat(name)
    first = int(free.history["nfev"][0])  # the first start's solve and its end point
    limit = max(first // 2, 3)
    assert first > limit
    cut = _repeat(name, RunSection(max_evaluations=limit))
    assert cut.nfev <= limit
    assert cut.message == StopReason.MAX_EVALUATIONS.value
    assert any(n.startswith("start 0 stopped: run.max_evaluations reached after")
               for n in cut.notes), cut.notes
    stopped = cut.table[-1]
    assert stopped["converged"] is False and stopped["feasible"] is False


@pytest.mark.parametrize("name", ["simplex", "newton_pp"])
def test_a_budget_not_reached_changes_nothing(name):
    """Limits far away: the same starts, end points, counts and messages as without."""
    free = _repeat(name)
    metered = _repeat(name, RunSection(max_evaluations=10**7, max_seconds=10**5))
    assert (metered.nfev, metered.message, metered.notes) == (free.nfev, free.message,
                                                              free.notes)
    np.testing.assert_array_equal(metered.x, free.x)
    assert metered.table == free.table


def test_a_spent_time_stops_the_first_start_before_it_evaluates():
    """A deadline already past: the start comes back unevaluated by scipy, not a design."""
    problem_cls, opts = CASES["simplex"]
    solver = get_solver("simplex")(problem_cls(), get_solver("simplex").Options(**opts),
                                   np.random.default_rng(0))
    solver.budget = Budget(deadline=time.perf_counter())
    x = solver.ask()[0]
    np.testing.assert_array_equal(x, solver.starts[0])
    assert solver.nfev == 0 and solver.results[0]["success"] is False
    assert solver.stop_reason() is StopReason.MAX_SECONDS


def test_with_max_evaluations_the_starts_run_in_order_whatever_the_jobs():
    """Each start's share of the budget is what the starts before it left, so a run with
    run.max_evaluations solves its starts in this process: the same with 2 jobs as 1."""
    run = RunSection(max_evaluations=150)
    one, two = _repeat("simplex", run, jobs=1), _repeat("simplex", run, jobs=2)
    assert (one.nfev, one.table) == (two.nfev, two.table)
