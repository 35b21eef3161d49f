"""Contract tests over every registered generic solver (Optuna/pymoo style)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.engine.driver import build_solver, prepare, run_repeat, validate
from camopt.errors import ConfigError, SolverError
from camopt.solvers import StopReason, get_solver, solvers
from camopt.solvers.registry import register_solver
from tests.conftest import SphereConfig, SphereProblem

# every registered solver that needs no capability runs on the sphere case
GENERIC = [name for name, cls in solvers().items() if not cls.requires and name != "evaluate"]


def _config(name: str, run: dict | None = None, **case):
    data = {"case": {"kind": "sphere", **case},
            "solver": {"name": name, **get_solver(name).test_options}, "run": run or {}}
    return validate(data, "sphere.toml")


def _run(name: str, seed: int = 0, run: dict | None = None, **case):
    cfg = _config(name, run, **case)
    problem, cls = prepare(cfg)
    rec = run_repeat(problem, cls, cfg, np.random.SeedSequence(seed), 0, 1)
    return problem, rec


def test_generic_solvers_exist():
    assert "de_gr" in GENERIC


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", GENERIC)
def test_finds_sphere_optimum(name, seed):
    """Under its own budget (``test_options``) every solver ends within 2e-3 of the
    sphere's optimum x = 0.3 (the constraint inactive there), whatever the seed."""
    _, rec = _run(name, seed)
    assert rec.feasible
    np.testing.assert_allclose(rec.x, 0.3, atol=2e-3)


@pytest.mark.parametrize("name", GENERIC)
def test_respects_bounds_and_integers(name):
    if not get_solver(name).integers:
        with pytest.raises(ConfigError, match="continuous variables only"):
            _run(name, integer_first=True)
        problem, rec = _run(name)
        assert np.all(rec.x >= problem.lower) and np.all(rec.x <= problem.upper)
        return
    problem, rec = _run(name, integer_first=True)
    assert np.all(rec.x >= problem.lower) and np.all(rec.x <= problem.upper)
    assert rec.x[0] == np.rint(rec.x[0]) and rec.x[0] == 0.0


@pytest.mark.parametrize("name", GENERIC)
def test_same_seed_same_result_other_seed_other_path(name):
    _, a = _run(name, seed=5)
    _, b = _run(name, seed=5)
    _, c = _run(name, seed=6)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun
    assert np.array_equal(a.history["best_objective"], b.history["best_objective"])
    assert not np.array_equal(a.history["best_objective"], c.history["best_objective"])


@pytest.mark.parametrize("name", GENERIC)
def test_stays_in_budget(name):
    """Every solver stops at the iteration budget it announces (``max_iterations``), with
    one history entry per iteration, and the best objective never worsens."""
    cfg = _config(name)
    problem, cls = prepare(cfg)
    announced = build_solver(problem, cls, cfg, np.random.default_rng(0)).max_iterations()
    _, rec = _run(name)
    assert announced is not None
    assert rec.nit == announced == len(rec.history["best_objective"])
    assert rec.history["nfev"][-1] == rec.nfev
    assert np.all(np.diff(rec.history["best_objective"]) <= 0)


@pytest.mark.parametrize("name", GENERIC)
def test_driver_limits_evaluations(name):
    """``run.max_evaluations`` stops any solver between iterations, once it is reached."""
    _, full = _run(name)
    limit = int(full.history["nfev"][1])  # reached after the second iteration
    _, rec = _run(name, run={"max_evaluations": limit})
    assert rec.message == StopReason.MAX_EVALUATIONS.value
    assert rec.nit == 2 and rec.nfev == limit


def test_enumeration_refuses_case_without_family():
    cls = get_solver("enumeration")
    with pytest.raises(SolverError, match="family"):
        cls(SphereProblem(SphereConfig()), cls.Options(), np.random.default_rng(0))


def test_duplicate_registration_raises():
    class Impostor(get_solver("de_gr")):  # type: ignore[misc, valid-type]
        pass

    with pytest.raises(SolverError, match="registered twice"):
        register_solver(Impostor)


def test_unknown_solver_lists_known():
    with pytest.raises(SolverError, match="known: cmaes, de_gr"):
        get_solver("nelder")
