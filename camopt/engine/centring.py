"""Yield centring: a robust repeat's result moved to where the most of one fixed set of
draws pass (docs/tolerance.md, "Yield centring").

The robust search (:mod:`camopt.engine.robust`) ranks a candidate by its worst draw's
worst constraint on each generation's few draws. Where discrete requirements fail (the
VCB's latch: a normalised violation of ~1 whatever the design), that column hides every
small margin beside it, and the search can end with a continuous requirement on its limit
(the VCB's rod travel 0.009 mm inside, with a spread of +-0.012 mm). Centring is the
yield maximisation of circuit design (design centring): a sample-average approximation
over ``S`` draws fixed for the whole stage, each draw's pass smoothed so the estimate is
continuous in the design,

    F(x) = 1 - 1/S sum_s prod_i sigmoid(-kappa g_si(x) / tau_i),

``g_si`` constraint ``i``'s normalised value (<= 0 met) at draw ``s``, ``tau_i`` its
standard deviation over the draws at the starting design (:data:`TAU_FLOOR` where it is
~0: a constraint that does not move), ``kappa`` = :data:`SHARPNESS`; a draw with a
non-finite objective or a NaN constraint passes with 0. A local CMA-ES (the core of the
``cmaes`` solver, :class:`camopt.solvers.cmaes.CMACore`) minimises F from the design for a
given number of generations, with a small initial step, ranking by F plus the nominal
design's violation, and the best nominally feasible design it saw is kept: a design its
case refuses at nominal is no result, however many draws it passes (the robust search's
draws judge the VCB in one model form each, its nominal verdict in every form at once),
but the walk may cross such designs (ranked by Deb's rules instead, the VCB's centring
from a design with three requirements on their nominal limits found nothing better in 80
generations; ranked by F plus the violation, 0.965 -> 0.976 on the selection's draws).
Whether it is kept in the end is judged on other draws (the robust selection's:
:meth:`camopt.engine.robust.RobustProblem.select`).

Written here: no library offers a smoothed sample-average yield; the optimiser is the
project's own CMA-ES core.

The solvers' CMA-ES core and rounding are imported where used (only a robust run with
``centre_generations`` centres)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from camopt.core.problem import FEASIBILITY_TOL, Problem
from camopt.mechanics import Floats, Ints

SHARPNESS = 3.0
"""kappa: a draw at one standard deviation inside every limit counts as passing with
sigmoid(3) = 0.95 per constraint, one on the limit with 0.5."""
TAU_FLOOR = 1e-3
"""tau of a constraint whose spread over the draws is below it (normalised units)."""

Draws = Callable[[Floats], tuple[Floats, Floats, Floats]]
"""Designs (n, n_var), SI, to their constraints (n, S, n_constr) and objectives (n, S) on
the stage's fixed draws, and their nominal designs' violations (n,; 0: feasible, +inf for
a non-finite nominal objective)."""


@dataclass(frozen=True)
class Centred:
    """The stage's result: the design (n_var,), SI, and on the stage's draws its pass
    share and that of the design it started from, and the generations run."""

    x: Floats
    passed: float
    passed_start: float
    generations: int


def spread(g: Floats) -> Floats:
    """tau (n_constr,): each constraint's standard deviation over the draws ``g`` (S,
    n_constr) of one design, finite values only, at least :data:`TAU_FLOOR`."""
    finite = np.where(np.isfinite(g), g, np.nan)
    with np.errstate(invalid="ignore"):
        counted = np.isfinite(finite).sum(axis=0) > 1
        tau = np.where(counted, np.nanstd(np.where(counted, finite, 0.0), axis=0), 0.0)
    return np.maximum(tau, TAU_FLOOR)


def smoothed_failure(g: Floats, f: Floats, tau: Floats) -> Floats:
    """F (n,) of designs whose draws gave constraints ``g`` (n, S, n_constr) and
    objectives ``f`` (n, S) (module docstring): 0 when every draw passes with a wide
    margin, 1 when none does."""
    with np.errstate(invalid="ignore"):  # NaN (not computed) fails, +-inf pass or fail
        z = np.where(np.isnan(g), -np.inf, -SHARPNESS * g / tau)
    # log sigmoid, summed over constraints: the product without underflow
    log_pass = -np.logaddexp(0.0, -z).sum(axis=2)
    passes = np.where(np.isfinite(f), np.exp(log_pass), 0.0)
    return 1.0 - passes.mean(axis=1)


def passed(g: Floats, f: Floats) -> Floats:
    """(n,) the share of each design's draws that meet every constraint with a finite
    objective, from ``g`` (n, S, n_constr) and ``f`` (n, S)."""
    worst = g.max(axis=2) if g.shape[2] else np.full(f.shape, -np.inf)
    return (np.isfinite(f) & (np.where(np.isnan(worst), np.inf, worst) <= FEASIBILITY_TOL)
            ).mean(axis=1)


def ranking(F: Floats, violation: Floats) -> Ints:
    """The order (n,) the walk ranks candidates in, best first: by F (n,) plus the
    nominal design's violation (n,), a refused design behind a feasible one whose F is
    worse by less than the refusal's violation, a non-finite violation last; ties keep
    the sampling order. F alone would walk into designs the case refuses, where F is
    least (the VCB's latch); Deb's rules stalled (module docstring)."""
    return np.argsort(np.where(np.isfinite(violation), F + violation, np.inf), kind="stable")


def keep(feasible_start: bool, feasible_centred: bool, share_start: float,
         share_centred: float) -> bool:
    """Whether the centred design replaces the design it started from, judged on the
    robust selection's draws: the case's nominal verdict first (a centred design the
    case accepts replaces a start it refuses, never the other way round), then, when
    both are judged alike, a strictly larger pass share ``share_centred`` than
    ``share_start`` (a tie keeps the start: centring that does not help changes
    nothing)."""
    if feasible_centred != feasible_start:
        return feasible_centred
    return share_centred > share_start


def centre(problem: Problem, draws: Draws, x0: Floats, generations: int, step: float,
           rng: np.random.Generator) -> Centred:
    """Minimise F from ``x0`` (n_var,), SI, for ``generations`` CMA-ES generations of
    the default population, initial step ``step`` (a fraction of each variable's range;
    integer variables are rounded, so with a small step they stay where they are).
    Returns the nominally feasible design with the least F seen: ``x0`` if none beat it,
    or, when ``x0`` is itself refused at nominal, if the walk met no feasible design."""
    from camopt.solvers.base import snap  # the solvers' modules, on first use
    from camopt.solvers.cmaes import CMACore

    g0, f0, v0 = draws(x0[None, :])
    tau = spread(g0[0])
    # a start the case refuses at nominal sets no bar: any feasible design replaces it
    best_x = x0.copy()
    best_F = float(smoothed_failure(g0, f0, tau)[0]) if v0[0] == 0 else np.inf
    best_passed = start = float(passed(g0, f0)[0])
    core = CMACore(np.clip(problem.to_unit(x0[None, :])[0], 0.0, 1.0), step, rng)
    for _ in range(generations):
        U = core.ask()
        X = snap(problem, problem.from_unit(U))  # integers rounded, as every solver's
        g, f, violation = draws(X)
        F = smoothed_failure(g, f, tau)
        core.tell(U, ranking(F, violation))
        i = int(np.argmin(np.where(violation == 0, F, np.inf)))
        if violation[i] == 0 and F[i] < best_F:
            best_x, best_F = X[i].copy(), float(F[i])
            best_passed = float(passed(g[i:i + 1], f[i:i + 1])[0])
    return Centred(best_x, best_passed, start, generations)
