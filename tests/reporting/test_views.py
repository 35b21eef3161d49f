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
