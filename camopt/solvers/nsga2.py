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

With ``cmaes_evaluations`` > 0 a CMA-ES start comes first (the core of
:mod:`camopt.solvers.cmaes`, from the case's design, else the box's centre, ranked by
Deb's rules: violation, then the first objective): a feasible set thin in the variables
(near-equalities such as a travel held within a tolerance, several limits active at once)
is reached by a search that learns its orientation, where NSGA-II's uniform random
population and SBX may never land in it. NSGA-II then starts from ``population`` designs
picked among every design the start evaluated by its own survival (the feasible first,
by rank and crowding; then the least violation), and runs its ``generations``.

pymoo draws from ``algorithm.random_state``; the plugin hands it the repeat's own
generator (after ``setup``, which would otherwise seed a fresh one), so the same seed
gives the same front. The CMA-ES start draws from the same generator.

pymoo is imported where the search runs (it is slow to import; ``camopt solvers`` lists this
one without it).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import Field, model_validator

from camopt.config.models import MAX_ITERATIONS, MAX_POPULATION, SolverOptions
from camopt.core.capabilities import Repairable
from camopt.core.documents import Row
from camopt.core.problem import Evaluation, Problem
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers.base import BestSoFar, Solver, StopReason, design_rows, snap
from camopt.solvers.cmaes import CMACore, deb_order
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
    cmaes_evaluations: int = Field(
        0, ge=0, le=1_000_000, description="evaluations of a CMA-ES start before NSGA-II "
        "(from the case's design, else the box's centre, ranked by violation then the first "
        "objective); NSGA-II starts from the best population of its designs by its own "
        "survival. 0: no start, a uniform random population (pymoo's)")
    cmaes_population: int = Field(32, ge=4, le=MAX_POPULATION,
                                  description="lambda of the CMA-ES start")
    cmaes_sigma: float = Field(0.3, gt=0, le=1, description="initial step of the CMA-ES "
                               "start, fraction of each range")

    @model_validator(mode="after")
    def _maximise_among_objectives(self) -> NSGA2Options:
        stray = [m for m in self.maximise if m not in self.objectives]
        if stray:
            raise ValueError(f"maximise: {', '.join(stray)} not among the objectives")
        if len(set(self.objectives)) != len(self.objectives):
            raise ValueError("objectives: a metric is named twice")
        if 0 < self.cmaes_evaluations < self.population:
            raise ValueError(f"cmaes_evaluations: at least the population "
                             f"({self.population}), or 0 (no CMA-ES start)")
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
        self._pymoo = (PymooNSGA2, NoTermination, SBX, PM)
        # the CMA-ES start: its generations, its core and every design it evaluated
        self.start_generations = -(-options.cmaes_evaluations // options.cmaes_population)
        self.start: CMACore | None = None
        self._pool: list[tuple[Floats, Floats, Floats]] = []
        self.algorithm: Any = None
        if self.start_generations:
            initial = problem.initial_x()
            x0 = ((problem.lower + problem.upper) / 2 if initial is None
                  else np.asarray(initial, dtype=float))
            self.start = CMACore(np.clip(problem.to_unit(x0), 0, 1), options.cmaes_sigma,
                                 rng, options.cmaes_population)
        else:
            self.algorithm = self._nsga2(None)
        self._pending: Any = None
        self._best = BestSoFar()

    def _nsga2(self, sampling: Floats | None) -> Any:
        """pymoo's NSGA-II set up on the problem, drawing from the repeat's generator;
        ``sampling``: its first population (None: pymoo's uniform random one)."""
        nsga2, no_termination, sbx, pm = self._pymoo
        extra = {} if sampling is None else {"sampling": sampling}
        algorithm = nsga2(pop_size=self.options.population,
                          crossover=sbx(eta=self.options.crossover_eta, prob=0.9),
                          mutation=pm(eta=self.options.mutation_eta), **extra)
        algorithm.setup(self.pproblem, termination=no_termination(), verbose=False)
        algorithm.random_state = self.rng  # the repeat's generator, not a fresh one
        return algorithm

    def _check_names(self) -> None:
        """Fail at construction on objective names the case does not report."""
        mid = (self.problem.lower + self.problem.upper) / 2
        known = [self.problem.objective_name, *self.problem.evaluate(mid[None, :]).extras]
        unknown = [o for o in self.objectives if o not in known]
        if unknown:
            raise SolverError(f"objectives: no metric {', '.join(map(repr, unknown))}; the "
                              f"case reports {', '.join(known)}")

    def max_iterations(self) -> int:
        return self.start_generations + self.options.generations

    def objective_matrix(self, ev: Evaluation) -> Floats:
        """The objectives of an evaluation as columns, (n_pop, n_obj), in their own units
        (maximised ones not negated)."""
        cols = [ev.f if o == self.problem.objective_name else ev.extras[o]
                for o in self.objectives]
        return np.column_stack([np.asarray(c, dtype=float) for c in cols])

    def pymoo_fg(self, ev: Evaluation) -> tuple[Floats, Floats]:
        """The objectives in minimisation form and the constraints as pymoo takes them,
        (n_pop, n_obj) and (n_pop, n_constr + 1): non-finite values as :data:`_BAD`, the
        last constraint whether every objective is finite."""
        F = self.objective_matrix(ev) * self.sign
        finite = np.isfinite(F).all(axis=1) & np.isfinite(ev.f)
        G = np.column_stack([ev.g, np.where(finite, -1.0, 1.0)])
        return np.where(np.isfinite(F), F, _BAD), np.where(np.isfinite(G), G, _BAD)

    def ask(self) -> Floats:
        if self.start is not None:
            return snap(self.problem, self.problem.from_unit(self.start.ask()))
        pop = self.algorithm.ask()
        X = snap(self.problem, np.asarray(pop.get("X"), dtype=float))
        if self.repairer and self.schedule:  # Lamarckian: corrected designs replace offspring
            nit = self.nit - self.start_generations
            frac = nit / max(self.options.generations - 1, 1)
            prob = {k: a + (b - a) * frac for k, (a, b) in self.schedule.items()}
            X = snap(self.problem, self.repairer.repair(X, self.rng, prob))
        pop.set("X", X)
        self._pending = pop
        return X.copy()

    def tell(self, X: Floats, ev: Evaluation) -> None:
        from pymoo.core.evaluator import Evaluator
        from pymoo.problems.static import StaticProblem

        F, G = self.pymoo_fg(ev)
        self.nfev += len(X)
        self.nit += 1
        self._best.offer(X, ev)
        if self.start is not None:
            self.start.tell(self.problem.to_unit(X), deb_order(F[:, 0],
                                                               np.maximum(G, 0).sum(axis=1)))
            self._pool.append((X, F, G))
            if self.nit >= self.start_generations:
                self.algorithm = self._nsga2(self._first_population())
                self.start, self._pool = None, []
            return
        pop, self._pending = self._pending, None
        Evaluator().eval(StaticProblem(self.pproblem, F=F, G=G), pop)
        self.algorithm.tell(infills=pop)

    def _first_population(self) -> Floats:
        """NSGA-II's first population: ``population`` of the CMA-ES start's designs, picked
        by NSGA-II's own survival (feasible ones by rank and crowding, then the least
        violation), (population, n_var)."""
        from pymoo.core.evaluator import Evaluator
        from pymoo.core.population import Population
        from pymoo.operators.survival.rank_and_crowding import RankAndCrowding
        from pymoo.problems.static import StaticProblem

        X, F, G = (np.concatenate(part) for part in zip(*self._pool))
        pool = Population.new(X=X)
        Evaluator().eval(StaticProblem(self.pproblem, F=F, G=G), pool)
        kept = RankAndCrowding().do(self.pproblem, pool, n_survive=self.options.population,
                                    random_state=self.rng)
        return np.asarray(kept.get("X"), dtype=float)

    def best(self) -> tuple[Floats, Evaluation]:
        return self._best.get()

    def pareto_set(self) -> Floats:
        """The designs of the final non-dominated set, (n_front, n_var), SI, ordered by the
        first objective (feasible ones only when any is feasible); none before NSGA-II
        has run (within a CMA-ES start)."""
        if self.algorithm is None or self.algorithm.opt is None:
            return np.empty((0, self.problem.n_var))
        opt = self.algorithm.opt
        X = np.asarray(opt.get("X"), dtype=float)
        F = np.asarray(opt.get("F"), dtype=float) * self.sign
        return X[np.lexsort(F.T[::-1])]

    def table(self) -> list[Row]:
        """One row per Pareto design: variables, metrics, objective, feasibility."""
        if self.algorithm is None or self.algorithm.opt is None:
            return []
        return design_rows(self.problem, self.pareto_set())

    def stop_reason(self) -> StopReason | None:
        return StopReason.BUDGET if self.nit >= self.max_iterations() else None
