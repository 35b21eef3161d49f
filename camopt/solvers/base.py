"""The one interface every solver implements: ask/tell over a vectorised Problem."""

from __future__ import annotations

import enum
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from camopt.config.models import SolverOptions
from camopt.core import batch
from camopt.core.capabilities import capability_name
from camopt.core.documents import Row
from camopt.core.problem import Evaluation, Problem, deb_best
from camopt.errors import SolverError
from camopt.mechanics import Bools, Floats

if TYPE_CHECKING:  # annotations only: no config models at import
    from camopt.config.raw import RawDoc


class StopReason(str, enum.Enum):
    """Why a solver stopped."""

    BUDGET = "iteration budget reached"
    CONVERGED = "converged"
    EXHAUSTED = "search space exhausted"
    MAX_EVALUATIONS = "run.max_evaluations reached"
    MAX_SECONDS = "run.max_seconds reached"


@dataclass(frozen=True)
class Budget:
    """The run's limits as the driver hands them to its solver (``run.max_evaluations``,
    and ``run.max_seconds`` as a ``time.perf_counter()`` deadline), for a stage that
    evaluates many times inside one iteration (a polish's scipy solve): between
    iterations the driver checks them itself."""

    max_nfev: int | None = None
    deadline: float | None = None

    def spent(self, nfev: int) -> StopReason | None:
        """Why a stage may not go on to ``nfev`` evaluations in all (the run's count so
        far plus the stage's next batch), or None while both limits hold."""
        if self.max_nfev is not None and nfev > self.max_nfev:
            return StopReason.MAX_EVALUATIONS
        if self.deadline is not None and time.perf_counter() >= self.deadline:
            return StopReason.MAX_SECONDS
        return None


class Solver(ABC):
    """Ask/tell solver (nevergrad style). No I/O, no console; the driver owns the loop.

    Subclasses set ``name``, ``Options`` (a pydantic model with ``name: Literal[...]``)
    and ``requires``: the capability Protocols (:mod:`camopt.core.capabilities`) a case's
    Problem must declare for the solver to run on it.
    """

    name: ClassVar[str]
    Options: ClassVar[type[SolverOptions]]
    requires: ClassVar[tuple[type, ...]] = ()
    summary: ClassVar[str] = ""
    integers: ClassVar[bool] = True  # whether the solver handles integer variables
    test_options: ClassVar[RawDoc] = {}
    """The solver's own small budget: options under which it solves the contract tests'
    4-variable sphere (tests/solvers/test_contract.py) in a few seconds."""
    jobs: int = 1
    """Worker processes the driver lends the solver (``camopt run --jobs``): an execution
    detail only, never a source of different results."""
    budget: Budget = Budget()
    """The run's limits, set by the driver (none by default)."""

    def __init__(self, problem: Problem, options: SolverOptions, rng: np.random.Generator):
        self.check(type(problem), options)
        if not self.integers and problem.integer.any():
            names = [v.name for v in problem.variables if v.integer]
            raise SolverError(f"solver '{self.name}' handles continuous variables only; "
                              f"integer: {', '.join(names)}")
        self.problem, self.options, self.rng = problem, options, rng
        self.nfev = 0
        self.nit = 0

    @classmethod
    def supports(cls, problem_class: type) -> bool:
        """Whether a Problem class declares every capability this solver always needs."""
        return all(issubclass(problem_class, cap) for cap in cls.requires)

    @classmethod
    def needs(cls, options: SolverOptions) -> tuple[type, ...]:
        """The capabilities these options need (``requires`` plus option-dependent ones)."""
        return cls.requires

    @classmethod
    def check(cls, problem_class: type, options: SolverOptions) -> None:
        """Raise SolverError when the case lacks a capability the options need (called when
        a case file is validated, before any work)."""
        missing = [capability_name(cap) for cap in cls.needs(options)
                   if not issubclass(problem_class, cap)]
        if missing:
            raise SolverError(f"solver '{cls.name}' needs a case that offers "
                              f"{', '.join(missing)}; '{problem_class.__name__}' does not")

    @abstractmethod
    def ask(self) -> Floats:
        """Candidates to evaluate next, shape (k, n_var), SI."""

    @abstractmethod
    def tell(self, X: Floats, ev: Evaluation) -> None:
        """Take the evaluation of the candidates from the last ask."""

    @abstractmethod
    def best(self) -> tuple[Floats, Evaluation]:
        """The best design so far and its evaluation (one row)."""

    @abstractmethod
    def stop_reason(self) -> StopReason | None:
        """Why to stop now, or None to go on."""

    def max_iterations(self) -> int | None:
        """The iteration budget, if the solver knows it (for progress bars)."""
        return None

    def table(self) -> list[Row]:
        """Rows of a table the solver produces for the archive (empty for most)."""
        return []

    def notes(self) -> list[str]:
        """Plain-language findings for the run's summary (e.g. non-unique optima)."""
        return []

    def population_objectives(self) -> Floats | None:
        """The current population's objectives, for the archive's mean-objective history
        (None: the last evaluated batch stands in)."""
        return None


def better(f_a: Floats, v_a: Floats, f_b: Floats, v_b: Floats) -> Bools:
    """Deb's feasibility rules: a beats b if less violated, or equally violated and lower f."""
    return (v_a < v_b) | ((v_a == v_b) & (f_a < f_b))


class BestSoFar:
    """The best design a solver has seen by Deb's rules (for solvers whose population
    does not keep it: CMA-ES, NSGA-II)."""

    def __init__(self) -> None:
        self.design: tuple[Floats, Evaluation] | None = None

    def offer(self, X: Floats, ev: Evaluation) -> None:
        """Keep the best row of a told batch if it beats the best so far."""
        i = best_index(ev)
        held = self.design
        if held is None or better(ev.f[i:i + 1], ev.violation[i:i + 1], held[1].f,
                                  held[1].violation)[0]:
            self.design = (X[i].copy(), ev.take(i))

    def get(self) -> tuple[Floats, Evaluation]:
        """A copy of the best design and its evaluation."""
        assert self.design is not None, "nothing told yet"
        return self.design[0].copy(), self.design[1]


def snap(problem: Problem, X: Floats) -> Floats:
    """Clip to bounds and round integer variables."""
    X = np.clip(X, problem.lower, problem.upper)
    mask = problem.integer
    if mask.any():
        X[:, mask] = np.rint(X[:, mask])
    return X


def best_index(ev: Evaluation) -> int:
    """Index of the best candidate of an evaluation by Deb's rules."""
    return deb_best(ev.f, ev.violation)


def design_rows(problem: Problem, X: Floats) -> list[Row]:
    """One table row per candidate: variables in display units, the case's descriptive
    metrics (:meth:`Problem.describe`), objective, feasibility, active and violated
    constraints. Tables are not a hot path."""
    ev = batch.describe(problem, X)
    rows = []
    for i, x in enumerate(X):
        row: Row = dict(problem.to_display(x))
        row.update({k: float(v[i]) for k, v in ev.extras.items() if k not in row})
        row[problem.objective_name] = float(ev.f[i])
        row["feasible"] = bool(ev.feasible[i])
        row["active"] = problem.active(ev.g[i])
        row["violated"] = problem.violated(ev.g[i])
        rows.append(row)
    return rows
