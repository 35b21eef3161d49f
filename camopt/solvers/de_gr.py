"""DE-gr: differential evolution DE/best/1/bin with golden-ratio settings.

Kang, Huang, Yang (2023), Table 5: F = 0.382, CR = 0.618. Written here rather than
wrapping ``scipy.optimize.differential_evolution`` because the driver needs the
ask/tell form (per-generation records, progress, one vectorised call per
generation) and Deb's feasibility rules for constraints returned separately from
the objective; scipy offers neither through its public interface.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from camopt.config.models import MAX_ITERATIONS, MAX_POPULATION
from camopt.core.capabilities import Stochastic
from camopt.core.problem import Evaluation, Problem
from camopt.mechanics import Floats
from camopt.solvers.base import Solver, StopReason, best_index, better, snap
from camopt.solvers.polish import PolishableOptions, Polishing
from camopt.solvers.registry import register_solver


def best1(pop: Floats, best: Floats, factor: float, rng: np.random.Generator) -> Floats:
    """DE/best/1 mutants (n, d): best + F (x_r1 - x_r2) with r1 != r2, both != i, drawn
    per row from the population ``pop`` (n, d)."""
    n = len(pop)
    idx = np.argsort(rng.random((n, n)), axis=1)
    # the row's own index is swapped for the last of its permutation: r1, r2 != i
    idx = np.where(idx == np.arange(n)[:, None], idx[:, -1:], idx)[:, :2]
    return best + factor * (pop[idx[:, 0]] - pop[idx[:, 1]])


def binomial_crossover(pop: Floats, mutant: Floats, rate: float, rng: np.random.Generator
                       ) -> Floats:
    """Trials (n, d): each gene from the mutant with probability ``rate`` (CR), else from
    the parent, and one random gene per row from the mutant whatever CR is."""
    n, d = pop.shape
    cross = rng.random((n, d)) < rate
    cross[np.arange(n), rng.integers(0, d, n)] = True
    return np.where(cross, mutant, pop)


class DEGROptions(PolishableOptions):
    """Options of ``de_gr``."""

    name: Literal["de_gr"] = "de_gr"
    population: int = Field(100, ge=4, le=MAX_POPULATION, description="individuals per "
                            f"generation (Table 5: 100; at most {MAX_POPULATION}: memory)")
    generations: int = Field(300, ge=1, le=MAX_ITERATIONS, description="generations "
                             f"(Table 5: 300; at most {MAX_ITERATIONS}: time)")
    mutation_factor: float = Field(0.382, gt=0, le=2, description="F (Table 5: 0.382)")
    crossover_rate: float = Field(0.618, ge=0, le=1, description="CR (Table 5: 0.618)")
    tolerance: float = Field(
        0.0, ge=0, description="stop early when the population's objective spread is below this"
    )


@register_solver
class DEGR(Polishing, Solver):
    """Differential evolution DE/best/1 with binomial crossover and bound reflection."""

    name = "de_gr"
    Options = DEGROptions
    options: DEGROptions
    summary = "differential evolution DE/best/1/bin, F=0.382, CR=0.618 (generic)"
    test_options = {"population": 30, "generations": 150}

    def __init__(self, problem: Problem, options: DEGROptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        self.lo, self.hi = problem.lower, problem.upper
        self.pop: Floats | None = None
        self.ev: Evaluation | None = None
        self._trial = False
        # parents are evaluated again on each generation's draws (Stochastic's docstring)
        self.redraws = isinstance(problem, Stochastic)
        self._again = np.arange(0)  # the parents evaluated again with the trials

    def max_iterations(self) -> int:
        return self.options.generations + (self.options.polish is not None)

    def ask(self) -> Floats:
        if self.polish_pending():
            return self.polish_ask()
        n = self.options.population
        if self.pop is None:
            return snap(self.problem, self.problem.sample(self.rng, n))
        best = self.pop[self._best_index()]
        mutant = best1(self.pop, best, self.options.mutation_factor, self.rng)
        trial = binomial_crossover(self.pop, mutant, self.options.crossover_rate, self.rng)
        # reflect into bounds, midway between the parent and the violated bound
        trial = np.where(trial < self.lo, (self.lo + self.pop) / 2, trial)
        trial = np.where(trial > self.hi, (self.hi + self.pop) / 2, trial)
        if self.redraws:
            # the parents again, on this generation's draws: a parent kept for passing an
            # earlier generation's draws by luck would otherwise lead best/1 (and every
            # comparison) with an evaluation no trial is measured against. Only the parents
            # whose evaluation depends on the draws: a screened one's is its nominal's
            assert self.ev is not None and isinstance(self.problem, Stochastic)
            self._again = np.flatnonzero(self.problem.draw_dependent(self.ev))
            return np.vstack([snap(self.problem, trial), self.pop[self._again]])
        return snap(self.problem, trial)

    def tell(self, X: Floats, ev: Evaluation) -> None:
        if self.polish_tell(X, ev):
            return
        self.nfev += len(X)
        self.nit += 1
        if self.pop is None:
            self.pop, self.ev = X.copy(), ev
            return
        assert self.ev is not None
        n = len(self.pop)
        if self.redraws and len(X) == n + len(self._again):
            # the parents evaluated again replace their old rows; the others keep theirs
            index = np.arange(n)
            index[self._again] = n + np.arange(len(self._again))
            self.ev = Evaluation.concat([self.ev, ev.take(slice(n, None))]).take(index)
            X, ev = X[:n], ev.take(slice(0, n))
        win = ~better(self.ev.f, self.ev.violation, ev.f, ev.violation)  # trial ties win
        self.pop = np.where(win[:, None], X, self.pop)
        self.ev = ev.where(win, self.ev)

    def _best_index(self) -> int:
        assert self.ev is not None
        return best_index(self.ev)

    def population_best(self) -> tuple[Floats, Evaluation]:
        """The population's best design by Deb's rules and its evaluation (one row)."""
        i = self._best_index()
        assert self.pop is not None and self.ev is not None
        return self.pop[i].copy(), self.ev.take(i)

    def population_objectives(self) -> Floats:
        assert self.ev is not None
        return self.ev.f

    def budget_spent(self) -> bool:
        """Whether the generations are spent (or the population has converged)."""
        if self.nit >= self.options.generations:
            return True
        return bool(self.options.tolerance > 0 and self.ev is not None
                    and self.ev.feasible.all() and np.ptp(self.ev.f) <= self.options.tolerance)

    def stop_reason(self) -> StopReason | None:
        if not self.budget_spent() or self.polish_pending():
            return None
        if self.polish_stopped is not None:
            return self.polish_stopped
        if self.nit >= self.options.generations + (self._polished is not None):
            return StopReason.BUDGET
        return StopReason.CONVERGED
