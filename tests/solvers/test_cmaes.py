"""The CMA-ES core (Hansen 2016) and the polish's cmaes stage, on problems with known
answers (the contract tests cover the ``cmaes`` solver on the sphere)."""

from __future__ import annotations

import numpy as np

from camopt.solvers.base import StopReason
from camopt.solvers.cmaes import CMAES, CMACore, CMAESOptions, deb_order
from camopt.solvers.polish import PolishOptions, polish
from tests.conftest import SphereConfig, SphereProblem


def test_core_solves_rosenbrock():
    """4-D Rosenbrock scaled into the unit box (x = 4 u - 2, minimum at u = 0.75): from
    u = 0.3 the core reaches the minimum to 1e-6 in at most 60 000 evaluations."""
    core = CMACore(np.full(4, 0.3), 0.2, np.random.default_rng(0))
    _minimise_rosenbrock(core)
    np.testing.assert_allclose(core.mean, 0.75, atol=1e-6)


def _minimise_rosenbrock(core: CMACore, check=lambda core: None) -> None:
    """Run ``core`` on the 4-D Rosenbrock scaled into the unit box (x = 4 u - 2) until its
    step falls below 1e-13 or 60 000 evaluations, calling ``check`` after every tell."""
    evals = 0
    while evals < 60_000 and core.step_size() > 1e-13:
        U = core.ask()
        X = 4 * U - 2
        f = np.sum(100 * (X[:, 1:] - X[:, :-1] ** 2) ** 2 + (1 - X[:, :-1]) ** 2, axis=1)
        core.tell(U, deb_order(f, np.zeros(len(f))))
        check(core)
        evals += len(U)


def test_active_core_solves_rosenbrock_with_a_positive_definite_covariance():
    """Active CMA-ES (Hansen 2016, Eq 53): the worst lambda - mu weigh in negatively,
    summing to minus the least of its three bounds, and the covariance stays positive
    definite every generation; from u = 0.3 it reaches the scaled 4-D Rosenbrock's
    minimum to 1e-6, as the passive core does."""
    rng = np.random.default_rng(0)
    core = CMACore(np.full(4, 0.3), 0.2, rng, popsize=12, active=True)
    assert core.negative is not None and np.all(core.negative < 0)
    alpha = min(1 + core.c1 / core.cmu, (1 - core.c1 - core.cmu) / (4 * core.cmu),
                1 + 2 * core.negative.sum() ** 2 / np.sum(core.negative**2) / (core.mueff + 2))
    np.testing.assert_allclose(core.negative.sum(), -alpha, rtol=1e-12)
    assert CMACore(np.full(4, 0.3), 0.2, rng).negative is None  # passive by default

    def positive_definite(c: CMACore) -> None:
        assert np.linalg.eigvalsh(c.C).min() > 0
    _minimise_rosenbrock(core, positive_definite)
    np.testing.assert_allclose(core.mean, 0.75, atol=1e-6)


def test_deb_order_puts_less_violation_first():
    f = np.array([1.0, 0.0, 2.0, np.nan])
    v = np.array([0.0, 0.5, 0.0, 0.0])
    assert deb_order(f, v).tolist() == [0, 2, 3, 1]


def test_cmaes_stage_minimises_a_metric_under_limits():
    """Epsilon-constraint use through Deb's ranking: minimise |x| subject to f <= 0.01:
    the closest point to the origin on the circle |x - 0.3| = 0.1 (to 1e-4 relative), and
    the limit holds."""
    problem = SphereProblem(SphereConfig(n_var=2))
    opts = PolishOptions(method=["cmaes"], minimise="norm", limits={"f": 0.01}, sigma=0.05,
                         evaluations=6000)
    x, nfev, message = polish(problem, np.array([0.3, 0.3]), opts, np.random.default_rng(1))
    ev = problem.evaluate(x[None, :])
    np.testing.assert_allclose(ev.extras["norm"][0], np.hypot(0.3, 0.3) - 0.1, rtol=1e-4)
    assert ev.f[0] <= 0.01 and nfev <= 6000 + 2 and "cmaes" in message


def test_cmaes_stage_same_generator_same_result():
    problem = SphereProblem(SphereConfig(n_var=3))
    opts = PolishOptions(method=["cmaes"], evaluations=500)
    a = polish(problem, np.full(3, -0.5), opts, np.random.default_rng(7))[0]
    b = polish(problem, np.full(3, -0.5), opts, np.random.default_rng(7))[0]
    c = polish(problem, np.full(3, -0.5), opts, np.random.default_rng(8))[0]
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def _run(options: CMAESOptions, seed: int, budget: int = 20_000):
    problem = SphereProblem(SphereConfig(n_var=3))
    solver = CMAES(problem, options, np.random.default_rng(seed))
    lams = []
    while solver.stop_reason() is None and solver.nfev < budget:
        X = solver.ask()
        lams.append(len(X))
        solver.tell(X, problem.evaluate(X))
    return solver, lams


def test_ipop_restarts_with_growing_populations_and_keeps_the_best():
    """IPOP (Auger & Hansen 2005): each run stagnates on the sphere, the next starts with
    twice the population; after the last restart the solver stops as converged; the best
    over every run is kept (the sphere's minimum, 0 at x = 0.3)."""
    solver, lams = _run(CMAESOptions(restarts=3, tolfun=1e-12), 0)
    assert solver.restart == 3 and solver.stop_reason() == StopReason.CONVERGED
    assert sorted(set(lams)) == [7, 14, 28, 56]  # 4 + 3 ln 3 = 7, doubled per restart
    assert lams == sorted(lams)
    x, ev = solver.best()
    np.testing.assert_allclose(x, 0.3, atol=1e-4)
    assert "3 restart(s)" in solver.notes()[0]


def test_ipop_same_seed_same_result():
    a, _ = _run(CMAESOptions(restarts=2), 5, 3000)
    b, _ = _run(CMAESOptions(restarts=2), 5, 3000)
    c, _ = _run(CMAESOptions(restarts=2), 6, 3000)
    assert np.array_equal(a.best()[0], b.best()[0]) and a.nfev == b.nfev
    assert not np.array_equal(a.best()[0], c.best()[0])


def test_no_restarts_is_the_single_run():
    """restarts = 0 (the default) keeps the one run's stop rule: converged on tolx only."""
    solver, lams = _run(CMAESOptions(generations=60), 1)
    assert set(lams) == {7} and solver.nit == 60 and solver.stop_reason() == StopReason.BUDGET


def test_the_evaluation_budget_spans_the_restarts():
    solver, lams = _run(CMAESOptions(restarts=5, tolfun=1e-6, evaluations=700), 2)
    assert solver.stop_reason() == StopReason.BUDGET and 700 <= solver.nfev < 700 + lams[-1]
    assert solver.restart >= 1
