"""Robust design: every solver searches for yield under manufacturing tolerances.

:class:`RobustProblem` wraps a case's Problem so that any solver runs on it unchanged.
Per generation (``new_generation``, called by the driver before every ask) it draws one
set of ``S`` perturbations in units of each input's half-width, the same for every
candidate (common random numbers: candidates are compared on the same parts, so their
differences are not sampling noise). A candidate ``x`` is evaluated at its nominal design
and at ``S`` perturbed copies, population x samples in one vectorised call (in chunks,
:mod:`camopt.core.batch`). Its evaluation is:

- ``g``: for each case constraint the ``k``-th smallest of its ``S`` sampled values,
  ``k = ceil(search_yield S)`` (``search_yield`` defaults to ``yield_target``), and a
  last column ``yield``, the ``k``-th smallest of each sample's worst constraint.
  ``yield <= 0`` exactly when at least ``k`` samples meet every constraint, i.e. when the
  estimated yield reaches the target; the order statistic
  is continuous in ``x``, so an infeasible candidate still tells the search how far off it
  is (a yield count is flat at 0 far from the feasible set).
- ``f``: the nominal objective, its mean over the samples with a finite objective, or its
  ``quantile``; or (``objective = "margin"``, objective name ``yield_margin``) the yield
  column itself: among designs that meet the target the search then prefers the one
  whose worst part at the target's order statistic keeps the most margin to every limit
  (a max-min margin design, for cases whose own objective pulls against the margins, as
  the VCB's least surplus work pulls against its latch energy).
- ``extras``: the nominal design's metrics and ``yield`` (the estimate, share of samples
  meeting every constraint with a finite objective).

A solver that keeps evaluations across generations compares new candidates with designs
judged on other draws; the :class:`~camopt.core.capabilities.Stochastic` capability
asks it to evaluate them again on each generation's draws (``de_gr`` does: its
parents; ``pso``'s personal bests, ``nsga2``'s survivors and ``cmaes``'s best so far
are not). Even so a design can pass one
generation's draws by luck and be the solver's best when it stops. So the ``finalists``
best designs that met the target on their own generation's draws, with the solver's
best, are evaluated again on ``check_samples`` fresh draws when the repeat ends, and the
best of them by Deb's rules on those draws is the repeat's result
(:meth:`RobustProblem.select`): there a design is feasible when the lower bound of its
yield's Clopper-Pearson interval reaches ``yield_target``.

A case with model variants (capability :class:`~camopt.core.capabilities.HasVariants`:
the VCB's kept model forms) has draw ``j`` judged under variant ``j mod m``
(:func:`~camopt.core.variation.assign_variants`): the yield is over the tolerances and the
forms together, and the final check gives it per form too (``per_form``). Racing
(``race``): a candidate's draws are evaluated in stages (:func:`stages`) and it stops once
it has failed more draws than the deciding order statistic allows (:func:`race`): no
candidate's feasibility changes; an infeasible one's columns are estimated from fewer
draws.

With ``screen`` a candidate whose nominal design breaks a constraint (in every variant,
where the case has them) is not sampled: its
columns are its nominal constraints, and its yield column its nominal worst constraint
plus ``SCREENED`` (1e6), so that it ranks behind every sampled candidate while Deb's rules
still lead the unsampled ones towards nominal feasibility. The best design is checked at the end
with ``check_samples`` fresh draws (:func:`check`), and the Clopper-Pearson interval of its yield
is reported. Seeds: repeat ``i``'s draws come from ``SeedSequence(run.seed,
spawn_key=(i, ROBUST_KEY, 0))``, its selection's from ``(i, ROBUST_KEY, 1)``, the final
check's from ``SeedSequence(run.seed, spawn_key=(ROBUST_KEY, CHECK_KEY))``; never the
solver's generator, so the search itself is unchanged by the draws and results do not
depend on the worker count.

:mod:`camopt.engine.centring` is imported where used (only a run with ``centre_generations``
centres).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from camopt.config.models import CaseConfig, RobustSection
from camopt.core import stats
from camopt.core.batch import RowsDone
from camopt.core.capabilities import (
    HasFamily,
    HasResiduals,
    Repairable,
    Stochastic,
    capability_name,
)
from camopt.core.documents import DesignCheck, RobustCheck, with_quantile
from camopt.core.problem import FEASIBILITY_TOL, Evaluation, ObjectiveFloor, Problem, deb_best
from camopt.core.variation import (
    Distribution,
    Vary,
    applicable_defaults,
    apply,
    assign_variants,
    check_varies,
    mark,
    outside,
    parse_vary,
    physical_range,
    unit_draws,
    variants_of,
)
from camopt.errors import ConfigError
from camopt.mechanics import Bools, Floats, Ints

SCREENED = 1e6
"""Added to the yield column of a candidate not sampled (its nominal design infeasible)."""
YIELD = "yield"
"""Name of the yield constraint column and of the yield estimate among the extras."""
MARGIN = "yield_margin"
"""Objective name of a robust run with ``objective = "margin"``: the yield column (the
worst normalised constraint at the target's order statistic; <= 0 met, lower better)."""
ROBUST_KEY = 0x524F42  # "ROB": the spawn-key word of every robust draw
CHECK_KEY = 2**32 - 1  # the final check's key under ROBUST_KEY (never a repeat index)


@dataclass(frozen=True)
class Plan:
    """What varies and how: the inputs, their physical ranges (input units), the case
    fields' nominal values (fields' units) and the case's model variants drawn over
    (capability :class:`~camopt.core.capabilities.HasVariants`; none: one model)."""

    spec: RobustSection
    varies: tuple[Vary, ...]
    ranges: tuple[tuple[float, bool, float], ...]
    field_nominal: dict[str, float]
    variants: tuple[str, ...] = ()

    @property
    def distribution(self) -> Distribution:
        return Distribution(self.spec.distribution)


def plan(problem: Problem, case: CaseConfig, spec: RobustSection, tolerances: dict[str, str],
         source: str) -> Plan:
    """The plan of a ``[robust]`` table for a Problem: its ``vary`` (or the case's default
    tolerances that apply), checked; bad input is a ConfigError against ``robust.vary``."""
    key = "robust.vary"
    try:
        if spec.vary:
            varies = [parse_vary(source, f"{name}={tol}", key) for name, tol in spec.vary.items()]
        else:
            varies = applicable_defaults(problem, tolerances, source, key)
        check_varies(problem, varies, source, case.kind, key)
    except ConfigError:
        raise
    except Exception as exc:  # CamoptError with "source: key: what"
        raise ConfigError(source, key, str(exc).split(f"{key}: ", 1)[-1]) from None
    if not varies:
        raise ConfigError(source, key, f"case '{case.kind}' documents no tolerance for these "
                          "inputs; give robust.vary")
    ranges = tuple(physical_range(problem, type(case), v) for v in varies)
    fields = {v.field: float(getattr(case, v.field)) for v in varies if v.is_case_field}
    return Plan(spec, tuple(varies), ranges, fields, variants_of(problem))


def _values(problem: Problem, plan: Plan, X: Floats, unit: Floats) -> Floats:
    """Input values of every candidate at every draw, (n * S, k) in input units, candidate-
    major: candidate ``i``'s samples are rows ``i S .. i S + S - 1``."""
    n, (S, k) = len(X), unit.shape
    nominal = np.empty((n, k))
    for j, v in enumerate(plan.varies):
        if v.is_case_field:
            nominal[:, j] = plan.field_nominal[v.field]
        else:
            i = problem.names.index(v.name)
            nominal[:, j] = X[:, i] * problem.variables[i].scale
    half = np.abs(nominal) * np.array([v.tolerance / 100 if v.relative else 0.0
                                       for v in plan.varies])
    half += np.array([0.0 if v.relative else v.tolerance for v in plan.varies])
    return (nominal[:, None, :] + unit[None, :, :] * half[:, None, :]).reshape(n * S, k)


@dataclass(frozen=True)
class Sampled:
    """Candidates evaluated at their samples: constraints (n, S, n_constr), objectives
    (n, S), each sample's worst constraint (n, S; +inf for a non-finite objective) and
    each draw's model variant (S,; -1: every variant)."""

    g: Floats
    f: Floats
    worst: Floats
    variant: Ints

    @property
    def feasible(self) -> Bools:
        """(n, S) bool: the sample meets every constraint with a finite objective."""
        return self.worst <= FEASIBILITY_TOL


def sample(problem: Problem, plan: Plan, X: Floats, unit: Floats,
           progress: RowsDone | None = None, first: int = 0) -> Sampled:
    """Evaluate designs ``X`` (n, n_var) at draws ``unit`` (S, k): n x S rows in chunks of
    ``plan.spec.chunk_rows`` (:mod:`camopt.core.batch`); draws outside an input's physical
    range count as failed. ``progress`` is told the rows done after each chunk. Draw ``j``
    is judged under the case's model variant ``j mod m`` (:func:`assign_variants`), the
    same for every candidate; ``unit`` may be draws ``first ..`` of a generation's."""
    n, S = len(X), len(unit)
    values = _values(problem, plan, X, unit)
    variant = assign_variants(first + S, len(plan.variants))[first:]
    ev = apply(problem, np.repeat(X, S, axis=0), plan.varies, values,
               size=plan.spec.chunk_rows, progress=progress, variant=np.tile(variant, n))
    ev = mark(ev, outside(values, plan.ranges))
    g = np.where(np.isnan(ev.g), np.inf, ev.g).reshape(n, S, -1)
    f = np.asarray(ev.f, dtype=float).reshape(n, S)
    worst = g.max(axis=2) if g.shape[2] else np.full((n, S), -np.inf)
    worst = np.where(np.isfinite(f), worst, np.inf)
    return Sampled(g, f, worst, variant)


def _worst(g: Floats, f: Floats) -> Floats:
    """Each row's worst constraint (n,), +inf for a non-finite objective (-inf without
    constraints)."""
    worst = g.max(axis=1) if g.shape[1] else np.full(len(g), -np.inf)
    return np.where(np.isfinite(f), worst, np.inf)


def stages(samples: int, race: int) -> list[slice]:
    """The draws of each racing stage: ``race``, as many again, then doubling, the last
    stage cut at ``samples`` (one stage of all when ``race`` is 0 or covers them)."""
    if race <= 0 or race >= samples:
        return [slice(0, samples)]
    out, start, size = [], 0, race
    while start < samples:
        out.append(slice(start, min(start + size, samples)))
        start += size
        size = race if len(out) == 1 else 2 * size
    return out


@dataclass(frozen=True)
class Raced:
    """Candidates (n) raced over a generation's S draws (:func:`race`): the constraints at
    the deciding order statistic (n, n_constr), each candidate's worst constraint there
    (n,), its pass share over the draws it was evaluated on (n,), the objective statistic
    (n,) and the draws evaluated (n,; a prefix of the S)."""

    g: Floats
    worst: Floats
    estimate: Floats
    f: Floats
    evaluated: Floats


def race(problem: Problem, plan: Plan, X: Floats, unit: Floats, k: int) -> Raced:
    """Designs ``X`` (n, n_var) on draws ``unit`` (S, k_in), their evaluation decided by
    the 0-based order statistic ``k`` of each draw's worst constraint: it is <= 0 iff at
    least k + 1 draws pass, so a candidate that has failed more than S - k - 1 draws
    cannot meet it whatever its other draws give, and is not evaluated on them
    (:func:`stages`, ``plan.spec.race``). A stopped candidate's columns are the same
    quantile's order statistic over the draws it was evaluated on (index
    ceil((k + 1) e / S) - 1 of e): a positive yield column, as the full S would give
    (it failed), ranking it among the infeasible by an estimate of the same quantity.
    A candidate evaluated on every draw gets exactly :func:`sample`'s numbers."""
    n, S = len(X), len(unit)
    spec = plan.spec
    g = np.full((n, S, len(problem.constraint_names)), np.nan)
    f = np.full((n, S), np.nan)
    worst = np.full((n, S), np.nan)
    done = np.zeros(n, dtype=int)
    alive = np.arange(n)
    allowed = S - k - 1
    for rows in stages(S, spec.race):
        if not alive.size:
            break
        s = sample(problem, plan, X[alive], unit[rows], first=rows.start)
        g[alive, rows], f[alive, rows], worst[alive, rows] = s.g, s.f, s.worst
        done[alive] = rows.stop
        failed = (~(worst[alive, :rows.stop] <= FEASIBILITY_TOL)).sum(axis=1)
        alive = alive[failed <= allowed]
    n_constr = g.shape[2]
    g_at, worst_at = np.empty((n, n_constr)), np.empty(n)
    estimate, f_stat = np.empty(n), np.empty(n)
    for e in np.unique(done):
        mine = np.flatnonzero(done == e)
        j = k if e == S else min(int(math.ceil((k + 1) * e / S - 1e-9)) - 1, e - 1)
        j = max(j, 0)
        g_at[mine] = np.partition(g[mine, :e], j, axis=1)[:, j, :]
        worst_at[mine] = np.partition(worst[mine, :e], j, axis=1)[:, j]
        estimate[mine] = (worst[mine, :e] <= FEASIBILITY_TOL).mean(axis=1)
        if spec.objective in ("mean", "quantile"):
            f_stat[mine] = statistic(f[mine, :e], spec.objective, spec.quantile)
    return Raced(g_at, worst_at, estimate, f_stat, done)


def order_index(target: float, samples: int) -> int:
    """0-based index of the order statistic that decides a yield target:
    ``ceil(target S) - 1`` (at least ``ceil(target S)`` of ``S`` samples must pass)."""
    return max(int(math.ceil(target * samples - 1e-9)) - 1, 0)


def confident_index(target: float, samples: int, confidence: float) -> int:
    """0-based order statistic that decides "yield >= target" with confidence: at least
    ``c`` samples must pass, ``c`` the least count whose lower bound
    (:func:`camopt.core.stats.share_interval`, the interval every yield is reported
    with) reaches the target (all samples when none does)."""
    low, _ = stats.share_interval(np.arange(samples + 1), samples, confidence)
    enough = np.flatnonzero(low >= target - 1e-12)
    need = int(enough[0]) if enough.size else samples
    return max(need, 1) - 1


def statistic(f: Floats, objective: str, quantile: float) -> Floats:
    """The objective's mean over samples with a finite value, or its quantile (the next
    order statistic above, non-finite values counted as +inf), per row of ``f`` (n, S)."""
    if objective == "mean":
        finite = np.isfinite(f)
        total = np.where(finite, f, 0.0).sum(axis=1)
        count = finite.sum(axis=1)
        return np.divide(total, count, out=np.full(len(f), np.inf), where=count > 0)
    # "higher": an order statistic (never interpolated towards a better value, and no
    # inf - inf when failed samples are among the neighbours)
    return np.quantile(np.where(np.isnan(f), np.inf, f), quantile, axis=1, method="higher")


class RobustProblem(Problem, Stochastic):
    """A case's Problem whose evaluation is robust (module docstring): same variables,
    constraints plus ``yield``, objective a statistic of the case's. It declares
    :class:`~camopt.core.capabilities.Stochastic`, which the driver (and ``de_gr``) ask
    for; :func:`wrap` adds the case's own capabilities."""

    def __init__(self, base: Problem, robust_plan: Plan) -> None:
        self.base, self.plan = base, robust_plan
        self.variables = base.variables
        self.constraint_names = (*base.constraint_names, YIELD)
        self.objective_name = MARGIN if robust_plan.spec.objective == "margin" \
            else base.objective_name
        self.rng = np.random.default_rng(0)
        self.unit: Floats | None = None
        self.nominal_best: tuple[Floats, float] | None = None
        """The best design seen whose nominal evaluation is feasible, and its objective."""
        self.draws_evaluated = 0
        """Candidate draws evaluated so far (racing's saving is measured against it)."""
        self.finalists: tuple[Floats, Floats] = (np.empty((0, self.n_var)), np.empty(0))
        """Designs (m, n_var) that met the target on their generation's draws, lowest
        objective (m,) first: checked again at the end of the repeat (:meth:`select`)."""
        self.notes: tuple[str, ...] = ()
        """What the last :meth:`select` did beyond choosing (the yield centring)."""
        self._last: tuple[Floats, tuple[Evaluation, Floats, Bools]] | None = None
        """The designs of the last evaluation and their :meth:`_nominal`."""

    def reseed(self, seed: np.random.SeedSequence) -> None:
        """Start a repeat: its own draws, nothing carried over from another repeat."""
        self.rng = np.random.default_rng(seed)
        self.unit = None
        self.nominal_best = None
        self.finalists = (np.empty((0, self.n_var)), np.empty(0))
        self._last = None

    def new_generation(self) -> None:
        """Draw the generation's perturbations (S, k), shared by every candidate; with
        ``draws = "repeat"`` only the repeat's first generation draws (:meth:`reseed`
        clears them)."""
        spec = self.plan.spec
        if spec.draws == "repeat" and self.unit is not None:
            return
        self.unit = unit_draws(self.rng, spec.samples, len(self.plan.varies),
                               self.plan.distribution)

    def evaluate(self, X: Floats) -> Evaluation:
        """Robust objective and constraints of designs ``X`` (n, n_var), SI (module
        docstring); the draws are the current generation's."""
        if self.unit is None:
            self.new_generation()
        assert self.unit is not None
        X = np.atleast_2d(np.asarray(X, dtype=float))
        spec = self.plan.spec
        target = spec.yield_target if spec.search_yield is None else spec.search_yield
        ev = self.evaluate_at(X, self.unit, order_index(target, len(self.unit)))
        self._keep_finalists(X, ev)
        return ev

    def evaluate_at(self, X: Floats, unit: Floats, k: int) -> Evaluation:
        """As :meth:`evaluate` with the draws ``unit`` (S, k) given (any S), ``k`` the
        0-based order statistic that decides the yield column."""
        spec = self.plan.spec
        nominal, nom_worst, screened_in = self._nominal(X)
        self._remember(X, nominal)
        nom_g = np.where(np.isnan(nominal.g), np.inf, nominal.g)
        # an unsampled candidate ranks behind every sampled one: without the offset a
        # nominal design just outside a limit (violation 1e-3) beats a nominally feasible
        # one whose draws fail (violation ~1), and the search never leaves the limit
        g = np.column_stack([nom_g, SCREENED + np.maximum(nom_worst, 0.0)])
        f = np.array(nominal.f, dtype=float)
        estimate = np.full(len(X), np.nan)
        todo = np.flatnonzero(screened_in) if spec.screen else np.arange(len(X))
        if todo.size:
            r = race(self.base, self.plan, X[todo], unit, k)
            g[todo, :-1] = r.g
            g[todo, -1] = r.worst
            estimate[todo] = r.estimate
            self.draws_evaluated += int(r.evaluated.sum())
            if spec.objective in ("mean", "quantile"):
                f[todo] = r.f
        if spec.objective == "margin":
            f = g[:, -1].copy()
        return Evaluation(f, g, {**nominal.extras, YIELD: estimate})

    def _nominal(self, X: Floats) -> tuple[Evaluation, Floats, Bools]:
        """The nominal evaluation of designs ``X`` (n, n_var), their worst constraint
        (n,; with ``screen`` and model variants the least over the variants for a design
        refused at nominal) and whether they are sampled (n,). A design of the previous
        call (a DE parent evaluated again on new draws) takes its rows from there: the
        nominal evaluation reads no draw, so they are the same numbers."""
        last = self._last
        if last is None or not len(X):
            done = self._nominal_of(X)
        else:
            old_x, old = last
            both = np.vstack([old_x, X])
            _, inverse = np.unique(both, axis=0, return_inverse=True)
            inverse = np.ravel(inverse)
            where = np.full(len(both), -1)
            where[inverse[:len(old_x)]] = np.arange(len(old_x))
            found = where[inverse[len(old_x):]]
            new = np.flatnonzero(found < 0)
            pieces = [old, self._nominal_of(X[new])] if new.size else [old]
            index = found.copy()
            index[new] = len(old_x) + np.arange(len(new))
            done = (Evaluation.concat([p[0] for p in pieces]).take(index),
                    np.concatenate([p[1] for p in pieces])[index],
                    np.concatenate([p[2] for p in pieces])[index])
        self._last = (X.copy(), done)
        return done

    def _nominal_of(self, X: Floats) -> tuple[Evaluation, Floats, Bools]:
        """:meth:`_nominal` computed."""
        spec = self.plan.spec
        nominal = self.base.evaluate(X)
        nom_g = np.where(np.isnan(nominal.g), np.inf, nominal.g)
        nom_worst = _worst(nom_g, nominal.f)
        screened_in = nominal.feasible.copy()
        if spec.screen and self.plan.variants and not screened_in.all():
            # draws are judged one variant each: a design that meets every constraint in
            # some variant has a yield above 0, and is sampled; the others rank by the
            # variant they come nearest in. A nominally feasible design is sampled anyway,
            # and its columns come from its draws: only the others are judged per variant
            m, out = len(self.plan.variants), np.flatnonzero(~screened_in)
            n = len(out)
            each = apply(self.base, np.repeat(X[out], m, axis=0), (), np.empty((n * m, 0)),
                         size=spec.chunk_rows, variant=np.tile(np.arange(m), n))
            each_g = np.where(np.isnan(each.g), np.inf, each.g)
            nom_worst[out] = np.minimum(nom_worst[out],
                                        _worst(each_g, each.f).reshape(n, m).min(axis=1))
            screened_in[out] = each.feasible.reshape(n, m).any(axis=1)
        return nominal, nom_worst, screened_in

    def _keep_finalists(self, X: Floats, ev: Evaluation) -> None:
        """Keep the ``finalists`` distinct designs with the lowest objective among those
        that met the target on their generation's draws, each with its latest score. A
        finalist evaluated again (a DE parent) that fails the new draws leaves: it passed
        by luck once, and kept, such designs crowd out the ones that pass every time (the
        winner's curse). The selection judges the rest on fresh draws."""
        ok = ev.feasible
        kept = self.finalists[0]
        if len(kept) and not ok.all():
            # (finalists, failed rows, n_var): at most 8 x population x n_var booleans
            gone = (kept[:, None, :] == X[~ok][None, :, :]).all(axis=2).any(axis=1)
            self.finalists = (kept[~gone], self.finalists[1][~gone])
        if not ok.any():
            return
        # this generation's rows first: np.unique keeps a design's first row, so a design
        # evaluated again (a DE parent) keeps its score on the latest draws, not a lucky one
        Xs = np.vstack([X[ok], self.finalists[0]])
        fs = np.concatenate([ev.f[ok], self.finalists[1]])
        Xs, first = np.unique(Xs, axis=0, return_index=True)
        fs = fs[first]
        keep = np.argsort(fs, kind="stable")[:self.plan.spec.finalists]
        self.finalists = (Xs[keep], fs[keep])

    def select(self, x: Floats, seed: np.random.SeedSequence) -> tuple[Floats, Evaluation]:
        """The repeat's result: the solver's best ``x`` and the finalists evaluated on
        ``check_samples`` fresh draws (the same for all), the best of them by Deb's rules,
        a design counting as feasible when the lower bound of its yield's interval (at
        ``confidence``) reaches ``yield_target``. A design kept for passing one
        generation's draws by luck fails here."""
        spec = self.plan.spec
        unit = unit_draws(np.random.default_rng(seed), spec.check_samples,
                          len(self.plan.varies), self.plan.distribution)
        X = np.vstack([x[None, :], self.finalists[0]])
        k = confident_index(spec.yield_target, len(unit), spec.confidence)
        ev = self.evaluate_at(X, unit, k)
        i = deb_best(ev.f, ev.violation)
        self.notes = ()
        if not spec.centre_generations:
            return X[i].copy(), ev.take(i)
        return self._centred(X[i].copy(), ev.take(i), unit, k, seed)

    def _centred(self, x: Floats, ev: Evaluation, unit: Floats, k: int,
                 seed: np.random.SeedSequence) -> tuple[Floats, Evaluation]:
        """Yield centring of the selected ``x`` (:mod:`camopt.engine.centring`) on its own
        draws (spawn key ``(*seed.spawn_key, 0)``: none of the search's or the
        selection's), kept if the case accepts it at nominal and not ``x``, or if both
        are judged alike there and more of the selection's draws ``unit`` pass it than
        ``x`` (a tie keeps ``x``); both shares go to the repeat's notes."""
        from camopt.engine.centring import centre, keep

        spec, base, plan = self.plan.spec, self.base, self.plan
        rng = np.random.default_rng(np.random.SeedSequence(seed.entropy,
                                                           spawn_key=(*seed.spawn_key, 0)))
        fixed = unit_draws(rng, spec.centre_samples, len(plan.varies), plan.distribution)

        def draws(X: Floats) -> tuple[Floats, Floats, Floats]:
            s, nominal = sample(base, plan, X, fixed), base.evaluate(X)
            return s.g, s.f, np.where(np.isfinite(nominal.f), nominal.violation, np.inf)

        c = centre(base, draws, x, spec.centre_generations, spec.centre_step, rng)
        both = sample(base, plan, np.vstack([x, c.x]), unit).feasible.mean(axis=1)
        ok = base.evaluate(np.vstack([x, c.x])).feasible
        kept = keep(bool(ok[0]), bool(ok[1]), float(both[0]), float(both[1]))
        self.notes = (f"yield centring ({c.generations} generations, {len(fixed)} fixed "
                      f"draws): pass share {c.passed_start:.4f} -> {c.passed:.4f} on its "
                      f"draws, {both[0]:.4f} -> {both[1]:.4f} on the selection's "
                      f"{len(unit)}: {'kept' if kept else 'not kept'}",)
        if not kept:
            return x, ev
        return c.x, self.evaluate_at(c.x[None, :], unit, k)

    def nominal_design(self) -> Floats | None:
        return None if self.nominal_best is None else self.nominal_best[0]

    def draw_dependent(self, ev: Evaluation) -> Bools:
        """The rows that were sampled: with ``screen`` an unsampled candidate's columns are
        its nominal design's (its yield estimate is NaN), the same on any draws."""
        if not self.plan.spec.screen:
            return np.ones(len(ev.f), dtype=bool)
        return np.isfinite(np.asarray(ev.extras[YIELD], dtype=float))

    def final_check(self, best: Floats, seen: Sequence[Floats], seed: int,
                    progress: RowsDone | None = None) -> RobustCheck:
        """The best design and the best nominally feasible design ``seen`` (lowest nominal
        objective over the repeats) checked on the same fresh draws (:func:`check`)."""
        designs = [best]
        if seen:
            f = self.base.evaluate(np.array(seen)).f
            designs.append(seen[int(np.argmin(f))])
        checked = check(self, designs, seed, progress)
        result: RobustCheck = {"robust": checked[0]}
        if len(checked) > 1:
            result["nominal"] = {**checked[1], "x": self.base.to_display(designs[1])}
        return result

    def _remember(self, X: Floats, nominal: Evaluation) -> None:
        ok = np.flatnonzero(nominal.feasible)
        if ok.size:
            i = ok[np.argmin(nominal.f[ok])]
            if self.nominal_best is None or nominal.f[i] < self.nominal_best[1]:
                self.nominal_best = (X[i].copy(), float(nominal.f[i]))

    # the case's single-design outputs describe the nominal design
    def metrics(self, x: Floats) -> Mapping[str, object]:
        return self.base.metrics(x)

    def analysis(self, x: Floats) -> dict[str, Floats]:
        return self.base.analysis(x)

    def initial_x(self) -> Floats | None:
        return self.base.initial_x()

    def objective_floor(self) -> ObjectiveFloor | None:
        """The case's floor for its objective and any statistic of it over the draws; the
        margin has none (a more negative margin is always possible in principle)."""
        return None if self.plan.spec.objective == "margin" else self.base.objective_floor()


# The case's capabilities, forwarded to it: one declared class per capability a case
# may offer (a solver checks a Problem *class*), none built at run time. Per-design case
# fields (VariesCase) stay the case's: they are what varies.
class RobustRepairable(RobustProblem, Repairable):
    """A robust problem whose swarm corrections are its case's."""

    def repair(self, X: Floats, rng: np.random.Generator,
               probability: Mapping[str, float]) -> Floats:
        return cast(Repairable, self.base).repair(X, rng, probability)

    def repair_schedule(self) -> Mapping[str, tuple[float, float]]:
        return cast(Repairable, self.base).repair_schedule()


class RobustFamily(RobustProblem, HasFamily):
    """A robust problem searching its case's one-degree-of-freedom family."""

    def family(self) -> Floats:
        return cast(HasFamily, self.base).family()


class RobustResiduals(RobustProblem, HasResiduals):
    """A robust problem with its case's residual equations."""

    def residuals(self, X: Floats) -> Floats:
        return cast(HasResiduals, self.base).residuals(X)


FORWARDED: dict[type, type[RobustProblem]] = {
    Repairable: RobustRepairable, HasFamily: RobustFamily, HasResiduals: RobustResiduals}
"""The robust class that offers each capability a case may declare."""


def wrap(base: Problem, robust_plan: Plan, source: str = "<case>") -> RobustProblem:
    """A RobustProblem offering the capability its case declares (repair, family or
    residuals: forwarded to the case), so every solver that runs the case runs it
    robustly. A case declaring more than one of them is refused (no class offers the
    combination; add one to :data:`FORWARDED` when a case needs it)."""
    caps = [c for c in FORWARDED if isinstance(base, c)]
    if len(caps) > 1:
        names = ", ".join(capability_name(c) for c in caps)
        raise ConfigError(source, "robust", f"a case offering {names} together cannot "
                          "be run robustly yet")
    cls = FORWARDED[caps[0]] if caps else RobustProblem
    return cls(base, robust_plan)


def repeat_seed(child: np.random.SeedSequence, stage: int = 0) -> np.random.SeedSequence:
    """The draws of the repeat whose solver is seeded by ``child`` (the run's
    ``SeedSequence(seed).spawn(repeats)[i]``): spawn key ``(i, ROBUST_KEY, stage)``, stage
    0 the generations', 1 the selection's (:meth:`RobustProblem.select`)."""
    return np.random.SeedSequence(child.entropy,
                                  spawn_key=(*child.spawn_key, ROBUST_KEY, stage))


def check(problem: RobustProblem, designs: Sequence[Floats], seed: int,
          progress: RowsDone | None = None) -> list[DesignCheck]:
    """The final check: designs (SI) evaluated at ``check_samples`` fresh draws, the same
    draws for every design. Per design: nominal objective, mean and quantile objective,
    yield with its Clopper-Pearson interval, and per constraint its nominal value and its value at
    the yield target's order statistic (normalised, <= 0 met: the margin). ``progress``
    is told the rows (designs x draws) done after each chunk."""
    spec = problem.plan.spec
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(ROBUST_KEY, CHECK_KEY)))
    unit = unit_draws(rng, spec.check_samples, len(problem.plan.varies),
                      problem.plan.distribution)
    X = np.array(designs, dtype=float)
    nominal = problem.base.evaluate(X)
    s = sample(problem.base, problem.plan, X, unit, progress)
    k = order_index(spec.yield_target, spec.check_samples)
    at_target = np.partition(s.g, k, axis=1)[:, k, :]
    mean = statistic(s.f, "mean", spec.quantile)
    quant = statistic(s.f, "quantile", spec.quantile)
    out: list[DesignCheck] = []
    for i in range(len(X)):
        passed = int(s.feasible[i].sum())
        rate = stats.success_rate(passed, spec.check_samples, spec.confidence)
        doc: DesignCheck = {
            "samples": spec.check_samples, "yield": rate["rate"], "yield_low": rate["ci_low"],
            "yield_high": rate["ci_high"], "confidence": spec.confidence,
            # the case's objective, also when the search minimised the margin
            "case_objective": problem.base.objective_name,
            "objective_nominal": float(nominal.f[i]), "objective_mean": float(mean[i]),
            "nominal_feasible": bool(nominal.feasible[i]),
            "margins": {c: {"nominal": float(nominal.g[i, j]), "at_target": float(at_target[i, j])}
                        for j, c in enumerate(problem.base.constraint_names)},
        }
        if problem.plan.variants:
            doc["per_form"] = stats.per_variant(s.feasible[i], s.variant, problem.plan.variants,
                                                spec.confidence)
        out.append(with_quantile(doc, spec.quantile, float(quant[i])))
    return out

