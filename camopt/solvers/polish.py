"""A gradient polish of a population solver's best design (scipy's SLSQP).

The same idea as ``polish=True`` in scipy's differential_evolution: the swarm finds
the basin, a local constrained solver walks to its bottom. Two options make it an
epsilon-constraint method as well: ``minimise`` picks one of the case's reported
metrics as the objective, and ``limits`` caps other metrics; every case constraint
is kept, ``margin`` inside its bound so the end point is strictly feasible.

The polish is one iteration of its solver but many evaluations, so it runs under the
run's :class:`~camopt.solvers.base.Budget` (``run.max_evaluations``, ``run.max_seconds``),
which the driver hands the solver: every evaluation of every stage goes through a meter
that counts them and stops the scipy solve (an exception out of its objective) before a
batch would pass the budget or once the time is spent; the polish then ends on the best
design it evaluated. Without a limit reached the meter changes nothing.

scipy.optimize and the CMA-ES core are imported where a polish runs (scipy is slow to
import).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from camopt.config.models import MAX_LOCAL_ITERATIONS, SolverOptions
from camopt.core.problem import Evaluation, Problem
from camopt.errors import SolverError
from camopt.mechanics import Floats
from camopt.solvers.base import Budget, StopReason, better

_BAD = 1e6  # stands for a non-finite objective or constraint inside SLSQP


class PolishOptions(BaseModel):
    """``[solver.polish]``: SLSQP from the best design once the budget is spent."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    minimise: str | None = Field(
        None, description="metric to minimise (the objective's name or one the case "
        "reports); default the objective")
    limits: dict[str, float] = Field(
        default_factory=dict, description="upper limits on the objective or reported metrics, "
        "kept as constraints")
    margin: float = Field(
        1e-7, ge=0, description="normalised distance kept inside each bound; when SLSQP "
        "still ends outside one (it stops within its own accuracy), it is rerun from its "
        "end point with ten and a hundred times the margin")
    maxiter: int = Field(500, ge=1, le=MAX_LOCAL_ITERATIONS,
                         description=f"SLSQP iterations (at most {MAX_LOCAL_ITERATIONS})")
    ftol: float = Field(1e-10, gt=0, description="SLSQP objective tolerance")
    restore_within: float = Field(
        0.01, gt=0, description="slsqp, from an infeasible start: rerun further inside and "
        "restore feasibility only when SLSQP ends within this total normalised shortfall")
    method: list[Literal["slsqp", "cmaes"]] = Field(
        ["slsqp"], min_length=1, description="stages run in turn, each from the better "
        "of its start and the previous end: 'slsqp' (gradient, keeps a margin) and/or "
        "'cmaes' (CMA-ES ranked by Deb's rules; for sampled, kinked measures)")
    sigma: float = Field(0.01, gt=0, le=0.5, description="cmaes: initial step, fraction "
                         "of each variable's range")
    evaluations: int = Field(20000, ge=10, description="cmaes: evaluation budget (split "
                             "over the restarts)")
    population: int | None = Field(None, ge=4, description="cmaes: candidates per "
                                   "generation (default 4 + 3 ln n)")
    restarts: int = Field(0, ge=0, description="cmaes: reruns from the best so far")
    integer_reach: int = Field(
        2, ge=1, description="integer variables: how many steps beyond the best integer "
        "value to try in each direction (each with its continuous variables polished)")


class PolishableOptions(SolverOptions):
    """Options of a population solver that can end with a polish."""

    polish: PolishOptions | None = Field(
        None, description="[solver.polish] table (minimise, limits, margin, maxiter, ftol): "
        "SLSQP from the best design once the budget is spent")


class _BudgetSpent(Exception):
    """Raised by :class:`_Metered` out of a scipy solve when the run's budget is spent
    (control flow inside :func:`polish`, never seen outside it)."""

    def __init__(self, reason: StopReason) -> None:
        super().__init__(reason.value)
        self.reason = reason


class _Metered(Problem):
    """``base`` with every evaluation counted against ``budget`` (``used`` evaluations
    already spent by the run) and the best row seen kept by Deb's rules on ``rank``'s
    (objective, violation): a batch that would pass the budget, or any once the time is
    spent, raises :class:`_BudgetSpent` instead of being evaluated."""

    def __init__(self, base: Problem, budget: Budget, used: int,
                 rank: Callable[[Evaluation], tuple[Floats, Floats]]) -> None:
        self.base, self.budget, self.used, self.rank = base, budget, used, rank
        self.variables = base.variables
        self.constraint_names = base.constraint_names
        self.objective_name = base.objective_name
        self.count = 0
        self.best: tuple[Floats, Floats, Floats] | None = None

    def evaluate(self, X: Floats) -> Evaluation:
        X = np.atleast_2d(X)
        reason = self.budget.spent(self.used + self.count + len(X))
        if reason is not None:
            raise _BudgetSpent(reason)
        ev = self.base.evaluate(X)
        self.count += len(X)
        f, v = self.rank(ev)
        i = int(np.lexsort((f, v))[0])
        if self.best is None or better(f[i:i + 1], v[i:i + 1], *self.best[1:])[0]:
            self.best = (X[i].copy(), f[i:i + 1], v[i:i + 1])
        return ev


def polish(problem: Problem, x0: Floats, options: PolishOptions,
           rng: np.random.Generator | None = None) -> tuple[Floats, int, str]:
    """Polish ``x0``: SLSQP on the continuous variables; with integer variables, the
    integer-aware search of :func:`polish_mixed`. End point, evaluations, message."""
    end, nfev, message, _ = polish_within(problem, x0, options, rng, Budget(), 0)
    return end, nfev, message


def polish_within(problem: Problem, x0: Floats, options: PolishOptions,
                  rng: np.random.Generator | None, budget: Budget, used: int
                  ) -> tuple[Floats, int, str, StopReason | None]:
    """:func:`polish` under the run's ``budget``, of which ``used`` evaluations are
    spent; one more is kept for the end point's own evaluation by the driver. End point,
    evaluations, message, and the limit that stopped the polish (None: it ran to its
    end, and then end point, evaluations and message are :func:`polish`'s)."""
    metered = _Metered(problem, Budget(None if budget.max_nfev is None
                                       else budget.max_nfev - 1, budget.deadline),
                       used, lambda ev: _score(problem, ev, options))
    try:
        if problem.integer.any():
            return (*polish_mixed(metered, x0, options, rng), None)
        return (*polish_continuous(metered, x0, options, rng), None)
    except _BudgetSpent as stop:
        end = np.asarray(x0, dtype=float) if metered.best is None else metered.best[0]
        return (end, metered.count, f"stopped: {stop.reason.value} after "
                f"{metered.count} evaluations; the best design it evaluated", stop.reason)


def polish_mixed(problem: Problem, x0: Floats, options: PolishOptions,
                 rng: np.random.Generator | None = None) -> tuple[Floats, int, str]:
    """Integer-aware polish: fix the integer variables, polish the continuous ones
    (:func:`polish_continuous`), then step each integer variable to its neighbours,
    polishing the continuous ones again at each, and move while Deb's rules prefer the
    neighbour; ``options.integer_reach`` non-improving steps in a row end a direction
    (the objective over an integer can be flat with small bumps)."""
    ints = np.flatnonzero(problem.integer)
    nfev = 0

    seen: dict[bytes, tuple[Floats, Evaluation]] = {}

    def local(x: Floats) -> tuple[Floats, Evaluation]:
        nonlocal nfev
        key = x[ints].tobytes()  # each integer combination is polished once
        if key not in seen:
            end, n, _ = polish_continuous(problem, x, options, rng)
            seen[key] = (end, problem.evaluate(end[None, :]))
            nfev += n + 1
        return seen[key]

    x, ev = local(np.asarray(x0, dtype=float))
    start_int = x[ints].copy()
    moved = True
    while moved:
        moved = False
        for j in ints:
            for step in (-1.0, 1.0):
                base = x.copy()
                for k in range(1, options.integer_reach + 1):
                    cand = base.copy()
                    cand[j] = base[j] + step * k
                    if not problem.lower[j] <= cand[j] <= problem.upper[j]:
                        break
                    end, eev = local(cand)
                    if better(eev.f, eev.violation, ev.f, ev.violation)[0]:
                        x, ev, moved = end, eev, True
                        break
    names = [problem.variables[j].name for j in ints]
    moves = ", ".join(f"{n} {a:g} -> {b:g}" for n, a, b in zip(names, start_int, x[ints]))
    return x, nfev, (f"integer-aware: {len(seen)} integer designs polished; {moves}")


def polish_continuous(problem: Problem, x0: Floats, options: PolishOptions,
                      rng: np.random.Generator | None = None) -> tuple[Floats, int, str]:
    """Each stage of ``options.method`` in turn over the continuous variables (integer ones
    held at ``x0``'s values), each from the better (Deb's rules) of the previous stage's
    start and end: end point, evaluations and the stages' messages."""
    x = np.asarray(x0, dtype=float)
    ev = problem.evaluate(x[None, :])
    nfev, messages = 1, []
    for stage in options.method:
        if stage == "slsqp":
            end, n, message = _slsqp(problem, x, options)
        else:
            if rng is None:
                raise SolverError("polish: the cmaes stage needs the solver's generator")
            end, n, message = _cmaes(problem, x, options, rng)
        end_ev = problem.evaluate(end[None, :])
        nfev += n + 1
        kept = better(*_score(problem, end_ev, options), *_score(problem, ev, options))[0]
        if kept:
            x, ev = end, end_ev
        messages.append(f"{stage}: {message}" + ("" if kept else " (not kept)"))
    return x, nfev, "; ".join(messages)


def _unit_map(problem: Problem, x0: Floats) -> tuple[Floats, Any]:
    """The continuous variables of ``x0`` in bounds-normalised coordinates, and the map
    from such coordinates back to a full SI design (integer variables held at ``x0``'s)."""
    x0 = np.asarray(x0, dtype=float)
    free = ~problem.integer
    lo, span = problem.lower[free], problem.upper[free] - problem.lower[free]

    def design(U: Floats) -> Floats:
        U = np.asarray(U, dtype=float)
        X = np.broadcast_to(x0, U.shape[:-1] + x0.shape).copy()
        X[..., free] = lo + U * span
        return X

    return np.clip((x0[free] - lo) / span, 0, 1), design


def _score(problem: Problem, ev: Evaluation, options: PolishOptions
           ) -> tuple[Floats, Floats]:
    """What the polish ranks by (Deb's rules): the ``minimise`` metric (+inf where not
    finite) and the violation plus the excess over ``limits``, each (n,)."""
    name = options.minimise
    f = ev.f if name is None or name == problem.objective_name else ev.extras[name]
    return (np.where(np.isfinite(f), f, np.inf),
            ev.violation + _limit_excess(problem, ev, options))


def _limit_excess(problem: Problem, ev: Evaluation, options: PolishOptions) -> Floats:
    """Normalised excess of each candidate over ``options.limits`` (0 where within), (n,)."""
    out = np.zeros(len(ev.f))
    for name, cap in options.limits.items():
        v = ev.f if name == problem.objective_name else ev.extras[name]
        out += np.clip((v - cap) / abs(cap) if cap else v, 0, None)
    return np.where(np.isnan(out), np.inf, out)


def _cmaes(problem: Problem, x0: Floats, options: PolishOptions, rng: np.random.Generator
           ) -> tuple[Floats, int, str]:
    """CMA-ES (:mod:`camopt.solvers.cmaes`) from ``x0`` over the continuous variables, in
    bounds-normalised coordinates, ranking each generation by Deb's rules on
    (violation + excess over ``limits``, ``minimise`` metric): the case's penalty scale
    does not matter and an infeasible start walks toward feasibility. ``restarts`` rerun
    it from the best so far. Every generation is one vectorised evaluation."""
    from camopt.solvers.cmaes import CMACore, deb_order

    u0, design = _unit_map(problem, x0)
    best_u, (best_f, best_v) = u0, _score(problem, problem.evaluate(design(u0)[None, :]),
                                          options)
    nfev, stops = 1, []
    per_run = options.evaluations // (options.restarts + 1)
    for _ in range(options.restarts + 1):
        core = CMACore(best_u, options.sigma, rng, options.population)
        used, stop = 0, "budget"
        while used + core.lam <= per_run:
            U = core.ask()
            f, v = _score(problem, problem.evaluate(design(U)), options)
            order = deb_order(f, v)
            core.tell(U, order)
            used += len(U)
            i = order[0]
            if better(f[i:i + 1], v[i:i + 1], best_f, best_v)[0]:
                best_u, best_f, best_v = U[i].copy(), f[i:i + 1], v[i:i + 1]
            if core.step_size() < 1e-12:
                stop = "step below 1e-12"
                break
        nfev += used
        stops.append(stop)
    return design(best_u), nfev, f"CMA-ES {nfev} evaluations (stops: {', '.join(stops)})"


def _slsqp(problem: Problem, x0: Floats, options: PolishOptions
           ) -> tuple[Floats, int, str]:
    """SLSQP in bounds-normalised coordinates from ``x0`` over the continuous variables
    (integer ones held at ``x0``'s values): end point, evaluations and scipy's message."""
    start, design = _unit_map(problem, x0)
    n_free = start.size
    cache: dict[bytes, Evaluation] = {}
    keep = 2 * (n_free + 2)

    def evaluate(u: Floats) -> Evaluation:
        # SLSQP asks for f and then g at each point, and differences both at the same
        # n_free + 1 points (the same absolute step): one evaluation serves both (the
        # constraints' Jacobian evaluated again at every point was half the polish's time)
        key = u.tobytes()
        hit = cache.get(key)
        if hit is None:
            if len(cache) >= keep:
                del cache[next(iter(cache))]  # the oldest
            hit = cache[key] = problem.evaluate(design(u)[None, :])
        return hit

    def metric(ev: Evaluation, name: str | None) -> float:
        if name is None or name == problem.objective_name:
            return float(ev.f[0])
        return float(ev.extras[name][0])

    def objective(u: Floats) -> float:
        v = metric(evaluate(u), options.minimise)
        return v if np.isfinite(v) else _BAD

    def constraints(u: Floats, margin: float) -> Floats:
        ev = evaluate(u)
        caps = [(cap - metric(ev, k)) / abs(cap) if cap else -metric(ev, k)
                for k, cap in options.limits.items()]
        c = np.r_[-ev.g[0], caps] - margin
        return np.where(np.isfinite(c), c, -_BAD)

    from scipy.optimize import minimize  # scipy.optimize: 0.5 s, only for a run

    x, nfev, message = start, 0, ""
    start_feasible = bool(np.all(constraints(start, 0.0) >= 0))
    for factor in (1.0, 10.0, 100.0):  # rerun, further inside, while it ends outside
        margin = options.margin * factor
        res = minimize(objective, x, method="SLSQP", bounds=[(0.0, 1.0)] * n_free,
                       constraints=[{"type": "ineq",
                                     "fun": lambda u, m=margin: constraints(u, m)}],
                       options={"maxiter": options.maxiter, "ftol": options.ftol})
        x, nfev, message = np.clip(res.x, 0, 1), nfev + int(res.nfev), str(res.message)
        shortfall = float(np.sum(np.clip(-constraints(x, 0.0), 0, None)))
        if shortfall == 0:
            return design(x), nfev, message
        if shortfall > options.restore_within and not start_feasible:
            # from an infeasible start and still far outside: reruns and the restoration
            # below (which needs a feasible anchor) cost up to 1e4 evaluations for little
            return design(x), nfev, message + f"; ended infeasible (shortfall {shortfall:.3g})"
    # SLSQP's finite-difference gradients can stall a hair outside a bound on cases
    # whose measures are sampled (a sample entering a section makes small jumps).
    # Restore: minimise the squared shortfall from 100 margins inside every bound
    # (reaching zero makes a feasible anchor; failing that, a feasible start is one),
    # then walk from the anchor toward SLSQP's end point to the last feasible point
    target = max(100 * options.margin, 1e-6)

    def excess(u: Floats) -> float:  # in units of the target margin: O(1) near the bound
        return float(np.sum(np.clip(1 - constraints(u, 0.0) / target, 0, None) ** 2))

    # derivative-free (the same kinks stall gradients), from a small simplex at the end
    step = np.where(x + 1e-5 <= 1.0, 1e-5, -1e-5)
    simplex = np.vstack([x, x + np.diag(step)])
    back = minimize(excess, x, method="Nelder-Mead", bounds=[(0.0, 1.0)] * n_free,
                    options={"initial_simplex": simplex, "xatol": 1e-10, "fatol": 1e-12,
                             "maxiter": 200 * n_free})
    nfev += int(back.nfev)
    anchor = next((a for a in (np.clip(back.x, 0, 1), start)
                   if np.all(constraints(a, 0.0) >= 0)), None)  # else: a feasible start
    if anchor is None:
        return design(x), nfev, message + "; could not restore feasibility"
    inside, outside = 0.0, 1.0  # fractions of the way from the anchor to SLSQP's end
    for _ in range(30):
        t = (inside + outside) / 2
        if np.all(constraints(anchor + t * (x - anchor), 0.0) >= 0):
            inside = t
        else:
            outside = t
    nfev += 30
    x = anchor + inside * (x - anchor)
    return design(x), nfev, message + "; feasibility restored"


class Polishing:
    """Mixin for population solvers with a ``polish`` option: after the budget, one more
    iteration runs :func:`polish` from the best design; the end point replaces the best
    when Deb's rules prefer it."""

    problem: Problem
    options: Any
    nfev: int
    nit: int
    rng: np.random.Generator
    budget: Budget
    _polished: tuple[Floats, Evaluation] | None = None
    _polishing = False
    polish_message = ""
    polish_stopped: StopReason | None = None
    """The run's limit that stopped the polish (the solver's stop reason then)."""

    def __init__(self, problem: Problem, options: Any, rng: np.random.Generator) -> None:
        super().__init__(problem, options, rng)  # type: ignore[call-arg]
        self.check_polish()

    def budget_spent(self) -> bool:  # pragma: no cover - each solver says
        raise NotImplementedError

    def population_best(self) -> tuple[Floats, Evaluation]:  # pragma: no cover
        raise NotImplementedError

    def check_polish(self) -> None:
        """Fail at construction, not after the budget, on metric names the case lacks."""
        o = self.options.polish
        if o is None:
            return
        mid = (self.problem.lower + self.problem.upper) / 2
        known = [self.problem.objective_name, *self.problem.evaluate(mid[None, :]).extras]
        for key, name in [("minimise", o.minimise), *(("limits", k) for k in o.limits)]:
            if name is not None and name not in known:
                raise SolverError(f"polish.{key}: no metric '{name}'; the case reports "
                                  f"{', '.join(known)}")

    def polish_pending(self) -> bool:
        """Whether the budget is spent and the polish has not run yet."""
        return (self.options.polish is not None and self.budget_spent()
                and self._polished is None)

    def polish_ask(self) -> Floats:
        """Run the polish from the population's best; its end point, (1, n_var)."""
        x, _ = self.population_best()
        end, nfev, self.polish_message, self.polish_stopped = polish_within(
            self.problem, x, self.options.polish, self.rng, self.budget, self.nfev)
        self.nfev += nfev
        self._polishing = True
        return end[None, :]

    def polish_tell(self, X: Floats, ev: Evaluation) -> bool:
        """Take the polished point if this tell is the polish's; True when it was."""
        if not self._polishing:
            return False
        self._polishing = False
        self.nfev += len(X)
        self.nit += 1
        self._polished = (X[0].copy(), ev.take(0))
        return True

    def with_polish(self, x: Floats, ev: Evaluation) -> tuple[Floats, Evaluation]:
        """The better of the population's best and the polished design."""
        if self._polished is None:
            return x, ev
        px, pev = self._polished
        if better(pev.f, pev.violation, ev.f, ev.violation)[0]:
            return px.copy(), pev
        return x, ev

    def best(self) -> tuple[Floats, Evaluation]:
        return self.with_polish(*self.population_best())

    def notes(self) -> list[str]:
        return self.polish_notes()

    def polish_notes(self) -> list[str]:
        if self._polished is None:
            return []
        x, ev = self.population_best()
        kept = self.with_polish(x, ev)[1] is not ev
        return [f"polish: {self.polish_message}; "
                f"{'replaced' if kept else 'did not improve on'} the population's best"]
