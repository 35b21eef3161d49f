"""Typed views of runs compared and of sweeps ranked (``compare``, ``show`` of a sweep
archive, the HTML report's sweep table), as :mod:`camopt.reporting.views` describes
views: frozen dataclasses whose ``to_json()`` is the JSON document, typed by a
``TypedDict``. A module apart from the views of one run, so ``show`` of a run archive
does not define them (start-up time)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypedDict

from camopt.core.documents import CheckDoc, FrontsCompared, RunStatisticsDoc
from camopt.core.stats import ObjectivesTest, RunStatistics
from camopt.reporting.views import Verdict, json_doc


class SignificanceJson(TypedDict):
    """Two sets of final objectives compared (:class:`camopt.core.stats.ObjectivesTest`'s
    fields between the labels and the success rates)."""

    a: str
    b: str
    p_value: float
    p_a_better: float
    rank_biserial: float
    median_a: float | None
    median_b: float | None
    n_a: int
    n_b: int
    effect: float | None
    threshold: float | None
    decidable: bool
    success_a: dict[str, float]
    success_b: dict[str, float]
    success_p_value: float
    verdict: str


class SameObjectiveJson(TypedDict):
    """Two runs reaching one objective with designs differing in ``differ``."""

    runs: list[int]
    objective: float | None
    differ: list[str]


class _ComparisonJson(TypedDict):
    runs: list[str]
    objective_name: str
    verdict: list[str | None]
    verdict_sentence: list[str]
    requirements: list[list[CheckDoc]]
    config_differences: dict[str, list[object]]
    objective: list[float | None]
    feasible: list[bool]
    x: dict[str, list[object]]
    metrics: dict[str, list[object]]
    same_objective_different_designs: list[SameObjectiveJson]
    statistics: list[RunStatisticsDoc]
    labels: list[str]
    tests: list[SignificanceJson]


class ComparisonJson(_ComparisonJson, total=False):
    """The ``compare --format json`` document: per run (lists in the runs' order) the
    verdicts, objectives, variables and metrics; the fronts' ``hypervolume`` where the
    runs have fronts; then the grades, headlines and yield targets (set after it, so
    optional to the type though always written)."""

    hypervolume: FrontsCompared
    verdict_grade: list[str | None]
    verdict_headline: list[str]
    yield_target: list[float | None]


class SweepJson(TypedDict):
    """A sweep archive's document: its verdict, case file, grid, seeds and ranking. A
    ranked point is a table row (``rank``, ``label``, the columns of
    :func:`camopt.core.stats.sweep_summary`, which include the grid's own keys, and
    ``vs_best``), so it stays a mapping of column names."""

    verdict: str | None
    verdict_sentence: str
    requirements: list[CheckDoc]
    sweep: str
    grid: object
    seeds: list[int]
    ranking: list[dict[str, object]]


@dataclass(frozen=True)
class Significance:
    """Two sets of final objectives compared: ``test`` is
    :func:`camopt.core.stats.compare_objectives`'s test with the practical-equivalence
    ``threshold`` set; success rates with their intervals, Fisher's p on them, whether
    these counts can decide at all, and the verdict line."""

    a: str
    b: str
    test: ObjectivesTest
    decidable: bool
    success_a: Mapping[str, float]
    success_b: Mapping[str, float]
    success_p_value: float
    verdict: str

    @property
    def p_value(self) -> float:
        return self.test.p_value

    @property
    def p_a_better(self) -> float:
        return self.test.p_a_better

    @property
    def effect(self) -> float | None:
        """The medians' difference B - A in the objective's unit (None when undefined)."""
        return self.test.effect

    @property
    def threshold(self) -> float | None:
        return self.test.threshold

    def to_json(self) -> SignificanceJson:
        t = self.test
        return json_doc(SignificanceJson(
            a=self.a, b=self.b, p_value=t.p_value, p_a_better=t.p_a_better,
            rank_biserial=t.rank_biserial, median_a=t.median_a, median_b=t.median_b,
            n_a=t.n_a, n_b=t.n_b, effect=t.effect, threshold=t.threshold,
            decidable=self.decidable, success_a=dict(self.success_a),
            success_b=dict(self.success_b), success_p_value=self.success_p_value,
            verdict=self.verdict))


@dataclass(frozen=True)
class SameObjective:
    """Runs ``runs`` (indices) reach one ``objective`` with designs that ``differ`` in
    these variables."""

    runs: tuple[int, int]
    objective: float
    differ: tuple[str, ...]

    def to_json(self) -> SameObjectiveJson:
        return json_doc(SameObjectiveJson(runs=list(self.runs), objective=self.objective,
                                          differ=list(self.differ)))


@dataclass(frozen=True)
class Comparison:
    """``compare``'s view of runs: their paths and labels (A, B or run 1..n), each run's
    verdict, the config keys that differ (one value per run), best objectives,
    feasibility, variables and metrics side by side (None where a run lacks one), pairs
    reaching one objective with different designs, repeat statistics, the significance
    test (two runs with repeats) and, for multi-objective runs, the fronts' hypervolumes."""

    runs: tuple[str, ...]
    objective_name: str
    verdicts: tuple[Verdict, ...]
    config_differences: Mapping[str, list[Any]]
    objective: tuple[float, ...]
    feasible: tuple[bool, ...]
    x: Mapping[str, list[Any]]
    metrics: Mapping[str, list[Any]]
    same_objective_different_designs: tuple[SameObjective, ...]
    statistics: tuple[RunStatistics, ...]
    labels: tuple[str, ...]
    tests: tuple[Significance, ...]
    hypervolume: FrontsCompared | None = None

    def to_json(self) -> ComparisonJson:
        """The ``compare --format json`` document."""
        doc = ComparisonJson(
            runs=list(self.runs), objective_name=self.objective_name,
            verdict=[v.verdict for v in self.verdicts],
            verdict_sentence=[v.sentence for v in self.verdicts],
            requirements=[v.requirements for v in self.verdicts],
            config_differences=dict(self.config_differences),
            objective=list(self.objective), feasible=list(self.feasible),
            x=dict(self.x), metrics=dict(self.metrics),
            same_objective_different_designs=[
                s.to_json() for s in self.same_objective_different_designs],
            statistics=[s.as_dict() for s in self.statistics],
            labels=list(self.labels), tests=[t.to_json() for t in self.tests])
        if self.hypervolume:
            doc["hypervolume"] = self.hypervolume
        doc["verdict_grade"] = [v.grade for v in self.verdicts]  # after the older keys
        doc["verdict_headline"] = [v.headline for v in self.verdicts]
        doc["yield_target"] = [v.yield_target for v in self.verdicts]
        return json_doc(doc)


@dataclass(frozen=True)
class RankedPoint:
    """A sweep's grid point in the ranking: its rank and label, its row of
    :func:`camopt.core.stats.sweep_summary` (success rate, objective statistics,
    evaluations to the target) and, below rank 1, its test against the best point."""

    rank: int
    label: str
    row: Mapping[str, Any]
    vs_best: Significance | None = None

    def to_json(self) -> dict[str, object]:
        """The point's row with its rank and label first (columns are the sweep's own)."""
        doc: dict[str, object] = {"rank": self.rank, "label": self.label, **self.row}
        if self.vs_best is not None:
            doc["vs_best"] = self.vs_best.to_json()
        return json_doc(doc)


@dataclass(frozen=True)
class SweepRanking:
    """A sweep's view: its verdict (each grid point's success rate against
    ``run.min_success_rate``), its case file, grid and seed range, and its points
    ranked by success rate, then median objective."""

    verdict: Verdict
    sweep: str
    grid: Any
    seeds: tuple[int, ...]
    ranking: tuple[RankedPoint, ...]

    def to_json(self) -> SweepJson:
        """The document ``show --format json`` and ``compare --format json`` write for a
        sweep archive."""
        return json_doc(SweepJson(
            verdict=self.verdict.verdict, verdict_sentence=self.verdict.sentence,
            requirements=self.verdict.requirements, sweep=self.sweep, grid=self.grid,
            seeds=list(self.seeds), ranking=[p.to_json() for p in self.ranking]))
