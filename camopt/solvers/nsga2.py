"""``nsga2``: multi-objective search by pymoo's NSGA-II through its ask/tell interface.

The objectives are metrics the case reports (``Evaluation.extras``) or the case's own
objective, named in ``[solver] objectives``; ``maximise`` lists those to maximise. The
case's constraints are kept exactly as every solver keeps them: pymoo ranks by the sum of
their excesses first (Deb's rules inside non-dominated sorting), so no penalty is tuned.

The Pareto set is the non-dominated set of the final population as pymoo reports it
(``algorithm.opt``, spread by crowding distance, at most ``population`` designs); it is
the solver's ``table`` and thereby the archive's ``/table``. ``best`` is the best design
by the case's own objective seen so far (Deb's rules), so runs, ``show`` and ``compare``
keep one headline design and the convergence history stays monotone.

pymoo draws from ``algorithm.random_state``; the plugin hands it the repeat's own
generator (after ``setup``, which would otherwise seed a fresh one), so the same seed
gives the same front.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from camopt.config.models import MAX_ITERATIONS, MAX_POPULATION, SolverOptions
from camopt.core.capabilities import Repairable
from camopt.core.problem import Evaluation, Problem
from camopt.errors import SolverError
from camopt.solvers.base import BestSoFar, Solver, StopReason, design_rows, snap
from camopt.solvers.registry import register_solver

_BAD = 1e12
"""Stands for a non-finite objective or constraint inside pymoo (whose crowding distance
would turn inf - inf into NaN); such a design is also marked infeasible."""


class NSGA2Options(SolverOptions):
    """Options of ``nsga2``."""

    name: Literal["nsga2"] = "nsga2"
    objectives: list[str] = Field(
        default_factory=list, description="metrics to optimise (names the case reports, or "
        "its objective's); empty: the case's objective alone")
    maximise: list[str] = Field(
        default_factory=list, description="those of the objectives to maximise (the rest "
        "are minimised)")
    population: int = Field(100, ge=4, le=MAX_POPULATION, description="population size "
                            f"(pymoo's pop_size; at most {MAX_POPULATION}: memory)")
    generations: int = Field(250, ge=1, le=MAX_ITERATIONS,
                             description=f"generations (at most {MAX_ITERATIONS}: time)")
    crossover_eta: float = Field(15.0, gt=0, description="SBX distribution index (pymoo's)")
    mutation_eta: float = Field(20.0, gt=0, description="polynomial mutation index (pymoo's)")
    repair: bool = Field(
        False, description="apply the case's corrections (capability 'repair') to every "
        "offspring before it is evaluated, on the case's schedule from the first to the "
        "last generation (as pso's)")

    @model_validator(mode="after")
    def _maximise_among_objectives(self) -> NSGA2Options:
        stray = [m for m in self.maximise if m not in self.objectives]
        if stray:
            raise ValueError(f"maximise: {', '.join(stray)} not among the objectives")
        if len(set(self.objectives)) != len(self.objectives):
            raise ValueError("objectives: a metric is named twice")
        return self


@register_solver
class NSGA2(Solver):
    """pymoo's NSGA-II (SBX crossover, polynomial mutation, rank and crowding survival)."""

    name = "nsga2"
    Options = NSGA2Options
    options: NSGA2Options
    summary = "multi-objective NSGA-II (pymoo, ask/tell); Pareto set in the archive's table"
    test_options = {"population": 40, "generations": 150}

    @classmethod
    def needs(cls, options: SolverOptions) -> tuple[type, ...]:
        assert isinstance(options, NSGA2Options)
        return (Repairable,) if options.repair else ()

    def __init__(self, problem: Problem, options: NSGA2Options, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        # options.repair on a case without corrections was refused by check() (needs)
        self.repairer = problem if isinstance(problem, Repairable) and options.repair else None
        self.schedule = dict(self.repairer.repair_schedule()) if self.repairer else {}
        self.objectives = tuple(options.objectives) or (problem.objective_name,)
        self.sign = np.array([-1.0 if o in options.maximise else 1.0 for o in self.objectives])
        self._check_names()
        # pymoo costs ~0.6 s to import: only a run that builds this solver pays it
        from pymoo.algorithms.moo.nsga2 import NSGA2 as PymooNSGA2
        from pymoo.core.problem import Problem as PymooProblem
        from pymoo.core.termination import NoTermination
        from pymoo.operators.crossover.sbx import SBX
        from pymoo.operators.mutation.pm import PM

        n_constr = problem.n_constr + 1  # + one: every objective finite
        self.pproblem = PymooProblem(n_var=problem.n_var, n_obj=len(self.objectives),
                                     n_ieq_constr=n_constr, xl=problem.lower,
                                     xu=problem.upper)
        self.algorithm = PymooNSGA2(pop_size=options.population,
                                    crossover=SBX(eta=options.crossover_eta, prob=0.9),
                                    mutation=PM(eta=options.mutation_eta))
        self.algorithm.setup(self.pproblem, termination=NoTermination(), verbose=False)
        self.algorithm.random_state = rng  # the repeat's generator, not a fresh one
        self._pending: Any = None
        self._best = BestSoFar()

    def _check_names(self) -> None:
        """Fail at construction on objective names the case does not report."""
        mid = (self.problem.lower + self.problem.upper) / 2
        known = [self.problem.objective_name, *self.problem.evaluate(mid[None, :]).extras]
        unknown = [o for o in self.objectives if o not in known]
        if unknown:
            raise SolverError(f"objectives: no metric {', '.join(map(repr, unknown))}; the "
                              f"case reports {', '.join(known)}")

    def max_iterations(self) -> int:
        return self.options.generations

    def objective_matrix(self, ev: Evaluation) -> NDArray:
        """The objectives of an evaluation as columns, (n_pop, n_obj), in their own units
        (maximised ones not negated)."""
        cols = [ev.f if o == self.problem.objective_name else ev.extras[o]
                for o in self.objectives]
        return np.column_stack([np.asarray(c, dtype=float) for c in cols])

    def ask(self) -> NDArray:
        pop = self.algorithm.ask()
        X = snap(self.problem, np.asarray(pop.get("X"), dtype=float))
        if self.repairer and self.schedule:  # Lamarckian: corrected designs replace offspring
            frac = self.nit / max(self.options.generations - 1, 1)
            prob = {k: a + (b - a) * frac for k, (a, b) in self.schedule.items()}
            X = snap(self.problem, self.repairer.repair(X, self.rng, prob))
        pop.set("X", X)
        self._pending = pop
        return X.copy()

    def tell(self, X: NDArray, ev: Evaluation) -> None:
        from pymoo.core.evaluator import Evaluator
        from pymoo.problems.static import StaticProblem

        pop, self._pending = self._pending, None
        F = self.objective_matrix(ev) * self.sign
        finite = np.isfinite(F).all(axis=1) & np.isfinite(ev.f)
        G = np.column_stack([ev.g, np.where(finite, -1.0, 1.0)])
        F = np.where(np.isfinite(F), F, _BAD)
        G = np.where(np.isfinite(G), G, _BAD)
        Evaluator().eval(StaticProblem(self.pproblem, F=F, G=G), pop)
        self.algorithm.tell(infills=pop)
        self.nfev += len(X)
        self.nit += 1
        self._best.offer(X, ev)

    def best(self) -> tuple[NDArray, Evaluation]:
        return self._best.get()

    def pareto_set(self) -> NDArray:
        """The designs of the final non-dominated set, (n_front, n_var), SI, ordered by the
        first objective (feasible ones only when any is feasible)."""
        opt = self.algorithm.opt
        X = np.asarray(opt.get("X"), dtype=float)
        F = np.asarray(opt.get("F"), dtype=float) * self.sign
        return X[np.lexsort(F.T[::-1])]

    def table(self) -> list[dict[str, Any]]:
        """One row per Pareto design: variables, metrics, objective, feasibility."""
        if self.algorithm.opt is None:
            return []
        return design_rows(self.problem, self.pareto_set())

    def stop_reason(self) -> StopReason | None:
        return StopReason.BUDGET if self.nit >= self.options.generations else None
