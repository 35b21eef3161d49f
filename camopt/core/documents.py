"""The JSON documents camopt computes, stores and prints, with their fields named.

Each is a ``TypedDict``: the document is a plain dict at run time (what ``json.dumps``
writes, key order as built, so the archives and ``--format json`` outputs keep their
bytes), and mypy checks every key read or written. Keys that are Python words (``yield``,
``pass``) use the functional form. Pure data (no numpy).

One alias is not a document: :data:`Row`, a table row keyed by the columns its table
chose (a case's variable and metric names), whose values are scalars or name lists. A
TOML table or JSON object as parsed is :data:`camopt.config.raw.RawDoc`.
"""

from __future__ import annotations

from typing import TypedDict, cast

Cell = float | int | bool | str | list[str] | None
"""One value of a table row: a number, a flag, a text, or names (``active``)."""

Row = dict[str, Cell]
"""One row of a table (a solver's designs or starts, a sweep's grid points, a folder's
archives): column name to a scalar; columns are the table's own (variable names)."""

# -- statistics -----------------------------------------------------------------------

FormYield = TypedDict("FormYield", {
    "form": str, "samples": int, "yield": float, "yield_low": float, "yield_high": float})
"""The yield of the draws of one model form with its Clopper-Pearson interval."""


class RunStatisticsDoc(TypedDict):
    """Final objectives over runs (repeats, a sweep point's seeds): their count, best,
    median and worst (+inf for an infeasible run), the feasible share, the successes and
    their rate."""

    runs: int
    best: float
    median: float
    worst: float
    feasible_fraction: float
    successes: int
    success_rate: float


# -- a robust run's final check ---------------------------------------------------------

class Margin(TypedDict):
    """A constraint's normalised value (<= 0 met) at the nominal design and at the yield
    target's order statistic over the draws."""

    nominal: float
    at_target: float


DesignCheck = TypedDict("DesignCheck", {
    "samples": int, "yield": float, "yield_low": float, "yield_high": float,
    "confidence": float, "case_objective": str, "objective_nominal": float,
    "objective_mean": float, "nominal_feasible": bool, "margins": dict[str, Margin],
    "per_form": list[FormYield], "x": dict[str, float]}, total=False)
"""One design on the final check's fresh draws: the yield with its interval, the case's
objective at nominal, its mean and (key ``objective_qNN``, :func:`quantile_key`) its
quantile over the draws, each constraint's margins, per model form the yield
(``per_form``, where the case has forms), and for the nominal best seen its variables
(``x``, display units). Every key optional: archives of older versions lack some."""


class RobustCheck(TypedDict, total=False):
    """The archive's ``robust_check``: the robust optimum (``robust``) and the best
    nominally feasible design the repeats saw (``nominal``) on the same fresh draws."""

    robust: DesignCheck
    nominal: DesignCheck


def quantile_key(quantile: float) -> str:
    """The key of the objective's quantile over the draws (0.9: ``objective_q90``)."""
    return f"objective_q{round(quantile * 100):02d}"


def with_quantile(check: DesignCheck, quantile: float, value: float) -> DesignCheck:
    """``check`` with its objective's quantile under :func:`quantile_key`, placed after
    ``objective_mean`` (the stored key order). A TypedDict cannot name a computed key, so
    this one key is set through a plain dict view of the document."""
    out: dict[str, object] = {}
    for key, v in check.items():
        out[key] = v
        if key == "objective_mean":
            out[quantile_key(quantile)] = value
    return cast(DesignCheck, out)


# -- requirements and the tolerance analysis --------------------------------------------

CheckDoc = TypedDict("CheckDoc", {
    "name": str, "limit": str, "value": "float | None", "margin": "float | None",
    "pass": "bool | None", "at_limit": bool, "margin_share": "float | None", "unit": str,
    "source": str, "quantity": str})
"""One requirement judged on one design (``show --format json``'s ``requirements``)."""

_RequirementSpread = TypedDict("_RequirementSpread", {
    "name": str, "quantity": str, "limit": str, "lower": "float | None",
    "upper": "float | None", "flag": bool, "unit": str, "yield": float,
    "margin_p5": "float | None", "margin_p50": "float | None",
    "half_spread": "float | None"})


class RequirementSpread(_RequirementSpread, total=False):
    """One requirement over tolerance draws: its finite limits, the share of draws that
    pass, its margin's 5th and 50th percentiles and its quantity's half spread (5 to
    95 %; None for a flag); ``nominal_pass`` where the tolerance analysis adds it."""

    nominal_pass: bool


class Percentiles(TypedDict):
    """A quantity's 5th, 50th and 95th percentiles over the draws."""

    p05: float
    p50: float
    p95: float


class Histogram(TypedDict):
    """Counts of values in the bins between consecutive ``edges``."""

    edges: list[float]
    counts: list[int]


class AdjustmentUse(TypedDict):
    """A factory adjustment over the draws: the travel the draws needed within its reach
    (percentiles, histogram) and the share needing more than the reach."""

    name: str
    metric: str
    unit: str
    target: str
    reach: float
    p05: float
    p50: float
    p95: float
    histogram: Histogram
    out_of_reach_share: float


class VaryDoc(TypedDict):
    """One varied input: its nominal value, tolerance and half width (input units)."""

    input: str
    nominal: float
    tolerance: float
    unit: str
    half_width: float


class Sensitivity(TypedDict):
    """An input's Spearman rank correlation with a quantity over the draws."""

    input: str
    spearman: float | None


class Swing(TypedDict):
    """A quantity with one input at the low and at the high end of its tolerance."""

    input: str
    low: float
    high: float


ToleranceDoc = TypedDict("ToleranceDoc", {
    "run": str, "samples": int, "seed": int, "distribution": str, "vary": list[VaryDoc],
    "yield": float, "yield_low": float, "yield_high": float, "yield_confidence": float,
    "forms": list[str], "per_form": list[FormYield], "tolerance_class": "str | None",
    "nominal_feasible": bool, "nominal": dict[str, float],
    "metrics": dict[str, Percentiles], "sensitivity": dict[str, list[Sensitivity]],
    "one_at_a_time": dict[str, list[Swing]], "outside_share": float,
    "violated_share": dict[str, float], "objective_over": str,
    "requirements": list[RequirementSpread], "limiting": "str | None",
    "adjustments": list[AdjustmentUse]})
"""The ``tolerance --format json`` document, also stored in the samples archive."""


# -- Pareto fronts ----------------------------------------------------------------------

class ObjectiveSense(TypedDict):
    """An objective of a multi-objective run and whether it is minimised or maximised."""

    name: str
    sense: str


class _ParetoSummary(TypedDict):
    objectives: list[ObjectiveSense]
    front_size: int
    designs: int


class ParetoSummary(_ParetoSummary, total=False):
    """What a Pareto run found: the objectives, the feasible front's size and ``extent``
    (least and greatest of each objective; None without a feasible design), its ``knee``
    (variables and objectives), and how the headline design stands to the front."""

    extent: dict[str, list[float]] | None
    knee: dict[str, Cell] | None
    headline_on_front: bool
    headline_dominated_by: int
    headline: str


class Normalisation(TypedDict):
    """The union of the fronts' ideal and nadir points (own units)."""

    ideal: list[float]
    nadir: list[float]


class _FrontsCompared(TypedDict):
    objectives: list[str]
    reference_point: list[float] | None
    values: list[float]
    sizes: list[int]


class FrontsCompared(_FrontsCompared, total=False):
    """Each run's hypervolume (``values``) with one reference point for all, and the
    normalisation of the union of the fronts (absent when no run has a feasible one)."""

    normalisation: Normalisation
