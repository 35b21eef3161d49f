"""``evaluate``: no search, just the designs given in the TOML (e.g. a paper's tables)."""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from camopt.config.models import SolverOptions
from camopt.core.documents import Row
from camopt.core.problem import Evaluation, Problem
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers.base import Solver, StopReason, best_index, design_rows
from camopt.solvers.registry import register_solver


class EvaluateOptions(SolverOptions):
    """Options of ``evaluate``: designs as tables ``{variable_with_unit = value}``."""

    name: Literal["evaluate"] = "evaluate"
    designs: list[dict[str, float]] = Field(
        default_factory=list, description="designs to evaluate, in the variables' display units"
    )
    labels: list[str] = Field(default_factory=list, description="optional label per design")


@register_solver
class Evaluate(Solver):
    """Evaluates given designs once; the best of them is the run's result."""

    name = "evaluate"
    Options = EvaluateOptions
    options: EvaluateOptions
    summary = "evaluates the designs listed in the TOML (reference designs, papers' tables)"

    def __init__(self, problem: Problem, options: EvaluateOptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        if not options.designs:
            raise SolverError("solver.designs: give at least one design to evaluate")
        try:
            self.X = np.array([problem.from_display(d) for d in options.designs])
        except ValueError as exc:
            raise SolverError(f"solver.designs: {exc}") from None
        self.ev: Evaluation | None = None

    def max_iterations(self) -> int:
        return 1

    def ask(self) -> Floats:
        return self.X.copy()

    def tell(self, X: Floats, ev: Evaluation) -> None:
        self.ev = ev
        self.nfev += len(X)
        self.nit += 1

    def best(self) -> tuple[Floats, Evaluation]:
        assert self.ev is not None
        i = best_index(self.ev)
        return self.X[i].copy(), self.ev.take(i)

    def stop_reason(self) -> StopReason | None:
        return StopReason.EXHAUSTED if self.ev is not None else None

    def table(self) -> list[Row]:
        """One row per given design, labelled."""
        assert self.ev is not None
        labels = list(self.options.labels) + [f"design {i}" for i in range(len(self.X))]
        rows = design_rows(self.problem, self.X)
        return [{"label": label, **row} for label, row in zip(labels, rows)]
