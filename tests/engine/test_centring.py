"""Yield centring (camopt/engine/centring.py, RobustProblem.select): the smoothed failure
against the sigmoids it is made of, a design moved off its limit to the known centre of a
tolerance window, the case's nominal verdict kept, the keep decided on the selection's
draws (not the centring's own, which are others), reproducibility, and a centring that
does not help is not kept (review of 9c22e93 by a helper session: the tests it found
missing)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camopt.config.models import RobustSection
from camopt.core.problem import Evaluation, Problem, Variable
from camopt.core.variation import Vary
from camopt.engine import centring, robust


class _Window(Problem):
    """Two parts x, y drawn +-10 % about the design; each must stay within [0.6, 1.0]:
    the yield is 1 for designs in [0.6 / 0.9, 1.0 / 1.1] = [0.667, 0.909] in both, and
    falls as a design nears a limit (x = 0.98 passes a draw with probability
    (1 / 0.98 - 0.9) / 0.2 = 0.602)."""

    variables = (Variable("x", 0.1, 2.0), Variable("y", 0.1, 2.0))
    constraint_names = ("x_high", "x_low", "y_high", "y_low")

    def evaluate(self, X):
        X = np.atleast_2d(X)
        g = np.column_stack([X[:, 0] - 1.0, 0.6 - X[:, 0], X[:, 1] - 1.0, 0.6 - X[:, 1]])
        return Evaluation(X.sum(axis=1), g)


def _robust(centre_generations=40, **spec):
    base = _Window()
    section = RobustSection(samples=16, check_samples=2000, objective="margin",
                            centre_generations=centre_generations, **spec)
    varies = (Vary("x", 10.0, True), Vary("y", 10.0, True))
    plan = robust.Plan(section, varies, ((0.0, True, math.inf),) * 2, {})
    problem = robust.RobustProblem(base, plan)
    problem.reseed(np.random.SeedSequence(1))
    return problem


def test_smoothed_failure_follows_the_pass_count():
    """Every draw far inside: F ~ 0; every draw far outside: F ~ 1; a NaN constraint or
    a non-finite objective fails its draw; -inf (no limit near) passes."""
    tau = np.array([0.1, 0.1])
    inside = np.full((1, 4, 2), -10.0)
    outside = np.full((1, 4, 2), 10.0)
    f = np.zeros((1, 4))
    assert centring.smoothed_failure(inside, f, tau)[0] == pytest.approx(0.0, abs=1e-9)
    assert centring.smoothed_failure(outside, f, tau)[0] == pytest.approx(1.0, abs=1e-9)
    g = inside.copy()
    g[0, 0, 0] = np.nan
    g[0, 1, 1] = -np.inf
    f2 = f.copy()
    f2[0, 2] = np.inf
    assert centring.smoothed_failure(g, f2, tau)[0] == pytest.approx(0.5, abs=1e-9)
    np.testing.assert_array_equal(centring.passed(g, f2), [0.5])


def test_spread_floors_a_constraint_that_does_not_move():
    g = np.column_stack([np.linspace(-1, 1, 9), np.zeros(9), np.full(9, np.inf)])
    tau = centring.spread(g)
    assert tau[0] == pytest.approx(np.std(np.linspace(-1, 1, 9)))
    np.testing.assert_array_equal(tau[1:], centring.TAU_FLOOR)


def test_a_design_on_its_limit_is_moved_inside_the_window():
    """From (0.98, 0.8) (yield 0.60) the centring ends where the selection's 2,000 fresh
    draws all pass, x inside [0.667, 0.909] (the only place they can)."""
    problem = _robust(centre_generations=60, centre_step=0.01)
    x0 = np.array([0.98, 0.8])
    x, ev = problem.select(x0, np.random.SeedSequence(5))
    assert 0.6 / 0.9 <= x[0] <= 1.0 / 1.1
    assert ev.extras["yield"][0] == 1.0
    (note,) = problem.notes
    assert "kept" in note and "not kept" not in note


def test_centring_is_reproducible():
    a = _robust().select(np.array([0.98, 0.8]), np.random.SeedSequence(5))[0]
    b = _robust().select(np.array([0.98, 0.8]), np.random.SeedSequence(5))[0]
    np.testing.assert_array_equal(a, b)


def test_a_centring_that_does_not_help_is_not_kept():
    """A design at the window's centre already passes every draw: the selection keeps it
    (a tie keeps the selected design), and says so."""
    problem = _robust(centre_generations=5)
    x0 = np.array([0.78, 0.78])
    x, _ = problem.select(x0, np.random.SeedSequence(5))
    np.testing.assert_array_equal(x, x0)
    assert problem.notes[0].endswith("not kept")


def test_no_centring_by_default():
    problem = _robust(centre_generations=0)
    problem.select(np.array([0.98, 0.8]), np.random.SeedSequence(5))
    assert problem.notes == ()


class _Guarded(Problem):
    """One part x drawn +-20 % about the design, judged in model form "a" (x <= 1.0) or
    "b" (x <= 0.8) per draw; the nominal design, judged in every form at once (-1), must
    also keep x >= 0.75. The draws alone would be best at x <= 0.667 (all pass); among
    nominally feasible designs, at x = 0.75 (yield 1/2 + 1/2 x 2/3 = 0.83)."""

    variables = (Variable("x", 0.1, 2.0),)
    constraint_names = ("c", "nominal_floor")

    def evaluate(self, X):
        return self.describe_variants(X, {}, np.full(len(X), -1))

    def variants(self):
        return ("a", "b")

    def describe_variants(self, X, fields, variant, detail=True):
        variant = np.asarray(variant)
        limit = np.where(variant == 0, 1.0, 0.8)
        floor = np.where(variant == -1, 0.75 - X[:, 0], -1.0)
        return Evaluation(X[:, 0].copy(), np.column_stack([X[:, 0] / limit - 1, floor]))


def _guarded():
    from camopt.core.capabilities import HasVariants

    class Guarded(_Guarded, HasVariants):
        pass

    base = Guarded()
    section = RobustSection(samples=16, check_samples=2000, objective="margin",
                            centre_generations=40, centre_step=0.02)
    plan = robust.Plan(section, (Vary("x", 20.0, True),), ((0.0, True, math.inf),), {},
                       robust.variants_of(base))
    return robust.RobustProblem(base, plan)


def test_the_centred_design_meets_its_cases_nominal_verdict():
    """A design the case refuses at nominal is no result however many draws it passes:
    the centring ends at the nominal floor (0.75), not below it."""
    x, _ = _guarded().select(np.array([0.79]), np.random.SeedSequence(2))
    assert 0.75 <= x[0] < 0.76
    assert _Guarded().evaluate(x[None, :]).feasible[0]


def test_a_start_the_case_refuses_gives_way_to_a_feasible_design():
    """From x = 0.74, below the nominal floor (found by the review): the walk crosses
    0.75..0.8, nominally feasible, and the result is one of those."""
    x0 = np.array([0.74])
    assert not _Guarded().evaluate(x0[None, :]).feasible[0]
    problem = _guarded()
    x, _ = problem.select(x0, np.random.SeedSequence(2))
    assert _Guarded().evaluate(x[None, :]).feasible[0], problem.notes


def test_smoothed_failure_is_the_product_of_sigmoids_scaled_by_each_spread():
    """One draw, two constraints of different spreads: F = 1 - sigmoid(-3 g1 / tau1)
    sigmoid(-3 g2 / tau2), each constraint on its own scale."""
    g = np.array([[[0.01, -0.5]]])
    tau = np.array([0.02, 1.0])
    sig = lambda z: 1 / (1 + np.exp(-z))  # noqa: E731
    want = 1 - sig(-3 * 0.01 / 0.02) * sig(3 * 0.5 / 1.0)
    assert centring.smoothed_failure(g, np.zeros((1, 1)), tau)[0] == pytest.approx(want,
                                                                                 rel=1e-12)


def test_the_centring_draws_are_not_the_selections(monkeypatch):
    """The centring's fixed draws share no row with the selection's 2,000 (its own
    spawn key), so the keep is judged on draws the centring never saw."""
    seen = []
    real = centring.centre

    def spy(problem, draws, x0, generations, step, rng):
        original = draws

        def recording(X):
            seen.append(X)
            return original(X)
        return real(problem, recording, x0, generations, step, rng)

    monkeypatch.setattr(centring, "centre", spy)
    captured = {}
    real_sample = robust.sample

    def sample(problem, plan, X, unit, *a, **k):
        captured.setdefault(len(unit), unit.copy())
        return real_sample(problem, plan, X, unit, *a, **k)

    monkeypatch.setattr(robust, "sample", sample)
    _robust(centre_generations=3).select(np.array([0.98, 0.8]), np.random.SeedSequence(5))
    fixed, selection = captured[256], captured[2000]
    assert not (fixed[:, None, :] == selection[None, :, :]).all(axis=2).any()
    assert seen


def test_the_keep_is_decided_on_the_selections_draws(monkeypatch):
    """A centring whose design passes more of its own draws is still not kept when the
    selection's draws pass it less: here the stage's result is forced to a design outside
    the window (every selection draw fails it)."""
    outside = np.array([1.5, 1.5])
    monkeypatch.setattr(centring, "centre", lambda *a, **k: centring.Centred(
        outside, 1.0, 0.5, 1))
    problem = _robust(centre_generations=1)
    x, _ = problem.select(np.array([0.98, 0.8]), np.random.SeedSequence(5))
    np.testing.assert_array_equal(x, [0.98, 0.8])
    assert problem.notes[0].endswith("not kept")


def test_centring_asks_for_the_margin_objective():
    """The centring maximises the yield, trading the objective for it: with any other
    objective it is bad input."""
    with pytest.raises(ValueError, match="objective"):
        RobustSection(centre_generations=10, objective="mean")


def test_the_walk_ranks_by_failure_plus_the_nominal_violation():
    """A design the case refuses ranks behind a feasible one when its violation exceeds
    its lead in F, ahead of it when it does not; a non-finite violation is last, ties
    keep the sampling order (ranked by F alone, the walk would enter the refused
    designs where F is least: review of stop 42's centring, the sixth mutation)."""
    F = np.array([0.30, 0.10, 0.05, 0.30, 0.00])
    violation = np.array([0.0, 0.05, 0.40, 0.0, np.inf])
    assert centring.ranking(F, violation).tolist() == [1, 0, 3, 2, 4]


def test_the_walk_ranking_is_stable_on_many_ties_and_ties_every_non_finite_violation():
    """Ties keep the sampling order among many (a default, unstable argsort reorders
    them) and a NaN violation ties with +inf (both last, in sampling order)."""
    F = np.tile([0.2, 0.1, 0.3], 20)
    assert centring.ranking(F, np.zeros(60)).tolist() == np.argsort(F, kind="stable").tolist()
    order = centring.ranking(np.array([0.0, 0.0, 1.0]), np.array([np.nan, np.inf, 0.0]))
    assert order.tolist() == [2, 0, 1]


@pytest.mark.parametrize("start, centred, share_start, share_centred, kept", [
    (True, True, 0.90, 0.95, True),     # alike at nominal: more draws pass
    (True, True, 0.95, 0.90, False),    # alike: fewer pass
    (True, True, 0.95, 0.95, False),    # a tie keeps the start
    (False, False, 0.10, 0.20, True),   # both refused: the pass share still decides
    (False, False, 0.20, 0.20, False),
    (False, True, 0.99, 0.01, True),    # the case accepts only the centred design
    (True, False, 0.01, 0.99, False),   # the case refuses the centred design
])
def test_the_centring_keep_rule(start, centred, share_start, share_centred, kept):
    """centring.keep's truth table, exact: the case's nominal verdict first, then a
    strictly larger share of the selection's draws passing."""
    assert centring.keep(start, centred, share_start, share_centred) is kept
