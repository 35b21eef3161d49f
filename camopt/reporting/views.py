"""Typed views of archives, as :mod:`camopt.reporting.report` builds them and the printers,
the HTML report and the JSON outputs read them.

Each view is a frozen dataclass read by attribute; its ``to_json()`` is the JSON document
``show --format json``, ``compare --format json`` and ``export --format json`` write (the
keys, their order and the values are a contract scripts rely on: non-finite floats as
null, numpy scalars as Python ones). Values held by a view are raw (inf and NaN kept),
which tables print as ``inf`` and ``n/a``. Documents a view carries from elsewhere (the
archive's stored expected yield and robust check, a case's findings, the Pareto summary
of :mod:`camopt.core.pareto`, the statistics tests of :mod:`camopt.core.stats`) stay
mappings under their own keys.

Each ``to_json()`` returns a ``TypedDict`` naming the document's keys (below, after
:func:`json_doc`); its types are the values as written, after :func:`jsonable`, so a
float that may be unbounded or undefined is declared ``| None``.

Here the views of one run (``show``); those of several runs and of a sweep (``compare``)
are in :mod:`camopt.reporting.comparisons`, which ``show`` of a run does not import.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, TypedDict, TypeVar, cast

import numpy as np

from camopt.core.documents import (
    CheckDoc,
    ParetoSummary,
    RobustCheck,
    Row,
)
from camopt.core.record import ExpectedYield
from camopt.core.requirements import (
    GRADE_STYLES,
    Check,
    grade,
    positional,
    short_sentence,
)
from camopt.core.runview import BestView
from camopt.core.stats import YieldInterval

Doc = TypeVar("Doc", bound=Mapping[str, object])


def jsonable(value: Any) -> Any:
    """Replace non-finite floats by None and numpy scalars by Python ones, recursively
    (dicts, lists, tuples; a view by its ``to_json()``)."""
    if hasattr(value, "to_json"):
        return value.to_json()
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_doc(doc: Doc) -> Doc:
    """A JSON object: :func:`jsonable` of each of ``doc``'s values, under the document's
    own type (whose fields declare the values as written)."""
    return cast(Doc, {k: jsonable(v) for k, v in doc.items()})


# -- the views' JSON documents ----------------------------------------------------------

class VerdictJson(TypedDict):
    """A verdict: each requirement's check, the verdict, its grade, sentence and headline,
    and the yield target that grades it."""

    requirements: list[CheckDoc]
    verdict: str | None
    verdict_grade: str | None
    sentence: str
    headline: str
    yield_target: float | None


class ReferenceJson(TypedDict):
    """A reference design: its label and values under the optimum's names."""

    label: str
    values: dict[str, object]


class ReferenceVerdictJson(TypedDict):
    """``show``'s ``reference``: the reference design with its own verdict."""

    label: str
    values: dict[str, object]
    verdict: str | None
    verdict_sentence: str
    requirements: list[CheckDoc]


class RepeatJson(TypedDict):
    """One repeat (``show``'s ``repeats``); ``objective`` None when unbounded."""

    seed: int
    objective: float | None
    feasible: bool
    nfev: int
    wall_s: float
    converged_nit: int | None
    spawn_key: list[int]
    notes: list[str]


class RobustYieldJson(TypedDict):
    """A robust run's yield with its interval and target (``show``'s ``robust_yield``)."""

    value: float | None
    low: float | None
    high: float | None
    samples: int | None
    target: float | None
    meets_target: bool | None


class RobustRowJson(TypedDict):
    """A quantity of the robust check, one value per design compared."""

    name: str
    values: list[object]


class RobustSummaryJson(TypedDict):
    """A robust run's final check, design beside design."""

    labels: list[str]
    samples: int | None
    yield_target: float | None
    rows: list[RobustRowJson]


class SummaryRowJson(TypedDict):
    """A row of the run summary: the optimum's and the reference design's values."""

    section: str
    name: str
    optimum: object
    reference: object


class SummaryJson(TypedDict):
    """The run summary, row by row."""

    reference_label: str
    rows: list[SummaryRowJson]


class RobustDocJson(TypedDict):
    """``show``'s ``robust``: the ``[robust]`` settings as run and the stored check."""

    settings: dict[str, object]
    check: RobustCheck


class BestJson(TypedDict):
    """``show``'s ``best``: the best design (its repeat not repeated)."""

    objective: float | None
    feasible: bool
    x: dict[str, float]
    metrics: dict[str, object]
    active: list[str]
    violated: list[str]


class _ShowJson(TypedDict):
    verdict: str | None
    verdict_sentence: str
    requirements: list[CheckDoc]
    at_limit: list[str]
    expected_yield: ExpectedYield
    next: str
    case: dict[str, object]
    solver: dict[str, object]
    best: BestJson
    repeats: list[RepeatJson]
    table: list[Row]


class ShowJson(_ShowJson, total=False):
    """The ``show --format json`` document of a run. A reference design, a Pareto run's
    rows and summary, a robust run's settings, check and yield where the run has them;
    then the grade, the headline and the yield target (set after those, so optional to
    the type though always written); then a case's findings under their own names,
    which a ``TypedDict`` cannot name."""

    reference: ReferenceVerdictJson
    pareto: list[Row]
    pareto_summary: ParetoSummary | None
    robust: RobustDocJson
    robust_yield: RobustYieldJson | None
    verdict_grade: str | None
    verdict_headline: str
    yield_target: float | None


@dataclass(frozen=True)
class Verdict:
    """Requirements judged on one design: the checks (in the case's order), the overall
    verdict (``"pass"``, ``"fail"``, or None: not judged) and the sentence saying it; for
    a run's best design, the expected yield (``value``, ``low``, ``high``, ``samples``:
    the stored estimate, or a robust run's final check) and the yield target that grade
    it (:func:`camopt.core.requirements.grade`); ``nominal`` False for a verdict on
    something other than a design (a sweep's success rates: graded by its verdict)."""

    checks: tuple[Check, ...]
    verdict: str | None
    sentence: str
    expected_yield: YieldInterval | None = None
    yield_target: float | None = None
    nominal: bool = True

    @property
    def yield_low(self) -> float | None:
        """The low end of the expected yield's 95 % interval (what the grade compares with
        the target), or None."""
        return None if self.expected_yield is None else self.expected_yield.low

    @property
    def grade(self) -> str | None:
        """``pass`` (green), ``pass at nominal`` (amber) or ``fail`` (red); None when not
        judged. A pass is green only when no requirement is at its limit and the yield's
        95 % interval lies at or above the target."""
        if not self.nominal:
            return self.verdict
        return grade(self.verdict, bool(self.at_limit), self.yield_low, self.yield_target)

    @property
    def style(self) -> str:
        """The grade's terminal colour (``green``, ``yellow`` for amber, ``red``)."""
        return GRADE_STYLES.get(self.grade or "", "")

    @property
    def yield_words(self) -> str:
        """``expected yield 1.3 % [0.4, 3.4] (target 95 %, below it)``; '' when not a
        design's verdict."""
        if not self.nominal:
            return ""
        y = self.expected_yield
        if y is None:
            return "expected yield not estimated"
        text = f"expected yield {100 * y.value:.1f} %"
        if y.low is not None and y.high is not None:
            text += f" [{100 * y.low:.1f}, {100 * y.high:.1f}]"
        if self.yield_target is not None:
            below = self.yield_low is not None and self.yield_low < self.yield_target
            text += (f" (target {positional(100 * self.yield_target, 1)} %"
                     f"{', below it' if below else ''})")
        return text

    @property
    def headline(self) -> str:
        """The verdict with the expected yield beside any pass: ``PASS at nominal: meets
        all 6 requirements; expected yield 1.3 % [0.4, 3.4] (target 95 %, below it)``."""
        if self.verdict == "pass" and self.nominal:
            return f"{self.sentence}; {self.yield_words}"
        return self.sentence

    @property
    def short(self) -> str:
        """:attr:`headline` with the failing requirements named only (a run's last
        lines)."""
        words = short_sentence(self.checks) if self.checks else self.sentence
        if self.verdict == "pass" and self.nominal:
            return f"{words}; {self.yield_words}"
        return words

    @property
    def requirements(self) -> list[CheckDoc]:
        """Each check's JSON form (:meth:`Check.as_dict`)."""
        return [c.as_dict() for c in self.checks]

    @property
    def at_limit(self) -> list[str]:
        """Names of the passing requirements at their limit."""
        return [c.requirement.name for c in self.checks if c.at_limit]

    def to_json(self) -> VerdictJson:
        return json_doc(VerdictJson(
            requirements=self.requirements, verdict=self.verdict, verdict_grade=self.grade,
            sentence=self.sentence, headline=self.headline, yield_target=self.yield_target))


@dataclass(frozen=True)
class Reference:
    """The reference design the optimum is shown beside: its label (``reference: vendor,
    Sec 2.3 and Table 2``; '' when there is none) and ``{name: value}`` under the
    optimum's names (``objective`` included)."""

    label: str = ""
    values: Mapping[str, Any] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.label)

    def get(self, name: str, default: Any = None) -> Any:
        return self.values.get(name, default)

    def to_json(self) -> ReferenceJson:
        return json_doc(ReferenceJson(label=self.label, values=dict(self.values)))


@dataclass(frozen=True)
class ReferenceVerdict:
    """The reference design with its own verdict (``show``'s ``reference``)."""

    reference: Reference
    judged: Verdict

    @property
    def label(self) -> str:
        return self.reference.label

    @property
    def verdict(self) -> str | None:
        return self.judged.verdict

    @property
    def verdict_sentence(self) -> str:
        return self.judged.sentence

    def to_json(self) -> ReferenceVerdictJson:
        return json_doc(ReferenceVerdictJson(
            label=self.label, values=dict(self.reference.values), verdict=self.verdict,
            verdict_sentence=self.verdict_sentence, requirements=self.judged.requirements))


@dataclass(frozen=True)
class RepeatRow:
    """One repeat as ``show`` reports it (``objective`` is the repeat's ``fun``; wall
    time in s; ``spawn_key`` (k,) for child k of ``SeedSequence(run.seed)``)."""

    seed: int
    objective: float
    feasible: bool
    nfev: int
    wall_s: float
    converged_nit: int | None
    spawn_key: tuple[int, ...]
    notes: tuple[str, ...]

    def to_json(self) -> RepeatJson:
        return json_doc(RepeatJson(
            seed=self.seed, objective=self.objective, feasible=self.feasible, nfev=self.nfev,
            wall_s=self.wall_s, converged_nit=self.converged_nit,
            spawn_key=list(self.spawn_key), notes=list(self.notes)))


@dataclass(frozen=True)
class RobustYield:
    """A robust run's answer: the final check's yield of the robust optimum (share of
    ``samples`` fresh draws) with its Clopper-Pearson interval ``low``..``high``, the
    ``target`` and ``meets_target`` (the interval's low end at or above it; None when
    either is unknown)."""

    value: float | None
    low: float | None
    high: float | None
    samples: int | None
    target: float | None
    meets_target: bool | None

    def to_json(self) -> RobustYieldJson:
        return json_doc(RobustYieldJson(
            value=self.value, low=self.low, high=self.high, samples=self.samples,
            target=self.target, meets_target=self.meets_target))


@dataclass(frozen=True)
class RobustRow:
    """A row of the robust check: a quantity's value for each design compared."""

    name: str
    values: tuple[Any, ...]

    def to_json(self) -> RobustRowJson:
        return json_doc(RobustRowJson(name=self.name, values=list(self.values)))


@dataclass(frozen=True)
class RobustSummary:
    """A robust run's final check, the robust optimum beside the best nominally feasible
    design (``labels``), on the same ``samples`` fresh draws."""

    labels: tuple[str, ...]
    samples: int | None
    yield_target: float | None
    rows: tuple[RobustRow, ...]

    def to_json(self) -> RobustSummaryJson:
        return json_doc(RobustSummaryJson(
            labels=list(self.labels), samples=self.samples, yield_target=self.yield_target,
            rows=[r.to_json() for r in self.rows]))


@dataclass(frozen=True)
class SummaryRow:
    """A row of the run summary: ``section`` (objective, variables, metrics), the name
    (its unit in it) and the optimum's and the reference design's values (None when
    the reference has none)."""

    section: str
    name: str
    optimum: Any
    reference: Any

    def to_json(self) -> SummaryRowJson:
        return json_doc(SummaryRowJson(section=self.section, name=self.name,
                                       optimum=self.optimum, reference=self.reference))


@dataclass(frozen=True)
class Summary:
    """The run summary: the best design beside the reference design, row by row."""

    reference_label: str
    rows: tuple[SummaryRow, ...]

    def to_json(self) -> SummaryJson:
        return json_doc(SummaryJson(reference_label=self.reference_label,
                                    rows=[r.to_json() for r in self.rows]))


@dataclass(frozen=True)
class RobustDoc:
    """A robust run's ``[robust]`` settings as run and its stored final check."""

    settings: Mapping[str, Any]
    check: RobustCheck

    def to_json(self) -> RobustDocJson:
        return json_doc(RobustDocJson(settings=dict(self.settings), check=self.check))


@dataclass(frozen=True)
class ShowView:
    """``show``'s view of a run: the verdict of the best design, the expected yield (the
    archive's stored estimate, or one made at show time), the next step, the config as
    run, the best design, repeats and the solver's table; the reference design with its
    own verdict; a multi-objective run's Pareto rows and summary; a robust run's settings,
    check and yield; a case's findings (under their own names)."""

    verdict: Verdict
    expected_yield: ExpectedYield
    next: str
    case: Mapping[str, Any]
    solver: Mapping[str, Any]
    best: BestView
    repeats: tuple[RepeatRow, ...]
    table: Sequence[Row]
    reference: ReferenceVerdict | None = None
    pareto: Sequence[Row] | None = None
    pareto_summary: ParetoSummary | None = None
    robust: RobustDoc | None = None
    robust_yield: RobustYield | None = None
    findings: Mapping[str, Any] = field(default_factory=dict)

    def to_json(self) -> ShowJson:
        """The ``show --format json`` document (keys in their documented order)."""
        b = asdict(self.best)
        best = BestJson(objective=b["objective"], feasible=b["feasible"], x=b["x"],
                        metrics=b["metrics"], active=b["active"], violated=b["violated"])
        doc = ShowJson(verdict=self.verdict.verdict, verdict_sentence=self.verdict.sentence,
                       requirements=self.verdict.requirements,
                       at_limit=self.verdict.at_limit, expected_yield=self.expected_yield,
                       next=self.next, case=dict(self.case), solver=dict(self.solver),
                       best=best, repeats=[r.to_json() for r in self.repeats],
                       table=list(self.table))
        if self.reference is not None:
            doc["reference"] = self.reference.to_json()
        if self.pareto is not None:
            doc["pareto"] = list(self.pareto)
            doc["pareto_summary"] = self.pareto_summary
        if self.robust is not None:
            doc["robust"] = self.robust.to_json()
            doc["robust_yield"] = (None if self.robust_yield is None
                                   else self.robust_yield.to_json())
        # the grade (green pass, amber pass at nominal, red fail) and the headline with the
        # yield beside a pass: after the older keys, whose order scripts rely on
        doc["verdict_grade"] = self.verdict.grade
        doc["verdict_headline"] = self.verdict.headline
        doc["yield_target"] = self.verdict.yield_target
        # a case's findings under their own names, never over the contract's keys; the
        # type cannot name them, so they are set through a plain dict view of the document
        out: dict[str, object] = dict(doc)
        out.update({k: v for k, v in self.findings.items() if k not in out})
        return json_doc(cast(ShowJson, out))
