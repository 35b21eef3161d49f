"""Statistics for comparing runs and sweep points (scipy.stats)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

ALPHA = 0.05


def success_rate(successes: int, runs: int, confidence: float = 0.95) -> dict[str, float]:
    """Success rate with its Wilson score interval."""
    if runs == 0:
        return {"rate": float("nan"), "ci_low": float("nan"), "ci_high": float("nan")}
    ci = stats.binomtest(successes, runs).proportion_ci(confidence, method="wilson")
    return {"rate": successes / runs, "ci_low": float(ci.low), "ci_high": float(ci.high)}


def compare_objectives(a: ArrayLike, b: ArrayLike) -> dict[str, float]:
    """Two-sided Mann-Whitney U on final objectives (lower is better) and effect sizes.

    ``p_a_better`` is P(A < B) + P(A = B)/2 (the common-language effect size); the
    rank-biserial correlation 2 p_a_better - 1 is positive when A tends to be lower.
    Infeasible or failed runs should be passed as +inf (they rank last).
    """
    a = np.where(np.isnan(a), np.inf, np.asarray(a, dtype=float))
    b = np.where(np.isnan(b), np.inf, np.asarray(b, dtype=float))
    if a.size < 2 or b.size < 2 or np.all(np.concatenate([a, b]) == a[0]):
        return {"p_value": 1.0, "p_a_better": 0.5, "rank_biserial": 0.0,
                "median_a": float(np.median(a)), "median_b": float(np.median(b))}
    res = stats.mannwhitneyu(a, b, alternative="two-sided")
    p_a_better = 1.0 - float(res.statistic) / (a.size * b.size)
    return {"p_value": float(res.pvalue), "p_a_better": p_a_better,
            "rank_biserial": 2 * p_a_better - 1,
            "median_a": float(np.median(a)), "median_b": float(np.median(b))}


def verdict(name_a: str, name_b: str, test: dict[str, Any], alpha: float = ALPHA) -> str:
    """A plain-language line for a comparison."""
    p = test["p_value"]
    if p >= alpha:
        return f"no significant difference between {name_a} and {name_b} (p = {p:.3g})"
    better, worse = (name_a, name_b) if test["p_a_better"] > 0.5 else (name_b, name_a)
    return f"{better} is better than {worse} at p = {p:.3g}"
