"""The driver: the one loop, the run's own limits, best-of-repeats and reproducibility."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.core.record import Repeat
from camopt.engine.driver import (
    best_repeat,
    converged_iteration,
    execute,
    validate,
)
from camopt.solvers import StopReason
from tests.conftest import CONFIGS
from tests.helpers import load


def _config(**run):
    return validate({"case": {"kind": "sphere"},
                     "solver": {"name": "de_gr", "population": 12, "generations": 40},
                     "run": {"seed": 4, "repeats": 3, **run}}, "sphere.toml")


def _record(index: int, fun: float, violation: float) -> Repeat:
    return Repeat(x=np.zeros(1), fun=fun, success=violation == 0, message="", nfev=0, nit=0,
                  index=index, spawn_key=(index,), seed=0, feasible=violation == 0,
                  violation=violation, converged_nit=0, nfev_to_target=-1, wall_s=0.0)


def test_best_repeat_follows_deb_rules_and_keeps_the_first_of_equals():
    recs = [_record(0, 1.0, 0.5), _record(1, 5.0, 0.0), _record(2, 2.0, 0.0),
            _record(3, 2.0, 0.0)]
    assert best_repeat(recs).index == 2  # feasible beats less objective; ties: first


def test_converged_iteration():
    f = np.array([5.0, 3.0, 1.0, 1.0, 1.0])
    assert converged_iteration(f, np.zeros(5)) == 3
    assert converged_iteration(np.array([]), np.array([])) == 0
    # still violated at first: converged only once the final violation is reached
    assert converged_iteration(np.ones(4), np.array([1.0, 0.0, 0.0, 0.0])) == 2


def test_execute_is_reproducible_and_reports_progress():
    seen = []
    a = execute(_config(), callback=seen.append)
    b = execute(_config())
    assert [r.fun for r in a.repeats] == [r.fun for r in b.repeats]
    assert np.array_equal(a.best.x, b.best.x)
    assert len(seen) == 3 * 40 and seen[-1].repeat == 2 and seen[-1].iteration == 40
    assert a.repeats[1].spawn_key == (1,)
    assert {p.objective_name for p in seen} == {a.problem.objective_name}


def test_a_robust_runs_progress_names_its_yield_margin():
    """The progress a robust run with ``objective = "margin"`` reports is its normalised
    yield margin, named so (the bar shows the name with the value: it is not the case's
    quantity)."""
    seen = []
    execute(load(CONFIGS / "fast_switch_robust.toml", "solver.generations=2",
                 "solver.population=8", "robust.samples=8", "robust.finalists=2",
                 "robust.check_samples=100", "solver.polish.evaluations=10",
                 "robust.objective=margin"),
            callback=seen.append)
    assert seen and {p.objective_name for p in seen} == {"yield_margin"}


def test_max_seconds_stops_every_repeat_between_iterations():
    rec = execute(_config(max_seconds=1e-9))
    for r in rec.repeats:
        assert r.message == StopReason.MAX_SECONDS.value and r.nit == 1


def test_run_limits_are_validated():
    from camopt.errors import ConfigError

    with pytest.raises(ConfigError, match="run.max_evaluations"):
        _config(max_evaluations=0)


def _comparable(record):
    return [(r.x.tolist(), r.fun, r.nfev, r.nit, {k: v.tolist() for k, v in r.history.items()},
             [{k: v for k, v in row.items() if k != "wall_s"} for row in r.table], r.notes)
            for r in record.repeats]


@pytest.mark.parametrize("config, overrides", [
    ("opening_spring_lse6.toml", ["solver.starts=4", "run.repeats=1"]),  # starts in workers
    ("vcb.toml", ["solver.generations=20", "run.repeats=3"]),  # repeats in workers
])
def test_jobs_change_nothing_but_wall_time(config, overrides):
    """Issue #12: `camopt run --jobs 2` runs repeats (or one repeat's starts) in forked
    workers; every record but wall times equals the sequential run's."""
    cfg = load(CONFIGS / config, *overrides)
    one, two = execute(cfg), execute(cfg, jobs=2)
    assert _comparable(one) == _comparable(two)
    assert one.best.fun == two.best.fun


def _first_generation_best(problem, seq: np.random.SeedSequence, n: int) -> np.ndarray:
    """The best of the n designs a generator from ``seq`` samples first (Deb's rules on the
    sphere: its constraint x0 + x1 <= 1.5, then f = sum (x - 0.3)^2), computed here."""
    X = problem.sample(np.random.default_rng(seq), n)
    f = np.where(X[:, 0] + X[:, 1] <= 1.5, np.sum((X - 0.3) ** 2, axis=1), np.inf)
    return X[np.argmin(f)]


def test_repeat_i_draws_from_child_i_of_the_run_seed():
    """Repeat i's generator is child i of SeedSequence(run.seed) (one generation of DE: the
    best of its first sample), so any repeat can be re-run alone from the archive."""
    cfg = validate({"case": {"kind": "sphere"},
                    "solver": {"name": "de_gr", "population": 12, "generations": 1},
                    "run": {"seed": 4, "repeats": 3}}, "sphere.toml")
    rec = execute(cfg)
    children = np.random.SeedSequence(4).spawn(3)
    for i, r in enumerate(rec.repeats):
        np.testing.assert_array_equal(r.x, _first_generation_best(rec.problem, children[i], 12))
    assert len({tuple(r.x) for r in rec.repeats}) == 3


def _first_hit(history: dict) -> int:
    """Evaluations at the first iteration whose best design was feasible."""
    feasible = np.flatnonzero(history["best_violation"] == 0)
    return int(history["nfev"][feasible[0]]) if feasible.size else -1


def _sphere(target: float | None = None, **solver):
    return validate({"case": {"kind": "sphere"},
                     "solver": {"name": "de_gr", "population": 12, "generations": 30,
                                **solver},
                     "run": {"seed": 2, "repeats": 1,
                             **({} if target is None else {"target": target})}},
                    "sphere.toml")


def test_success_is_feasible_at_or_below_the_target_and_false_when_the_solver_fails():
    """The sphere's optimum is 0 (x = 0.3, the constraint inactive): DE reaches below
    0.05 feasibly (success), not below a target of -1 (no success); a simplex run whose
    only start cannot converge in one iteration has no design (objective +inf)."""
    r = execute(_sphere()).repeats[0]
    assert r.feasible and r.fun < 0.05 and r.success
    assert r.nfev_to_target == _first_hit(r.history) > 0
    r = execute(_sphere(target=-1.0)).repeats[0]
    assert r.feasible and not r.success and r.nfev_to_target == -1
    failed = execute(load(CONFIGS / "opening_spring_lse6.toml", "solver.starts=1",
                          "solver.maxiter=1", "run.repeats=1")).repeats[0]
    assert failed.fun == np.inf and not failed.feasible and not failed.success
    assert failed.message == "search space exhausted"
