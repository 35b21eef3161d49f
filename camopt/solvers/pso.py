"""``pso``: particle swarm optimisation with linearly decreasing inertia (Yan et al. 2023,
Eqs 38-41), personal and global bests, velocity limits and bound handling.

Generic. When the case declares corrections (:class:`~camopt.core.capabilities.Repairable`),
the swarm is corrected after each move with probabilities that change linearly from
the first to the last iteration (the paper's "improved PSO", Sec 3.3.4). ``repair``
unset uses them when the case has them, ``true`` requires them (a case without is bad
input), ``false`` gives plain PSO. Written here because scipy has no PSO.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from camopt.config.models import MAX_ITERATIONS, MAX_POPULATION, AsTuple, SolverOptions
from camopt.core.capabilities import Repairable
from camopt.core.problem import Evaluation, Problem
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers.base import Solver, StopReason, best_index, better, snap
from camopt.solvers.polish import PolishableOptions, Polishing
from camopt.solvers.registry import register_solver


def inertia(iteration: int, iterations: int, w_max: float, w_min: float) -> float:
    """Inertia weight of Eq 40, falling linearly from w_max at iteration 0 to w_min at
    i_max = ``iterations``."""
    return w_max - iteration / iterations * (w_max - w_min)


class PSOOptions(PolishableOptions):
    """Options of ``pso``."""

    name: Literal["pso"] = "pso"
    particles: int = Field(60, ge=2, le=MAX_POPULATION,
                           description=f"swarm size (at most {MAX_POPULATION}: memory)")
    iterations: int = Field(300, ge=1, le=MAX_ITERATIONS, description="iterations (i_max of "
                            f"Eq 40; at most {MAX_ITERATIONS}: time)")
    c1: float = Field(1.5, ge=0, description="cognitive learning factor (Eq 38)")
    c2: float = Field(1.5, ge=0, description="social learning factor (Eq 38)")
    w_max: float = Field(0.9, ge=0, description="initial inertia (Eq 40)")
    w_min: float = Field(0.4, ge=0, description="final inertia (Eq 40)")
    v_max: float = Field(0.2, gt=0, le=1, description="velocity limit, fraction of the range")
    repair: bool | None = Field(
        None, description="the case's corrections (improved PSO): unset uses them when the "
        "case has them, true requires them, false is plain PSO")
    repair_probability: dict[str, Annotated[tuple[float, float], AsTuple]] | None = Field(
        None, description="per correction: trigger probability at the first and last "
        "iteration; corrections not named keep the case's schedule")


@register_solver
class PSO(Polishing, Solver):
    """Particle swarm with optional case repair; ranks particles by Deb's rules."""

    name = "pso"
    Options = PSOOptions
    options: PSOOptions
    summary = "particle swarm, decreasing inertia, optional case corrections (generic)"
    test_options = {"particles": 30, "iterations": 200}

    @classmethod
    def needs(cls, options: SolverOptions) -> tuple[type, ...]:
        assert isinstance(options, PSOOptions)
        asked = options.repair or (options.repair is None and options.repair_probability)
        return (Repairable,) if asked else ()

    def __init__(self, problem: Problem, options: PSOOptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        self.lo, self.hi = problem.lower, problem.upper
        self.vmax = options.v_max * (self.hi - self.lo)
        self.repairer: Repairable | None = (
            problem if options.repair is not False and isinstance(problem, Repairable)
            else None)
        self.schedule: dict[str, tuple[float, float]] = {}
        if self.repairer is not None:
            self.schedule = {k: (a, b) for k, (a, b) in self.repairer.repair_schedule().items()}
            given = options.repair_probability or {}
            unknown = sorted(set(given) - set(self.schedule))
            if unknown:
                raise SolverError(f"repair_probability: unknown correction "
                                  f"{', '.join(map(repr, unknown))}; the case's corrections: "
                                  f"{', '.join(self.schedule)}")
            self.schedule.update({k: (a, b) for k, (a, b) in given.items()})
        self.X: Floats | None = None
        self.V: Floats | None = None
        self.P: Floats | None = None
        self.pev: Evaluation | None = None
        self.cur_f: Floats | None = None

    def max_iterations(self) -> int:
        return self.options.iterations + (self.options.polish is not None)

    def budget_spent(self) -> bool:
        """Whether the swarm has made its iterations."""
        return self.nit >= self.options.iterations

    def probabilities(self) -> dict[str, float]:
        """Correction probabilities at the current iteration (linear decay)."""
        frac = self.nit / max(self.options.iterations - 1, 1)
        return {k: a + (b - a) * frac for k, (a, b) in self.schedule.items()}

    def _repair(self, X: Floats) -> Floats:
        if self.repairer is None:
            return X
        return snap(self.problem, self.repairer.repair(X, self.rng, self.probabilities()))

    def ask(self) -> Floats:
        if self.polish_pending():
            return self.polish_ask()
        o, n, d = self.options, self.options.particles, self.problem.n_var
        if self.X is None:
            X = self.problem.sample(self.rng, n)
            self.V = (self.rng.random((n, d)) * 2 - 1) * self.vmax
            return self._repair(snap(self.problem, X))
        assert self.P is not None and self.V is not None and self.pev is not None
        w = inertia(self.nit, o.iterations, o.w_max, o.w_min)
        g = self.P[best_index(self.pev)]
        r1, r2 = self.rng.random((n, d)), self.rng.random((n, d))
        desired = o.c1 * r1 * (self.P - self.X) + o.c2 * r2 * (g - self.X)  # Eq 38
        V = np.clip(w * self.V + desired, -self.vmax, self.vmax)  # Eq 39, speed limit
        X = self.X + V  # Eq 41
        out = (X < self.lo) | (X > self.hi)
        V[out] = 0.0  # absorbing walls
        self.V = V
        return self._repair(snap(self.problem, X))

    def tell(self, X: Floats, ev: Evaluation) -> None:
        if self.polish_tell(X, ev):
            return
        self.nfev += len(X)
        self.nit += 1
        if self.X is not None and self.V is not None:
            self.V = np.where(np.isfinite(X - self.X), self.V, 0.0)
        self.X, self.cur_f = X.copy(), ev.f
        if self.P is None or self.pev is None:
            self.P, self.pev = X.copy(), ev
            return
        win = better(ev.f, ev.violation, self.pev.f, self.pev.violation)
        self.P = np.where(win[:, None], X, self.P)
        self.pev = ev.where(win, self.pev)

    def population_best(self) -> tuple[Floats, Evaluation]:
        assert self.P is not None and self.pev is not None
        i = best_index(self.pev)
        return self.P[i].copy(), self.pev.take(i)

    def population_objectives(self) -> Floats:
        assert self.cur_f is not None
        return self.cur_f

    def stop_reason(self) -> StopReason | None:
        if not self.budget_spent() or self.polish_pending():
            return None
        return self.polish_stopped or StopReason.BUDGET
