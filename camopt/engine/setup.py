"""What a run needs before its loop: the case file loaded and validated against the
registries, the case's problem built and checked with the solver (:mod:`camopt.engine.driver`
re-exports it). A module apart from the driver, so ``camopt validate`` checks a case file
without importing the loop's process pools, records, statistics and robust evaluation
(start-up time); ``[robust]`` imports :mod:`camopt.engine.robust` when a case file has one."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from camopt.cases import build_problem, case_configs, get_case
from camopt.config import LoadedConfig, load_config, validate_data
from camopt.config.raw import RawDoc
from camopt.core.perf import pin_blas_threads
from camopt.core.problem import Problem
from camopt.errors import ConfigError, SolverError
from camopt.solvers import Solver, get_solver, registry


def solver_options() -> Mapping[str, Any]:
    """Solver names to their Options models (what the loader validates ``[solver]`` with;
    a name looked up imports that solver only: :func:`camopt.solvers.registry.solver_options`)."""
    return registry.solver_options()


def load(path: str | Path, overrides: Sequence[str] = ()) -> LoadedConfig:
    """Load and validate a case file against the registered cases and solvers."""
    return load_config(path, solver_options(), case_configs(), overrides)


def validate(data: RawDoc, source: str = "<data>", grid: Sequence[str] = ()
             ) -> LoadedConfig:
    """Validate parsed case-file data (a sweep cell's) against the registries; an error in
    one of the ``grid``'s keys is blamed on ``--grid``."""
    return validate_data(data, solver_options(), case_configs(), source,
                         overridden=set(grid), origin="--grid")


def prepare(config: LoadedConfig) -> tuple[Problem, type[Solver]]:
    """Build the case's problem and check the solver can run on it with these options
    (a capability the case lacks is bad input against ``solver``). With ``[robust]`` the
    problem is the case's wrapped for yield (:mod:`camopt.engine.robust`). BLAS runs on one
    thread from here on (``perf.pin_blas_threads``), so results do not depend on the
    thread count of the process or machine that evaluates them."""
    pin_blas_threads()
    with np.errstate(all="ignore"):  # a non-assembling mechanism is reported below
        problem = build_problem(config.case)
    _check_bounds(problem, config)
    tolerances = get_case(config.case.kind).tolerances_of(config.case.tolerance_class,
                                                          config.path)
    if config.robust is not None:
        from camopt.engine import robust

        problem = robust.wrap(problem, robust.plan(
            problem, config.case, config.robust, dict(tolerances), config.path),
            config.path)
    solver_cls = get_solver(config.solver.name)
    try:
        solver_cls.check(type(problem), config.solver)
    except SolverError as exc:
        # a capability every run of the solver needs is the solver's name's fault; one
        # that only some options need is the options' fault
        key = "solver.name" if not solver_cls.supports(type(problem)) else "solver"
        raise ConfigError(config.path, key, f"cannot run case '{config.case.kind}': "
                          f"{exc}") from None
    return problem, solver_cls


def _check_bounds(problem: Problem, config: LoadedConfig) -> None:
    """Every design variable has finite bounds, lower below upper: bounds a case derives
    from its parameters (an angle from an arccos, a radius range from two radii) say
    whether the mechanism can be assembled at all."""
    for v in problem.variables:
        if not (np.isfinite(v.lower) and np.isfinite(v.upper) and v.lower < v.upper):
            raise ConfigError(config.path, "case", f"the mechanism cannot be assembled with "
                              f"these values: variable {v.name} gets bounds "
                              f"[{v.lower * v.scale:g}, {v.upper * v.scale:g}]")


class FirstUseRng:
    """Stands for ``numpy.random.default_rng(seed)``, made on its first use: ``camopt
    validate`` builds the solver for the checks its constructor makes, which most solvers
    make without drawing, so the command need not import numpy.random (~0.005 s of its
    start-up); a solver that draws gets that very generator."""

    def __init__(self, seed: int) -> None:
        self._seed = seed
        self._rng: np.random.Generator | None = None

    def __getattr__(self, name: str) -> Any:
        if self._rng is None:
            self._rng = np.random.default_rng(self._seed)
        return getattr(self._rng, name)


def build_solver(problem: Problem, solver_cls: type[Solver], config: LoadedConfig,
                 rng: np.random.Generator) -> Solver:
    """The solver for one repeat; what it refuses (options the case cannot meet) is
    reported as bad input against the case file."""
    try:
        return solver_cls(problem, config.solver, rng)
    except SolverError as exc:
        raise ConfigError(config.path, "solver", str(exc)) from None
