"""The one interface every solver implements: ask/tell over a vectorised Problem."""

from __future__ import annotations

import enum
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from camopt.config.models import SolverOptions
from camopt.errors import SolverError
from camopt.problem import FEASIBILITY_TOL, Evaluation, Problem


class StopReason(str, enum.Enum):
    """Why a solver stopped."""

    BUDGET = "iteration budget reached"
    CONVERGED = "converged"
    EXHAUSTED = "search space exhausted"


class Solver(ABC):
    """Ask/tell solver (nevergrad style). No I/O, no console; the driver owns the loop.

    Subclasses set ``name``, ``Options`` (a pydantic model with ``name: Literal[...]``)
    and ``requires`` (names of Problem capabilities they need, e.g. ``"family"``).
    """

    name: ClassVar[str]
    Options: ClassVar[type[SolverOptions]]
    requires: ClassVar[tuple[str, ...]] = ()
    summary: ClassVar[str] = ""
    integers: ClassVar[bool] = True  # whether the solver handles integer variables

    def __init__(self, problem: Problem, options: SolverOptions, rng: np.random.Generator):
        missing = [cap for cap in self.requires if not callable(getattr(problem, cap, None))]
        if missing:
            raise SolverError(
                f"solver '{self.name}' needs a case that offers {', '.join(missing)}; "
                f"'{type(problem).__name__}' does not"
            )
        if not self.integers and problem.integer.any():
            names = [v.name for v in problem.variables if v.integer]
            raise SolverError(f"solver '{self.name}' handles continuous variables only; "
                              f"integer: {', '.join(names)}")
        self.problem, self.options, self.rng = problem, options, rng
        self.nfev = 0
        self.nit = 0

    @classmethod
    def supports(cls, problem_class: type) -> bool:
        """Whether a Problem class offers every capability this solver needs."""
        return all(callable(getattr(problem_class, cap, None)) for cap in cls.requires)

    @abstractmethod
    def ask(self) -> NDArray:
        """Candidates to evaluate next, shape (k, n_var), SI."""

    @abstractmethod
    def tell(self, X: NDArray, ev: Evaluation) -> None:
        """Take the evaluation of the candidates from the last ask."""

    @abstractmethod
    def best(self) -> tuple[NDArray, Evaluation]:
        """The best design so far and its evaluation (one row)."""

    @abstractmethod
    def stop_reason(self) -> StopReason | None:
        """Why to stop now, or None to go on."""

    def max_iterations(self) -> int | None:
        """The iteration budget, if the solver knows it (for progress bars)."""
        return None

    def table(self) -> list[dict[str, Any]]:
        """Rows of a table the solver produces for the archive (empty for most)."""
        return []

    def notes(self) -> list[str]:
        """Plain-language findings for the run's summary (e.g. non-unique optima)."""
        return []


def better(f_a: NDArray, v_a: NDArray, f_b: NDArray, v_b: NDArray) -> NDArray:
    """Deb's feasibility rules: a beats b if less violated, or equally violated and lower f."""
    return (v_a < v_b) | ((v_a == v_b) & (f_a < f_b))


def snap(problem: Problem, X: NDArray) -> NDArray:
    """Clip to bounds and round integer variables."""
    X = np.clip(X, problem.lower, problem.upper)
    mask = problem.integer
    if mask.any():
        X[:, mask] = np.rint(X[:, mask])
    return X


def best_index(ev: Evaluation) -> int:
    """Index of the best candidate by Deb's rules (least violation, then lowest f)."""
    return int(np.lexsort((ev.f, ev.violation))[0])


def design_rows(problem: Problem, X: NDArray, ev: Evaluation) -> list[dict[str, Any]]:
    """One table row per candidate: variables in display units, extras, objective,
    feasibility, active and violated constraints."""
    describe = getattr(problem, "describe", None)
    if callable(describe):  # tables are not a hot path: take the descriptive metrics too
        ev = describe(X)
    rows = []
    for i, x in enumerate(X):
        row: dict[str, Any] = dict(problem.to_display(x))
        row.update({k: float(v[i]) for k, v in ev.extras.items() if k not in row})
        row[problem.objective_name] = float(ev.f[i])
        row["feasible"] = bool(ev.feasible[i])
        row["active"] = problem.active(ev.g[i])
        row["violated"] = [n for n, gi in zip(problem.constraint_names, ev.g[i])
                           if not gi <= FEASIBILITY_TOL]
        rows.append(row)
    return rows
