"""DE-gr's operators (Kang 2023 Table 5: DE/best/1/bin) against their definitions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from camopt.solvers.de_gr import best1, binomial_crossover


def test_best1_is_best_plus_f_times_a_difference_of_two_other_members():
    """Every mutant equals best + F (x_r1 - x_r2) for some r1 != r2, both != i (searched
    over every pair), and the pairs differ between rows."""
    rng = np.random.default_rng(3)
    pop = rng.normal(size=(7, 3))
    best, factor = pop[4], 0.382
    mutant = best1(pop, best, factor, np.random.default_rng(11))
    pairs = []
    for i, row in enumerate(mutant):
        hits = [(a, b) for a, b in itertools.permutations(range(len(pop)), 2)
                if np.allclose(row, best + factor * (pop[a] - pop[b]), rtol=0, atol=1e-14)]
        assert len(hits) == 1, i
        a, b = hits[0]
        assert i not in (a, b)
        pairs.append(hits[0])
    assert len(set(pairs)) > 3


def test_crossover_takes_each_gene_with_probability_cr_and_one_gene_always():
    """P(gene from the mutant) = CR + (1 - CR)/d (the forced gene); CR = 0 gives exactly one
    mutant gene per row; CR = 1 gives the mutant."""
    n, d = 4000, 5
    parent, mutant = np.zeros((n, d)), np.ones((n, d))
    rng = np.random.default_rng(2)
    for cr in (0.2, 0.618):
        trial = binomial_crossover(parent, mutant, cr, rng)
        assert set(np.unique(trial)) <= {0.0, 1.0}
        assert trial.sum(axis=1).min() >= 1
        assert trial.mean() == pytest.approx(cr + (1 - cr) / d, abs=0.015)
    assert np.all(binomial_crossover(parent, mutant, 0.0, rng).sum(axis=1) == 1)
    assert np.all(binomial_crossover(parent, mutant, 1.0, rng) == 1)


def test_parents_are_evaluated_again_on_each_generations_draws():
    """On a problem that redraws its parts every generation (robust), each ask after the
    first holds the trials and then the parents, and after tell the parents that stay
    carry their evaluation on the current draws, not a stale one from an earlier
    generation (the comparison with the trials is on the same parts)."""
    from camopt.core.capabilities import Stochastic
    from camopt.engine.driver import prepare
    from camopt.solvers.de_gr import DEGR, DEGROptions
    from tests.conftest import CONFIGS
    from tests.helpers import load

    problem, _ = prepare(load(CONFIGS / "fast_switch_de.toml", "robust.samples=8",
                              "robust.screen=false"))
    assert isinstance(problem, Stochastic)
    solver = DEGR(problem, DEGROptions(population=6, generations=3), np.random.default_rng(1))
    assert solver.redraws
    problem.reseed(np.random.SeedSequence(2))
    problem.new_generation()
    first = solver.ask()
    solver.tell(first, problem.evaluate(first))
    problem.new_generation()
    both = solver.ask()
    assert len(both) == 12
    np.testing.assert_array_equal(both[6:], first)
    ev = problem.evaluate(both)
    solver.tell(both, ev)
    kept = np.all(solver.pop == first, axis=1)
    assert kept.any()
    np.testing.assert_array_equal(solver.ev.g[kept], ev.g[6:][kept])
    np.testing.assert_array_equal(solver.ev.f[kept], ev.f[6:][kept])


def test_screened_parents_are_not_evaluated_again():
    """With screen, a parent whose nominal design breaks a constraint was not sampled: its
    evaluation is its nominal's on any draws, so the ask after it holds only the sampled
    parents, and after tell every parent's row equals a fresh evaluation on the current
    draws (the skipped ones too)."""
    from camopt.core.capabilities import Stochastic
    from camopt.engine.driver import prepare
    from camopt.solvers.de_gr import DEGR, DEGROptions
    from tests.conftest import CONFIGS
    from tests.helpers import load

    problem, _ = prepare(load(CONFIGS / "fast_switch_de.toml", "robust.samples=8",
                              "robust.screen=true"))
    assert isinstance(problem, Stochastic)
    solver = DEGR(problem, DEGROptions(population=40, generations=3), np.random.default_rng(4))
    problem.reseed(np.random.SeedSequence(5))
    problem.new_generation()
    first = solver.ask()
    # six near fast_switch_robust.toml's optimum, which meet every nominal constraint
    x = problem.from_display({"coils": 17, "sf_mm": 98.78, "sud_mm": 170.41, "s0_mm": 46.48,
                              "r3_mm": 256.32, "r2_mm": 54.98})
    first[:6] = x * (1 + 0.003 * np.random.default_rng(3).standard_normal((6, len(x))))
    first[:6, 0] = 17
    ev0 = problem.evaluate(first)
    solver.tell(first, ev0)
    sampled = problem.draw_dependent(ev0)
    assert sampled.any() and not sampled.all()  # both kinds among the parents
    problem.new_generation()
    both = solver.ask()
    np.testing.assert_array_equal(both[40:], first[sampled])
    solver.tell(both, problem.evaluate(both))
    fresh = problem.evaluate(solver.pop)  # another batch: the same rows to round-off
    np.testing.assert_allclose(solver.ev.g, fresh.g, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(solver.ev.f, fresh.f, rtol=1e-12, atol=1e-12)
