"""Monotonicity-analysis enumeration: evaluate every member of a case's 1-DOF family.

The case's ``family()`` returns the designs left once monotonicity analysis has fixed
the active constraints (Clauss 1982, Eq 86); this solver evaluates all of them on the
case's full model in one call and tabulates each with its active constraints.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from camopt.config.models import SolverOptions
from camopt.core.capabilities import HasFamily
from camopt.core.documents import Row
from camopt.core.problem import Evaluation, Problem
from camopt.mechanics import Floats
from camopt.solvers.base import Solver, StopReason, best_index, design_rows
from camopt.solvers.registry import register_solver


class EnumerationOptions(SolverOptions):
    """Options of ``enumeration`` (none besides the name)."""

    name: Literal["enumeration"] = "enumeration"


@register_solver
class Enumeration(Solver):
    """Walk the discrete one-degree-of-freedom family a case exposes."""

    name = "enumeration"
    Options = EnumerationOptions
    options: EnumerationOptions
    requires = (HasFamily,)
    summary = "evaluates every member of the case's 1-DOF family (monotonicity analysis)"

    def __init__(self, problem: Problem, options: EnumerationOptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        self.X: Floats | None = None
        self.ev: Evaluation | None = None

    def max_iterations(self) -> int:
        return 1

    def ask(self) -> Floats:
        assert isinstance(self.problem, HasFamily)
        return np.atleast_2d(self.problem.family())

    def tell(self, X: Floats, ev: Evaluation) -> None:
        self.X, self.ev = X, ev
        self.nfev += len(X)
        self.nit += 1

    def best(self) -> tuple[Floats, Evaluation]:
        assert self.X is not None and self.ev is not None
        i = best_index(self.ev)
        return self.X[i].copy(), self.ev.take(i)

    def stop_reason(self) -> StopReason | None:
        return StopReason.EXHAUSTED if self.X is not None else None

    def table(self) -> list[Row]:
        """One row per family member with its active constraints."""
        assert self.X is not None and self.ev is not None
        return design_rows(self.problem, self.X)
