"""Statistics for comparing runs and sweep points (scipy.stats).

scipy is imported where used (``camopt show`` prints an interval without scipy.stats, ~1.2 s
to import)."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from math import comb
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from camopt.core.documents import FormYield, RunStatisticsDoc
from camopt.mechanics import Bools, Floats, Ints

if TYPE_CHECKING:
    from camopt.config.sweep_spec import SweepSpec
    from camopt.core.record import Repeat

ALPHA = 0.05
EQUIVALENCE_RTOL = 1e-3
"""Default practical-equivalence threshold of ``compare``: medians closer than 0.1 % of the
larger one's magnitude are the same objective in practice (a case may set an absolute one,
``CaseSpec.equivalence``; ``compare --equivalence`` overrides both)."""


def ranked(objectives: ArrayLike, feasible: ArrayLike) -> Floats:
    """Final objectives as they rank across runs: an infeasible (or NaN) run counts +inf."""
    f = np.asarray(objectives, dtype=float)
    return np.where(np.asarray(feasible, dtype=bool) & ~np.isnan(f), f, np.inf)


def succeeded(objectives: ArrayLike, feasible: ArrayLike, target: float | None) -> Bools:
    """camopt's one definition of a successful run: feasible, and at or below ``target``
    when the case file sets ``run.target``."""
    f = ranked(objectives, feasible)
    return np.isfinite(f) & (f <= target if target is not None else True)


@dataclass(frozen=True)
class YieldInterval:
    """A yield (the share of draws meeting every requirement) with its Clopper-Pearson
    interval [``low``, ``high``] over ``samples`` draws (None where a document lacks
    them). A verdict is graded on ``low`` (:attr:`camopt.reporting.views.Verdict.grade`):
    on the point estimate alone a design whose true yield sits at the target would pass
    half the time by sampling luck."""

    value: float
    low: float | None = None
    high: float | None = None
    samples: int | None = None

    @classmethod
    def of(cls, doc: Mapping[str, object]) -> YieldInterval | None:
        """From a yield document (``value`` or ``yield``, ``low``/``yield_low``,
        ``high``/``yield_high``, ``samples``); None without a value."""
        value = doc.get("value", doc.get("yield"))
        if value is None:
            return None

        def num(*keys: str) -> float | None:
            v = next((doc[k] for k in keys if doc.get(k) is not None), None)
            return None if v is None else float(v)  # type: ignore[arg-type]
        samples = doc.get("samples")
        return cls(float(value), num("low", "yield_low"),  # type: ignore[arg-type]
                   num("high", "yield_high"),
                   None if samples is None else int(samples))  # type: ignore[call-overload]

    def as_dict(self) -> dict[str, float | int | None]:
        return asdict(self)


@dataclass(frozen=True)
class RunStatistics:
    """Statistics of final objectives over runs (repeats of a run, seeds of a sweep
    point); infeasible runs count +inf in best/median/worst."""

    runs: int
    best: float
    median: float
    worst: float
    feasible_fraction: float
    successes: int
    success_rate: float

    def as_dict(self) -> RunStatisticsDoc:
        """The JSON document, in the fields' order."""
        return {"runs": self.runs, "best": self.best, "median": self.median,
                "worst": self.worst, "feasible_fraction": self.feasible_fraction,
                "successes": self.successes, "success_rate": self.success_rate}


def run_statistics(objectives: Sequence[float], feasible: Sequence[bool],
                   target: float | None) -> RunStatistics:
    """:class:`RunStatistics` of a set of runs (NaN statistics when there are none)."""
    n = len(objectives)
    if n == 0:
        nan = float("nan")
        return RunStatistics(0, nan, nan, nan, nan, 0, nan)
    f = ranked(objectives, feasible)
    ok = int(np.sum(succeeded(objectives, feasible, target)))
    return RunStatistics(n, float(np.min(f)), float(np.median(f)), float(np.max(f)),
                         float(np.mean(np.asarray(feasible, dtype=bool))), ok, ok / n)


def share_interval(successes: ArrayLike, trials: int, confidence: float = 0.95
                   ) -> tuple[Floats, Floats]:
    """Two-sided Clopper-Pearson ("exact") interval of a share (a yield, a success rate)
    from ``successes`` of ``trials``, vectorised over ``successes``: the beta quantiles
    ``B((1 - c)/2; k, n - k + 1)`` and ``B((1 + c)/2; k + 1, n - k)``.

    Why not Wilson's (camopt's interval before): its coverage dips below the
    stated level for yields near 1 at a few hundred draws (0.933 at n = 200, p = 0.98;
    0.920 at p = 0.995; computed exactly in tests/core/test_stats.py), which is where
    quick yield estimates and robust designs live; Clopper-Pearson covers at least the
    stated level for every n and p, at the price of a slightly wider interval."""
    # the beta quantile as the inverse regularised incomplete beta function: what
    # scipy.stats.beta.ppf computes (equal to the bit on k = 0..n for n up to 10^5), from
    # scipy.special (~0.35 s to import) rather than scipy.stats (~1.2 s:
    # `camopt show` prints a yield's interval)
    from scipy.special import betaincinv

    k = np.asarray(successes, dtype=float)
    alpha = 1.0 - confidence
    with np.errstate(invalid="ignore"):
        low = np.where(k > 0, betaincinv(k, trials - k + 1, alpha / 2), 0.0)
        high = np.where(k < trials, betaincinv(k + 1, trials - k, 1 - alpha / 2), 1.0)
    return low, high


def success_rate(successes: int, runs: int, confidence: float = 0.95) -> dict[str, float]:
    """Success rate (or yield) with its Clopper-Pearson interval (:func:`share_interval`)."""
    if runs == 0:
        return {"rate": float("nan"), "ci_low": float("nan"), "ci_high": float("nan")}
    low, high = share_interval(successes, runs, confidence)
    return {"rate": successes / runs, "ci_low": float(low), "ci_high": float(high)}


@dataclass(frozen=True)
class ObjectivesTest:
    """Two sets of final objectives compared (lower is better): the two-sided Mann-Whitney
    ``p_value``; ``p_a_better`` = P(A < B) + P(A = B)/2 (the common-language effect size)
    and the rank-biserial correlation 2 p_a_better - 1 (positive when A tends to be
    lower); the medians, the counts and ``effect`` = median B - median A in the
    objective's unit (None unless both are finite); ``threshold``, the practical-
    equivalence threshold in that unit, where the caller set one
    (:func:`equivalence_threshold`)."""

    p_value: float
    p_a_better: float
    rank_biserial: float
    median_a: float
    median_b: float
    n_a: int
    n_b: int
    effect: float | None
    threshold: float | None = None

    def as_dict(self) -> dict[str, float | int | None]:
        """The JSON document, in the fields' order."""
        return asdict(self)


def compare_objectives(a: ArrayLike, b: ArrayLike) -> ObjectivesTest:
    """Two-sided Mann-Whitney U on final objectives (lower is better) and effect sizes
    (:class:`ObjectivesTest`). Infeasible or failed runs should be passed as +inf (they
    rank last); all values equal, or fewer than 2 a side: p = 1, no side better."""
    a = np.where(np.isnan(a), np.inf, np.asarray(a, dtype=float))
    b = np.where(np.isnan(b), np.inf, np.asarray(b, dtype=float))
    ma, mb = float(np.median(a)), float(np.median(b))
    with np.errstate(invalid="ignore"):
        effect = mb - ma if np.isfinite(ma) and np.isfinite(mb) else None
    if a.size < 2 or b.size < 2 or np.all(np.concatenate([a, b]) == a[0]):
        return ObjectivesTest(1.0, 0.5, 0.0, ma, mb, int(a.size), int(b.size), effect)
    from scipy import stats

    res = stats.mannwhitneyu(a, b, alternative="two-sided")
    p_a_better = 1.0 - float(res.statistic) / (a.size * b.size)
    return ObjectivesTest(float(res.pvalue), p_a_better, 2 * p_a_better - 1, ma, mb,
                          int(a.size), int(b.size), effect)


def min_p_value(n_a: int, n_b: int) -> float:
    """The smallest two-sided p-value an exact Mann-Whitney test of ``n_a`` against ``n_b``
    runs can give (complete separation): 2 / C(n_a + n_b, n_a), at most 1. Below
    :data:`ALPHA` only from 4 against 4 (2/70); 3 against 3 gives 0.1 at best."""
    if n_a < 1 or n_b < 1:
        return 1.0
    return min(1.0, 2.0 / comb(n_a + n_b, n_a))


def min_repeats(alpha: float = ALPHA) -> int:
    """The fewest runs each side for which :func:`min_p_value` can fall below ``alpha``."""
    n = 1
    while min_p_value(n, n) >= alpha:
        n += 1
    return n


def compare_success(k_a: int, n_a: int, k_b: int, n_b: int) -> float:
    """Two-sided p-value of Fisher's exact test on two success counts (``k`` of ``n``):
    the success rates' own test, exact at any number of repeats (scipy.stats)."""
    from scipy import stats

    if n_a == 0 or n_b == 0:
        return 1.0
    return float(stats.fisher_exact([[k_a, n_a - k_a], [k_b, n_b - k_b]]).pvalue)


def equivalence_threshold(median_a: float, median_b: float,
                          absolute: float | None = None) -> float | None:
    """The practical-equivalence threshold in the objective's unit: ``absolute`` when
    given, else :data:`EQUIVALENCE_RTOL` of the larger finite median's magnitude (None
    when neither median is finite)."""
    if absolute is not None:
        return float(absolute)
    finite = [abs(m) for m in (median_a, median_b) if np.isfinite(m)]
    return EQUIVALENCE_RTOL * max(finite) if finite else None


def _num(x: float) -> str:
    return f"{x:.3g}"


def verdict(name_a: str, name_b: str, test: ObjectivesTest, alpha: float = ALPHA,
            unit: str = "") -> str:
    """A plain-language line for a comparison: too few runs to decide (when no p-value
    below ``alpha`` is possible: :func:`min_p_value`), no significant difference, or which
    is better and by how much (the medians' difference in ``unit``), saying when that
    difference is below the practical-equivalence threshold (``test.threshold``)."""
    p, n_a, n_b = test.p_value, test.n_a, test.n_b
    if min_p_value(n_a, n_b) >= alpha:
        return (f"too few repeats to decide: {n_a} against {n_b} can give no p-value below "
                f"{min_p_value(n_a, n_b):.3g} (alpha {alpha:g}); run at least "
                f"{min_repeats(alpha)} each")
    effect = test.effect
    size = abs(float(effect)) if effect is not None and np.isfinite(effect) else None
    threshold = test.threshold
    u = f" {unit}" if unit else ""
    equivalent = size is not None and threshold is not None and size < threshold
    if p >= alpha:
        tail = (f"; equivalent in practice (medians {_num(size or 0.0)}{u} apart, below the "
                f"threshold {_num(threshold or 0.0)}{u})" if equivalent else "")
        return f"no significant difference between {name_a} and {name_b} (p = {p:.3g}){tail}"
    better, worse = (name_a, name_b) if test.p_a_better > 0.5 else (name_b, name_a)
    if equivalent:
        return (f"{better} ranks lower than {worse} at p = {p:.3g}, but the medians differ by "
                f"{_num(size or 0.0)}{u}, below the practical-equivalence threshold "
                f"{_num(threshold or 0.0)}{u}: equivalent in practice")
    by = f", by {_num(size)}{u} (medians)" if size is not None else ""
    return f"{better} is better than {worse} at p = {p:.3g}{by}"


def sweep_summary(spec: SweepSpec, results: Iterable[Repeat]) -> list[dict[str, Any]]:
    """One row per grid point: success rate, objective statistics, evaluations to target."""
    target = spec.data["run"].get("target")
    by_point: dict[int, list[Repeat]] = {}
    for r in results:
        by_point.setdefault(r.point, []).append(r)
    rows = []
    for i, point in enumerate(spec.points()):
        cells = sorted(by_point.get(i, []), key=lambda r: r.index)
        stats = run_statistics([c.fun for c in cells], [c.feasible for c in cells],
                               target)
        reach = [c.nfev_to_target for c in cells if c.nfev_to_target >= 0]
        row: dict[str, Any] = {"point": i, **{k: json.dumps(v) for k, v in point.items()},
                               "runs": stats.runs, "successes": stats.successes,
                               "success_rate": stats.success_rate, "best": stats.best,
                               "median": stats.median, "worst": stats.worst}
        row.update({
            "median_nfev_to_target": float(np.median(reach)) if reach else float("nan"),
            "wall_s_median": float(np.median([c.wall_s for c in cells])) if cells else 0.0,
        })
        rows.append(row)
    return rows


def per_variant(passed: Bools, variant: Ints, names: Sequence[str],
                confidence: float) -> list[FormYield]:
    """The yield of the draws of each model variant, with its Clopper-Pearson interval:
    ``passed`` (S,) bool, ``variant`` (S,) each draw's index into ``names``."""
    out: list[FormYield] = []
    for v, name in enumerate(names):
        mine = variant == v
        count = int(mine.sum())
        rate = success_rate(int(passed[mine].sum()), count, confidence)
        out.append({"form": name, "samples": count, "yield": rate["rate"],
                    "yield_low": rate["ci_low"], "yield_high": rate["ci_high"]})
    return out
