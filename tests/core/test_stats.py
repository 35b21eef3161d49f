"""Run statistics and comparisons against hand counts and exact distributions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, binomtest

from camopt.core.stats import (
    compare_objectives,
    compare_success,
    equivalence_threshold,
    min_p_value,
    min_repeats,
    share_interval,
    succeeded,
    verdict,
)


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


def test_too_few_runs_cannot_decide():
    """The exact two-sided Mann-Whitney p of complete separation is 2 / C(n_a + n_b, n_a):
    0.1 at 3 against 3, 2/70 = 0.0286 at 4 against 4; 100 % against 0 % success at 3
    against 3 (issue #34) is therefore undecidable, whatever scipy's asymptotic p says."""
    assert min_p_value(3, 3) == pytest.approx(0.1)
    assert min_p_value(4, 4) == pytest.approx(2 / 70)
    assert min_repeats() == 4
    t = compare_objectives([1.0, 1.0, 1.0], [float("inf")] * 3)
    assert verdict("A", "B", t).startswith("too few repeats to decide: 3 against 3")
    # Fisher's exact test on 3/3 against 0/3: p = 2 / C(6, 3) = 0.1 (hypergeometric)
    assert compare_success(3, 3, 0, 3) == pytest.approx(0.1)


def test_a_significant_but_tiny_difference_is_equivalent_in_practice():
    """Medians 3e-9 ms apart at p < 0.05 (issue #34): below the default threshold of 0.1 %
    of the larger median, so equivalent in practice; a real difference names its size."""
    a = [18.0 + 1e-9 * i for i in range(8)]
    b = [18.0 + 3e-9 + 1e-9 * i + 1e-8 for i in range(8)]
    t = compare_objectives(a, b)
    t["threshold"] = equivalence_threshold(t["median_a"], t["median_b"])
    assert t["p_value"] < 0.05 and t["threshold"] == pytest.approx(0.018, rel=1e-6)
    assert verdict("A", "B", t, unit="ms").endswith("equivalent in practice")
    far = compare_objectives(a, [19.0 + 0.1 * i for i in range(8)])
    far["threshold"] = equivalence_threshold(far["median_a"], far["median_b"])
    assert verdict("A", "B", far, unit="ms").startswith("A is better than B at p = ")
    assert "by 1.35 ms (medians)" in verdict("A", "B", far, unit="ms")
