"""``cmaes``: CMA-ES ranked by Deb's rules, in bounds-normalised coordinates.

The (mu/mu_w, lambda)-CMA-ES with rank-one and rank-mu covariance updates and
cumulative step-size adaptation, as in Hansen's tutorial (arXiv:1604.00772, Table 1
and Fig 6 / ``purecma``); with ``active`` the rank-mu update takes the worst
lambda - mu with negative weights too (the tutorial's Eq 53, pycma's default).
CMA-ES uses only the ranking of each generation, so ranking by Deb's rules (less
violation first, then lower objective) handles constraints with no penalty scale, and an
infeasible start walks toward feasibility. Candidates are clipped into the unit box
before evaluation and the update uses the clipped points.

Written here rather than wrapping the ``cma`` package: importing it costs ~1.8 s,
its Python bookkeeping ~6 ms per generation (more than evaluating 100 EMB profiles),
and it draws from numpy's global generator unless told otherwise; this core draws from
the run's Generator and costs ~0.1 ms per generation.

The same core is the ``cmaes`` stage of ``[solver.polish]`` (:mod:`camopt.solvers.polish`).

IPOP (Auger & Hansen 2005, "A restart CMA evolution strategy with increasing population
size"): with ``restarts`` > 0 the solver starts again, from a uniform random point of the
unit box drawn from the run's Generator and with the population multiplied by
``population_growth``, when a run converges (every step below ``tolx``) or stagnates (its
generation-best by Deb's rules changes by at most ``tolfun`` relative, in violation and in
objective, over the last 10 + ceil(30 n / lambda) generations, Hansen's TolFun window).
The best so far is kept over every restart.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field

from camopt.config.models import MAX_ITERATIONS, MAX_POPULATION, SolverOptions
from camopt.core.problem import Evaluation, Problem
from camopt.mechanics import Floats, Ints
from camopt.solvers.base import BestSoFar, Solver, StopReason, snap
from camopt.solvers.registry import register_solver


class CMACore:
    """CMA-ES state in the unit box (Hansen 2016, Table 1): ``ask`` draws a generation,
    ``tell`` takes its ranking (0 = best)."""

    def __init__(self, u0: Floats, sigma: float, rng: np.random.Generator,
                 popsize: int | None = None, active: bool = False) -> None:
        n = self.n = len(u0)
        self.rng = rng
        self.lam = lam = popsize or 4 + int(3 * np.log(n))
        self.mu = mu = lam // 2
        w = np.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
        self.w = w / w.sum()
        self.mueff = mueff = 1.0 / np.sum(self.w**2)
        self.cc = (4 + mueff / n) / (n + 4 + 2 * mueff / n)
        self.cs = (mueff + 2) / (n + mueff + 5)
        self.c1 = 2 / ((n + 1.3) ** 2 + mueff)
        self.cmu = min(1 - self.c1, 2 * (mueff - 2 + 1 / mueff) / ((n + 2) ** 2 + mueff))
        self.damps = 1 + 2 * max(0.0, np.sqrt((mueff - 1) / (n + 1)) - 1) + self.cs
        self.negative = self._negative_weights(lam, mu) if active else None
        self.chi_n = np.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
        self.mean = np.asarray(u0, dtype=float).copy()
        self.sigma = float(sigma)
        self.C = np.eye(n)
        self.B = np.eye(n)
        self.D = np.ones(n)
        self.pc = np.zeros(n)
        self.ps = np.zeros(n)
        self.generation = 0

    def ask(self) -> Floats:
        """One generation, (lam, n), clipped into [0, 1]."""
        Z = self.rng.standard_normal((self.lam, self.n))
        return np.clip(self.mean + self.sigma * (Z * self.D) @ self.B.T, 0.0, 1.0)

    def tell(self, U: Floats, order: Ints) -> None:
        """Update from the generation ``U`` and its indices best first (``order``)."""
        n, cs, cc = self.n, self.cs, self.cc
        self.generation += 1
        old = self.mean
        sel = U[order[: self.mu]]
        self.mean = self.w @ sel
        y = (self.mean - old) / self.sigma
        inv_sqrt_c = (self.B / self.D) @ self.B.T
        self.ps = (1 - cs) * self.ps + np.sqrt(cs * (2 - cs) * self.mueff) * inv_sqrt_c @ y
        norm_ps = np.linalg.norm(self.ps)
        hsig = (norm_ps / np.sqrt(1 - (1 - cs) ** (2 * self.generation)) / self.chi_n
                < 1.4 + 2 / (n + 1))
        self.pc = (1 - cc) * self.pc + hsig * np.sqrt(cc * (2 - cc) * self.mueff) * y
        art = (sel - old) / self.sigma
        rank_mu = (art.T * self.w) @ art
        decay = 1 - self.c1 - self.cmu
        if self.negative is not None:  # active: the worst lambda - mu push C away
            worst = (U[order[self.mu:]] - old) / self.sigma
            z2 = np.sum((worst @ inv_sqrt_c) ** 2, axis=1)  # C^-1/2 is symmetric
            weights = self.negative * n / np.maximum(z2, 1e-300)
            rank_mu += (worst.T * weights) @ worst
            decay -= self.cmu * self.negative.sum()
        self.C = (decay * self.C
                  + self.c1 * (np.outer(self.pc, self.pc) + (1 - hsig) * cc * (2 - cc) * self.C)
                  + self.cmu * rank_mu)
        self.sigma *= np.exp(min(1.0, (cs / self.damps) * (norm_ps / self.chi_n - 1)))
        self.C = (self.C + self.C.T) / 2
        d2, self.B = np.linalg.eigh(self.C)
        self.D = np.sqrt(np.maximum(d2, 1e-30))

    def _negative_weights(self, lam: int, mu: int) -> Floats:
        """Active CMA-ES's weights of the worst ``lam - mu`` (Hansen 2016, Eq 53): the
        tail of ln((lam + 1) / 2) - ln i, scaled so that they sum to minus the least of
        1 + c1 / c_mu, 1 + 2 mu_eff^- / (mu_eff + 2) and (1 - c1 - c_mu) / (n c_mu)."""
        raw = np.log((lam + 1) / 2) - np.log(np.arange(mu + 1, lam + 1))
        if not raw.size:
            return raw
        mueff_neg = raw.sum() ** 2 / np.sum(raw**2)
        alpha = min(1 + self.c1 / self.cmu, 1 + 2 * mueff_neg / (self.mueff + 2),
                    (1 - self.c1 - self.cmu) / (self.n * self.cmu))
        return raw * alpha / np.abs(raw).sum()

    def step_size(self) -> float:
        """The largest standard deviation of the search distribution (unit coordinates)."""
        return float(self.sigma * self.D.max())


def deb_order(f: Floats, violation: Floats) -> Ints:
    """Indices best first by Deb's rules (violation, then objective; NaN as +inf)."""
    f = np.where(np.isnan(f), np.inf, f)
    return np.lexsort((f, np.where(np.isnan(violation), np.inf, violation)))


class CMAESOptions(SolverOptions):
    """Options of ``cmaes``."""

    name: Literal["cmaes"] = "cmaes"
    population: int | None = Field(None, ge=4, le=MAX_POPULATION, description="lambda "
                                   f"(default 4 + 3 ln n; at most {MAX_POPULATION}: memory)")
    generations: int = Field(500, ge=1, le=MAX_ITERATIONS,
                             description=f"generations (at most {MAX_ITERATIONS}: time)")
    sigma: float = Field(0.3, gt=0, le=1, description="initial step, fraction of each range")
    x0: dict[str, float] | None = Field(
        None, description="start (display units); default the case's design, else the centre")
    tolx: float = Field(1e-12, gt=0, description="stop when every step is below (normalised)")
    evaluations: int | None = Field(None, ge=1, description="evaluation budget over every "
                                    "restart (None: generations alone)")
    restarts: int = Field(0, ge=0, le=20, description="IPOP: restarts from random starts "
                          "with a growing population after convergence or stagnation")
    population_growth: float = Field(2.0, ge=1.0, le=10.0, description="IPOP: population "
                                     "factor per restart")
    active: bool = Field(False, description="active CMA-ES: the worst half of each "
                         "generation lowers the variance along its steps (Hansen 2016, Eq "
                         "53; pycma's default)")
    tolfun: float = Field(1e-9, ge=0, description="IPOP: a run stagnates when its "
                          "generation-best changes by at most this (relative) over "
                          "10 + 30 n / lambda generations")


@register_solver
class CMAES(Solver):
    """CMA-ES over a case's continuous variables, ranked by Deb's rules."""

    name = "cmaes"
    Options = CMAESOptions
    options: CMAESOptions
    summary = "CMA-ES (Hansen 2016) ranked by Deb's rules, in the unit box (generic)"
    test_options = {"generations": 150}
    integers = False

    def __init__(self, problem: Problem, options: CMAESOptions, rng: np.random.Generator
                 ) -> None:
        super().__init__(problem, options, rng)
        initial = problem.initial_x()
        if options.x0 is not None:
            x0 = problem.from_display(options.x0)
        elif initial is not None:
            x0 = np.asarray(initial, dtype=float)
        else:
            x0 = (problem.lower + problem.upper) / 2
        self.core = CMACore(np.clip(problem.to_unit(x0), 0, 1), options.sigma, rng,
                            options.population, options.active)
        self._best = BestSoFar()
        self.restart = 0
        self._history: list[tuple[float, float]] = []  # (violation, f) of each generation's best

    def max_iterations(self) -> int:
        return self.options.generations

    def ask(self) -> Floats:
        return snap(self.problem, self.problem.from_unit(self.core.ask()))

    def tell(self, X: Floats, ev: Evaluation) -> None:
        self.nfev += len(X)
        self.nit += 1
        order = deb_order(ev.f, ev.violation)
        self.core.tell(self.problem.to_unit(X), order)
        self._best.offer(X, ev)
        self._history.append((float(ev.violation[order[0]]), float(ev.f[order[0]])))
        if self.restart < self.options.restarts and self._run_ended():
            self._start_again()

    def _run_ended(self) -> bool:
        """Whether the current run converged (every step below ``tolx``) or stagnated
        (Hansen's TolFun over the window 10 + ceil(30 n / lambda) generations)."""
        if self.core.step_size() < self.options.tolx:
            return True
        window = 10 + int(np.ceil(30 * self.core.n / self.core.lam))
        if len(self._history) < window:
            return False
        recent = np.array(self._history[-window:])
        with np.errstate(invalid="ignore"):
            spread = np.ptp(recent, axis=0)
            scale = np.maximum(1.0, np.abs(recent).min(axis=0))
        return bool(np.all(spread <= self.options.tolfun * scale))

    def _start_again(self) -> None:
        """IPOP: a new run from a uniform random start, population times the growth."""
        self.restart += 1
        lam = min(int(np.ceil(self.core.lam * self.options.population_growth)),
                  MAX_POPULATION)
        self.core = CMACore(self.rng.random(self.core.n), self.options.sigma, self.rng, lam,
                            self.options.active)
        self._history = []

    def best(self) -> tuple[Floats, Evaluation]:
        return self._best.get()

    def stop_reason(self) -> StopReason | None:
        if self.nit >= self.options.generations:
            return StopReason.BUDGET
        if self.options.evaluations is not None and self.nfev >= self.options.evaluations:
            return StopReason.BUDGET
        if self.nit == 0:
            return None
        if not self.options.restarts:  # one run: it ends when it has converged
            return StopReason.CONVERGED if self.core.step_size() < self.options.tolx else None
        if self.restart >= self.options.restarts and self._run_ended():
            return StopReason.CONVERGED
        return None

    def notes(self) -> list[str]:
        if not self.options.restarts:
            return []
        return [f"IPOP: {self.restart} restart(s), last population {self.core.lam}"]
