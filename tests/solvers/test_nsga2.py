"""``nsga2``: pymoo's NSGA-II as an ask/tell plugin (the contract tests run it too)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.engine.driver import build_solver, prepare, run_repeat, validate
from camopt.errors import ConfigError
from camopt.solvers import get_solver


def _config(run: dict | None = None, **solver):
    data = {"case": {"kind": "sphere", "n_var": 2},
            "solver": {"name": "nsga2", "objectives": ["f", "norm"], "population": 40,
                       "generations": 150, **solver}, "run": run or {}}
    return validate(data, "sphere.toml")


def _run(seed: int = 0, **solver):
    cfg = _config(**solver)
    problem, cls = prepare(cfg)
    return problem, run_repeat(problem, cls, cfg, np.random.SeedSequence(seed), 0, 1)


def _dominated(F: np.ndarray) -> np.ndarray:
    """(n,) whether each row is dominated by another (all <=, one <)."""
    le = (F[None, :, :] <= F[:, None, :]).all(axis=2)
    lt = (F[None, :, :] < F[:, None, :]).any(axis=2)
    return (le & lt).any(axis=1)


def test_front_of_two_competing_objectives_is_the_segment_between_their_optima():
    """f = |x - 0.3|^2 against |x|: the exact front is f = (0.3 sqrt 2 - |x|)^2 for
    |x| <= 0.3 sqrt 2 (the segment from 0 to (0.3, 0.3)); every member lies within 1e-2
    of it in f (6 % of f's range, 0.18) and the set reaches within 5 % of both ends."""
    _, rec = _run()
    F = np.array([[r["f"], r["norm"]] for r in rec.table])
    assert len(rec.table) == 40 and all(r["feasible"] for r in rec.table)
    assert not _dominated(F).any()
    exact = (0.3 * np.sqrt(2) - F[:, 1]) ** 2
    assert np.all(F[:, 0] - exact >= -1e-12) and np.max(F[:, 0] - exact) < 1e-2
    assert F[:, 1].min() < 0.05 * 0.3 * np.sqrt(2) and F[:, 0].min() < 0.05 * 0.18
    assert np.all(np.diff(F[:, 0]) >= 0)  # ordered by the first objective


def test_maximise_flips_the_sense():
    """Maximising |x| while minimising f: the set runs from f's optimum (|x| = 0.42) out to
    a far corner (|x| -> sqrt 2 at (-1, -1)); as minimisation it would stop at |x| = 0.42."""
    _, rec = _run(maximise=["norm"])
    F = np.array([[r["f"], r["norm"]] for r in rec.table])
    assert F[:, 0].min() < 1e-3 and F[:, 1].max() > 1.35
    assert not _dominated(F * [1, -1]).any()


def test_same_seed_same_front():
    _, a = _run(seed=3)
    _, b = _run(seed=3)
    _, c = _run(seed=4)
    assert a.table == b.table and a.table != c.table


def test_unknown_objective_and_bad_maximise_are_bad_input():
    cfg = _config(objectives=["f", "speed"])
    problem, cls = prepare(cfg)
    with pytest.raises(ConfigError, match="objectives: no metric 'speed'; the case reports f"):
        build_solver(problem, cls, cfg, np.random.default_rng(0))
    with pytest.raises(ValueError, match="maximise: g not among the objectives"):
        _config(maximise=["g"])


def test_repair_needs_the_capability():
    cfg = _config(repair=True)
    with pytest.raises(ConfigError, match="needs a case that offers repair"):
        prepare(cfg)


def test_non_finite_objective_is_infeasible_for_pymoo():
    """A design whose objective metric is not finite ranks behind every finite one."""
    cfg = _config()
    problem, cls = prepare(cfg)
    solver = build_solver(problem, cls, cfg, np.random.default_rng(0))
    X = solver.ask()
    ev = problem.evaluate(X)
    ev.extras["norm"][0] = np.nan
    solver.tell(X, ev)
    G = solver.algorithm.pop.get("G")
    x0 = X[0]
    row = np.flatnonzero((solver.algorithm.pop.get("X") == x0).all(axis=1))
    assert row.size == 0 or G[row[0], -1] > 0
    assert get_solver("nsga2").Options().objectives == []


def _loop(solver, problem):
    """Run a built solver to its stop; the designs of every ask, in order."""
    asked = []
    while solver.stop_reason() is None:
        X = solver.ask()
        asked.append(X)
        solver.tell(X, problem.evaluate(X))
    return asked


def test_cmaes_start_comes_first_and_seeds_the_first_population():
    """10 CMA-ES generations of 20, then NSGA-II's 30 of 40: the first NSGA-II population
    is 40 of the start's 200 designs (picked by NSGA-II's survival), the budget adds up and
    the iterations announced are both stages'."""
    cfg = _config(generations=30, cmaes_evaluations=200, cmaes_population=20)
    problem, cls = prepare(cfg)
    solver = build_solver(problem, cls, cfg, np.random.default_rng(0))
    assert solver.max_iterations() == 40 and solver.algorithm is None
    asked = _loop(solver, problem)
    assert [len(X) for X in asked[:10]] == [20] * 10 and len(asked[10]) == 40
    start = np.concatenate(asked[:10])
    assert all((start == x).all(axis=1).any() for x in asked[10])
    assert solver.nfev == 200 + 40 * 30 and solver.nit == 40
    F = np.array([[r["f"], r["norm"]] for r in solver.table()])
    assert len(F) and not _dominated(F).any()


def test_cmaes_start_same_seed_same_front():
    _, a = _run(seed=3, cmaes_evaluations=200)
    _, b = _run(seed=3, cmaes_evaluations=200)
    _, c = _run(seed=3)
    assert a.table == b.table and a.table != c.table


def test_cmaes_start_shorter_than_a_population_is_refused():
    with pytest.raises(ValueError, match="cmaes_evaluations: at least the population"):
        _config(cmaes_evaluations=10)
