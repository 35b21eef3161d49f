"""The SLSQP polish stage of the population solvers, on the sphere case."""

from __future__ import annotations

import time

import numpy as np
import pytest

from camopt.config import RunSection
from camopt.core.problem import Evaluation, Variable
from camopt.engine.driver import run_repeat
from camopt.errors import SolverError
from camopt.solvers import get_solver
from camopt.solvers.base import Budget, StopReason
from camopt.solvers.polish import PolishOptions, polish, polish_within
from tests.conftest import SphereConfig, SphereProblem


class _Cfg:
    run = RunSection()
    path = "test.toml"

    def __init__(self, name: str, **opts):
        self.solver = get_solver(name).Options(**opts)


SHORT = {"pso": {"particles": 10, "iterations": 5}, "de_gr": {"population": 10, "generations": 5}}


@pytest.mark.parametrize("name", ["pso", "de_gr"])
def test_polish_takes_a_short_search_to_the_optimum(name):
    """Five iterations leave the sphere's best far from x = 0.3; the polish finishes it."""
    problem = SphereProblem(SphereConfig())
    plain = run_repeat(problem, get_solver(name), _Cfg(name, **SHORT[name]),
                       np.random.SeedSequence(0), 0, 1)
    polished = run_repeat(problem, get_solver(name),
                          _Cfg(name, **SHORT[name], polish={}), np.random.SeedSequence(0), 0, 1)
    assert plain.fun > 1e-3
    assert polished.fun < 1e-8 and polished.feasible
    assert polished.nit == plain.nit + 1 and polished.nfev > plain.nfev
    assert any("replaced" in n for n in polished.notes)
    np.testing.assert_allclose(polished.x, 0.3, atol=1e-4)


def test_polish_minimises_a_metric_under_limits_and_keeps_a_margin():
    """Epsilon-constraint use: minimise |x| subject to f <= 0.01 (and x0 + x1 <= 1.5)."""
    problem = SphereProblem(SphereConfig(n_var=2))
    opts = PolishOptions(minimise="norm", limits={"f": 0.01}, margin=1e-6)
    x, nfev, _ = polish(problem, np.array([0.3, 0.3]), opts)
    ev = problem.evaluate(x[None, :])
    # closest point to the origin on the circle |x - 0.3| = 0.1: along the diagonal
    np.testing.assert_allclose(ev.extras["norm"][0], np.hypot(0.3, 0.3) - 0.1, rtol=1e-4)
    assert ev.f[0] <= 0.01 * (1 - 0.5e-6) and nfev > 0  # inside the limit by the margin


def test_polish_rejects_unknown_metrics_before_the_search():
    problem = SphereProblem(SphereConfig())
    with pytest.raises(SolverError, match="polish.minimise: no metric 'torque'"):
        get_solver("pso")(problem, get_solver("pso").Options(polish={"minimise": "torque"}),
                          np.random.default_rng(0))


def test_integer_aware_polish_fixes_integers_and_tries_neighbours():
    """Sphere with x0 integer (best at 0) and x1, x2 continuous (best at 0.3), from
    x0 = 1: the continuous ones are polished with x0 held, then x0 = 0 (polished again)
    wins and x0 = -1 does not: the end point is (0, 0.3, 0.3) to 1e-6, and x0 stayed an
    integer throughout."""
    problem = SphereProblem(SphereConfig(n_var=3, integer_first=True))
    x, nfev, message = polish(problem, np.array([1.0, -0.5, 0.8]), PolishOptions())
    np.testing.assert_allclose(x, [0.0, 0.3, 0.3], atol=1e-6)
    assert x[0] == 0.0 and nfev > 0
    assert "x0 1 -> 0" in message


def test_integer_aware_polish_reaches_past_a_bump():
    """An objective over an integer with a bump: f(n) = (n - 4)^2 + 6 [n == 2] on n in
    0..6, start n = 0. One step (0 -> 1) improves, 1 -> 2 does not; with integer_reach = 2
    the search looks past the bump to n = 3 and goes on to the optimum 4."""

    class Bumpy(SphereProblem):
        def evaluate(self, X):
            X = np.atleast_2d(X)
            n = X[:, 0]
            f = (n - 4) ** 2 + 6.0 * (n == 2) + (X[:, 1] - 0.3) ** 2
            return Evaluation(f, np.full((len(X), 1), -1.0), {"norm": f})

    problem = Bumpy(SphereConfig(n_var=2, integer_first=True))
    problem.variables = (Variable("x0", 0.0, 6.0, integer=True), problem.variables[1])
    x, _, _ = polish(problem, np.array([0.0, 0.0]), PolishOptions(integer_reach=2))
    np.testing.assert_allclose(x, [4.0, 0.3], atol=1e-6)
    y, _, _ = polish(problem, np.array([0.0, 0.0]), PolishOptions(integer_reach=1))
    assert y[0] == 1.0  # one step of reach stops at the bump


class _Lowered(SphereProblem):
    """The sphere with its objective lowered by 0.02 (negative near the optimum)."""

    def evaluate(self, X):
        ev = super().evaluate(X)
        return Evaluation(ev.f - 0.02, ev.g, ev.extras)


def test_a_negative_limit_caps_from_above():
    """Limits are upper limits whatever their sign: f - 0.02 <= -0.01 is f <= 0.01."""
    opts = {"minimise": "norm", "margin": 1e-9}
    x, _, _ = polish(SphereProblem(SphereConfig(n_var=2)), np.array([0.3, 0.3]),
                     PolishOptions(**opts, limits={"f": 0.01}))
    y, _, _ = polish(_Lowered(SphereConfig(n_var=2)), np.array([0.3, 0.3]),
                     PolishOptions(**opts, limits={"f": -0.01}))
    np.testing.assert_allclose(y, x, atol=1e-5)


class _Staircase(SphereProblem):
    """Maximise x0 + x1 under x0 + x1 <= 1 measured in steps of 1e-4, like a measure
    taken on samples: finite differences see a flat constraint and SLSQP overshoots."""

    def evaluate(self, X):
        X = np.atleast_2d(X)
        s = X[:, 0] + X[:, 1]
        g = np.ceil((s - 1.0) / 1e-4) * 1e-4
        return Evaluation(-s, g[:, None], {"norm": np.linalg.norm(X, axis=1)})


def test_polish_restores_feasibility_when_slsqp_stops_outside():
    problem = _Staircase(SphereConfig(n_var=2))
    x, _, message = polish(problem, np.array([0.2, 0.2]), PolishOptions())
    ev = problem.evaluate(x[None, :])
    assert ev.feasible[0], message
    assert x.sum() == pytest.approx(1.0, abs=2e-4)


class _Budgeted(_Cfg):
    def __init__(self, name: str, max_evaluations: int, **opts):
        super().__init__(name, **opts)
        self.run = RunSection(max_evaluations=max_evaluations)


@pytest.mark.parametrize("name", ["pso", "de_gr"])
def test_run_max_evaluations_stops_a_polish(name):
    """Five iterations of 10 spend 50 evaluations; the polish alone would spend more than
    60. Under run.max_evaluations = 60 the scipy solve is stopped from inside: the repeat
    spends at most 60 (the polished point's own evaluation included), says why it
    stopped, and keeps the best design the polish evaluated (better than the search's)."""
    problem = SphereProblem(SphereConfig())
    args = (problem, get_solver(name))
    seed = (np.random.SeedSequence(0), 0, 1)
    plain = run_repeat(*args, _Cfg(name, **SHORT[name]), *seed)
    free = run_repeat(*args, _Cfg(name, **SHORT[name], polish={}), *seed)
    cut = run_repeat(*args, _Budgeted(name, 60, **SHORT[name], polish={}), *seed)
    assert plain.nfev == 50 and free.nfev > 60
    assert plain.nfev < cut.nfev <= 60
    assert cut.message == StopReason.MAX_EVALUATIONS.value
    assert any("stopped: run.max_evaluations reached after" in n for n in cut.notes)
    assert cut.fun < plain.fun


def test_a_spent_time_stops_a_polish_before_its_first_evaluation():
    """A deadline already past: nothing is evaluated and the start comes back."""
    problem = SphereProblem(SphereConfig(n_var=2))
    x0 = np.array([0.1, 0.2])
    x, nfev, message, reason = polish_within(problem, x0, PolishOptions(), None,
                                             Budget(deadline=time.perf_counter()), 0)
    np.testing.assert_array_equal(x, x0)
    assert (nfev, reason) == (0, StopReason.MAX_SECONDS) and "stopped" in message


def test_a_budget_not_reached_changes_nothing():
    """The meter is transparent: the same end point, count and message as without it."""
    problem = SphereProblem(SphereConfig(n_var=2))
    x0 = np.array([0.1, 0.2])
    free = polish(problem, x0, PolishOptions())
    x, nfev, message, reason = polish_within(problem, x0, PolishOptions(), None,
                                             Budget(max_nfev=10**6), 0)
    np.testing.assert_array_equal(x, free[0])
    assert (nfev, message, reason) == (free[1], free[2], None)


SHIPPED = ("fast_switch_de.toml", ["solver.population=20", "solver.generations=5",
                                   "solver.polish.maxiter=20", "run.repeats=1"])


def _shipped(*overrides: str):
    from camopt.engine.driver import execute, load
    from tests.conftest import CONFIGS

    name, short = SHIPPED
    return execute(load(CONFIGS / name, [*short, *overrides])).best


@pytest.fixture(scope="module")
def shipped_free():
    return _shipped()


def test_a_shipped_polish_config_is_the_same_under_a_budget_it_does_not_reach(shipped_free):
    """``fast_switch_de`` (DE-gr with ``[solver.polish]``; integer coils: the mixed
    polish), shortened (SLSQP's iterations too), at its seed: with limits far away its
    best repeat is the same, bit for bit (design, objective, evaluations, stop reason,
    notes, table)."""
    free = shipped_free
    far = _shipped("run.max_evaluations=100000000", "run.max_seconds=100000")
    np.testing.assert_array_equal(far.x, free.x)
    assert (far.fun, far.nfev, far.message, far.notes) == (free.fun, free.nfev,
                                                           free.message, free.notes)
    assert far.table == free.table


def test_a_tiny_max_evaluations_stops_a_shipped_polish_within_budget(shipped_free):
    """Five generations of 20 spend 100 evaluations; under run.max_evaluations = 130 the
    polish that would spend more stops from inside at most one population past it (in
    fact within it: one evaluation is kept for the end point)."""
    assert shipped_free.nfev > 130
    cut = _shipped("run.max_evaluations=130")
    assert 100 < cut.nfev <= 130 + 20
    assert cut.message == StopReason.MAX_EVALUATIONS.value
