"""Run statistics and comparisons against hand counts and exact distributions."""

from __future__ import annotations

import pytest

from camopt.core.stats import compare_objectives, succeeded, verdict


def test_mann_whitney_direction_and_exact_p():
    """A entirely below B (3 against 3, lower is better): P(A < B) = 1 counted by hand,
    rank-biserial +1, and the exact two-sided p = 2 / C(6, 3) = 0.1."""
    t = compare_objectives([1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    assert t["p_a_better"] == 1.0 and t["rank_biserial"] == 1.0
    assert t["p_value"] == pytest.approx(0.1, rel=1e-12)
    back = compare_objectives([4.0, 5.0, 6.0], [1.0, 2.0, 3.0])
    assert back["p_a_better"] == 0.0 and back["rank_biserial"] == -1.0


def test_mann_whitney_counts_ties_as_halves():
    """A = [1, 3, 5], B = [3, 4]: pairs with A < B: (1,3) (1,4) (3,4) = 3, one tie (3,3)
    counts 1/2: P = 3.5 / 6."""
    t = compare_objectives([1.0, 3.0, 5.0], [3.0, 4.0])
    assert t["p_a_better"] == pytest.approx(3.5 / 6)


def test_infeasible_runs_rank_last_and_the_verdict_names_the_better():
    a, b = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5], [4.0, 4.5, float("nan"), 5.0, 6.0, 7.0]
    t = compare_objectives(a, b)
    assert t["p_a_better"] == 1.0 and t["p_value"] < 0.01
    assert verdict("de", "pso", t).startswith("de is better than pso")
    assert verdict("pso", "de", compare_objectives(b, a)).startswith("de is better than pso")


def test_success_needs_feasible_and_target():
    assert succeeded([1.0, 1.0, 3.0, float("nan")], [True, False, True, True],
                     2.0).tolist() == [True, False, False, False]
