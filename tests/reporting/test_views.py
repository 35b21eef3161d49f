"""The report views' decisions (camopt/reporting/views.py): a verdict's grade reads the
expected yield's interval, never its point estimate."""

from __future__ import annotations

import pytest

from camopt.core.stats import YieldInterval
from camopt.reporting.views import Verdict


@pytest.mark.parametrize("estimate, target, grade", [
    (YieldInterval(0.97, 0.94, 0.99, 2000), 0.95, "pass at nominal"),
    (YieldInterval(0.97, 0.95, 0.99, 2000), 0.95, "pass"),  # equality meets it
    (YieldInterval(0.999, 0.9499, 1.0, 300), 0.95, "pass at nominal"),
    (YieldInterval(0.97), 0.95, "pass at nominal"),  # no interval: not judged green
    (None, 0.95, "pass at nominal"),  # not estimated: never green
])
def test_a_pass_is_green_only_when_the_yields_lower_end_reaches_the_target(estimate, target,
                                                                          grade):
    v = Verdict((), "pass", "meets all 0 requirements", estimate, target)
    assert v.grade == grade
    assert v.yield_low == (None if estimate is None else estimate.low)
    assert Verdict((), "fail", "", estimate, target).grade == "fail"


def test_the_yield_words_say_below_by_the_lower_end():
    v = Verdict((), "pass", "", YieldInterval(0.97, 0.94, 0.99), 0.95)
    assert v.yield_words == "expected yield 97.0 % [94.0, 99.0] (target 95 %, below it)"
    v = Verdict((), "pass", "", YieldInterval(0.97, 0.95, 0.99), 0.95)
    assert v.yield_words == "expected yield 97.0 % [95.0, 99.0] (target 95 %)"


# -- the typed documents name the keys written ----------------------------------------

RUN = "tests/data/archives/run_main_52e31ad.h5"


def _declared(doc_type: type) -> tuple[frozenset[str], frozenset[str]]:
    return doc_type.__required_keys__, doc_type.__optional_keys__  # type: ignore[attr-defined]


def _check_keys(doc: dict, doc_type: type, extra: frozenset[str] = frozenset()) -> None:
    """Every required key written, nothing written the type does not declare (``extra``:
    keys a type cannot name, a case's findings)."""
    required, optional = _declared(doc_type)
    assert required <= doc.keys(), required - doc.keys()
    assert doc.keys() - required - optional == extra


def test_each_views_document_type_names_the_keys_its_to_json_writes(monkeypatch):
    from pathlib import Path

    from camopt import archive
    from camopt.reporting import comparisons, report, views

    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    run = archive.load_run(RUN)
    show = report.show(run)
    doc = show.to_json()
    required, optional = _declared(views.ShowJson)
    _check_keys(dict(doc), views.ShowJson, frozenset(show.findings) - required - optional)
    # the grade, headline and target are optional to the type only: always written
    assert {"verdict_grade", "verdict_headline", "yield_target"} <= doc.keys()
    _check_keys(dict(doc["best"]), views.BestJson)
    for rep in doc["repeats"]:
        _check_keys(dict(rep), views.RepeatJson)
    _check_keys(dict(show.verdict.to_json()), views.VerdictJson)
    if show.reference is not None:
        _check_keys(dict(show.reference.to_json()), views.ReferenceVerdictJson)
    summary = report.summary(run).to_json()
    _check_keys(dict(summary), views.SummaryJson)
    for row in summary["rows"]:
        _check_keys(dict(row), views.SummaryRowJson)
    comparison = report.compare([run, run]).to_json()
    _check_keys(dict(comparison), comparisons.ComparisonJson)
    assert {"verdict_grade", "verdict_headline", "yield_target"} <= comparison.keys()
    assert comparison["tests"], "the golden run has repeats: one significance test"
    for t in comparison["tests"]:
        _check_keys(dict(t), comparisons.SignificanceJson)
