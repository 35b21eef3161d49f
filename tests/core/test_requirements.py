"""Requirements as data (camopt/core/requirements.py): limits as read, margins in the unit,
round-off at a limit passes, NaN and infinities fail, the verdict in words."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camopt.core.requirements import (
    Requirement,
    Spread,
    all_pass,
    check,
    engineering,
    grade,
    sentence,
    verdict,
    yields,
)

TRAVEL = Requirement("rod travel", "rod_travel_mm", "mm", 17.8, 18.2, source="Sec 3.2")
STRESS = Requirement("shear stress", "tau_max_mpa", "MPa", upper=1194.0, source="Table 1")
LATCH = Requirement("latches", "latched", flag=True, failing="does not latch")


def test_limits_read_as_written():
    assert TRAVEL.limit == "18 ± 0.2 mm"
    assert STRESS.limit == "<= 1194 MPa"
    assert Requirement("v", "v", "m/s", lower=0.7).limit == ">= 0.7 m/s"
    assert LATCH.limit == "yes"


def test_margins_in_the_unit_and_pass_at_the_limit():
    # 18.05 mm: 0.15 mm inside the upper end; 18.3 mm: 0.1 mm outside
    assert TRAVEL.margin(np.array([18.05, 18.3])) == pytest.approx([0.15, -0.1])
    assert STRESS.margin(1000.0) == pytest.approx(194.0)
    assert bool(STRESS.passes(1194.0 * (1 + 1e-13)))  # round-off at an active limit
    assert not bool(STRESS.passes(1194.1))
    assert not bool(STRESS.passes(math.inf)) and not bool(STRESS.passes(math.nan))
    assert STRESS.margin(math.inf) == -math.inf


def test_verdict_names_what_fails_in_words():
    checks = check([LATCH, TRAVEL, STRESS], {"latched": 0.0, "rod_travel_mm": 18.1,
                                             "tau_max_mpa": 1300.0})
    assert [c.passed for c in checks] == [False, True, False]
    assert verdict(checks) == "fail"
    assert sentence(checks) == ("FAIL: does not latch; shear stress 1300 MPa, required "
                                "<= 1194 MPa")
    ok = check([LATCH, TRAVEL], {"latched": 1.0, "rod_travel_mm": 18.0})
    assert verdict(ok) == "pass" and sentence(ok) == "PASS at nominal: meets all 2 requirements"


def test_a_quantity_not_reported_is_not_judged():
    (c,) = check([STRESS], {})
    assert c.value is None and c.passed is None
    assert verdict([c]) == "fail"  # nothing evaluated is no pass


def test_yield_per_requirement():
    samples = {"rod_travel_mm": np.array([17.7, 17.9, 18.0, 18.1, 18.25]),
               "tau_max_mpa": np.full(5, 100.0)}
    (travel, stress) = yields([TRAVEL, STRESS, LATCH], samples)  # latched not sampled
    assert travel["yield"] == pytest.approx(3 / 5) and stress["yield"] == 1.0


# ---- issue #34: at limit, the headline, engineering margins


def test_at_limit_against_the_tolerance_spread_or_the_band():
    """With draws: at limit when the margin is below half the quantity's 5-95 % spread;
    without: below 1 % of the band (two-sided) or of the scale (one-sided)."""
    assert TRAVEL.at_limit(4e-6)  # 4e-6 mm of a 0.4 mm band
    assert not TRAVEL.at_limit(0.15)
    assert TRAVEL.at_limit(0.15, spread=0.2) and not TRAVEL.at_limit(0.15, spread=0.1)
    assert STRESS.at_limit(11.0) and not STRESS.at_limit(12.0)  # 1 % of 1194 MPa
    assert LATCH.at_limit(1.0, sampled_yield=0.9) and not LATCH.at_limit(1.0)


def test_the_headline_names_what_is_at_its_limit():
    spreads = {"rod travel": Spread(0.05, 0.4)}
    checks = check([TRAVEL, STRESS], {"rod_travel_mm": 17.8 + 4e-6, "tau_max_mpa": 369.0},
                   spreads)
    assert [c.at_limit for c in checks] == [True, False]
    assert verdict(checks) == "pass"
    assert sentence(checks) == ("PASS at nominal: meets all 2 requirements, 1 at its limit "
                                "(rod travel)")
    doc = checks[0].as_dict()
    assert doc["at_limit"] is True and doc["margin_share"] == pytest.approx(1e-5, rel=1e-3)
    assert checks[1].as_dict()["margin_share"] is None  # one-sided: no band
    failing = check([TRAVEL], {"rod_travel_mm": 18.3})
    assert not failing[0].at_limit  # a failing requirement is FAIL, not at limit


def test_a_quantity_the_design_does_not_reach_fails_as_n_a():
    (c,) = check([TRAVEL], {"rod_travel_mm": math.nan})
    assert c.passed is False and "n/a" in c.words


def test_margins_in_three_significant_digits():
    assert [engineering(x) for x in (3.984e-6, 825.3, 1248.02, 0.974311, 123456.0)] == [
        "3.98e-06", "825", "1250", "0.974", "123000"]


def test_all_pass_joins_the_sampled_requirements():
    samples = {"rod_travel_mm": np.array([18.0, 18.3, 18.1]),
               "tau_max_mpa": np.array([100.0, 100.0, 1300.0])}
    assert all_pass([TRAVEL, STRESS, LATCH], samples).tolist() == [True, False, False]


def test_values_and_margins_print_at_the_judging_resolution():
    """A value printed at its requirement's resolution meets the printed limit exactly
    when it passes; margins show the excess and are never in e- notation."""
    from camopt.core.requirements import margin_text, value_text

    v = Requirement("closing velocity", "v", "m/s", upper=1.1)  # resolution 1e-5 m/s
    assert v.passes(1.1000000011) and value_text(v, 1.1000000011) == "1.1"
    assert margin_text(v, -1.1e-9) == "0"  # round-off at the limit: met, margin 0
    assert not v.passes(1.100006) and value_text(v, 1.100006) == "1.10001"
    assert margin_text(v, -6e-6) == "-0.000006"  # the excess shown, positional
    assert margin_text(v, 0.0473) == "0.0473" and margin_text(v, 987.46) == "987"
    e = Requirement("latch energy", "e", "J", upper=5.0)
    assert value_text(e, 1.81389e-05) == "0.0000181"  # small, well inside: 3 digits
    for value in (1.1 - 4e-6, 1.1 + 4e-6, 1.1 + 6e-6, 0.9, 2.0):
        shown = float(value_text(v, value))
        assert (shown <= 1.1) is bool(v.passes(value)), value


# ---- issue #49: the decision rules at their exact boundaries ----------------------------
PASS_WORD = verdict(check([STRESS], {"tau_max_mpa": 100.0}))
FAIL_WORD = verdict(check([STRESS], {"tau_max_mpa": 2000.0}))


@pytest.mark.parametrize("values, word", [
    ({"rod_travel_mm": 18.0, "tau_max_mpa": 100.0}, PASS_WORD),
    ({"rod_travel_mm": 18.0, "tau_max_mpa": 1200.0}, FAIL_WORD),   # one fails
    ({"rod_travel_mm": 18.0}, PASS_WORD),                         # one not reported
    ({"rod_travel_mm": math.nan, "tau_max_mpa": 100.0}, FAIL_WORD),  # n/a fails
    ({}, FAIL_WORD),                                              # nothing evaluated
])
def test_the_verdict_rule(values, word):
    """Every evaluated requirement passes, and at least one was evaluated."""
    assert PASS_WORD != FAIL_WORD
    assert verdict(check([TRAVEL, STRESS], values)) == word


def test_a_value_passes_up_to_half_its_resolution_and_no_further():
    """A limit at 0 (scale 1, resolution 1e-5): a value half a resolution beyond passes,
    the next float fails; at a larger limit the allowance scales with it (STRESS:
    1194 MPa, resolution 0.01 MPa)."""
    at_zero = Requirement("r", "q", upper=0.0)
    assert at_zero.tol_scale == 1.0 and at_zero.resolution == pytest.approx(1e-5, rel=1e-12)
    edge = 0.5 * at_zero.resolution
    assert at_zero.passes(edge) and not at_zero.passes(np.nextafter(edge, 1.0))
    allowance = 0.5 * STRESS.resolution
    assert STRESS.resolution == pytest.approx(0.01, rel=1e-12)
    assert STRESS.passes(1194.0 + 0.99 * allowance)
    assert not STRESS.passes(1194.0 + 1.01 * allowance)


def test_at_limit_at_its_exact_boundaries():
    """Strictly below: a margin equal to the spread, to 1 % of the band or scale, or a
    flag's sampled yield equal to 95 %, is not at the limit; the next float below is."""
    from camopt.core.requirements import AT_LIMIT_SHARE, AT_LIMIT_YIELD

    below = lambda v: np.nextafter(v, -np.inf)  # noqa: E731
    assert not TRAVEL.at_limit(0.05, spread=0.05) and TRAVEL.at_limit(below(0.05), 0.05)
    band = AT_LIMIT_SHARE * (18.2 - 17.8)
    for spread in (None, 0.0, math.nan, math.inf):  # no usable spread: the band's share
        assert not TRAVEL.at_limit(band, spread) and TRAVEL.at_limit(below(band), spread)
    scale = AT_LIMIT_SHARE * 1194.0  # one-sided: the share of its scale
    assert not STRESS.at_limit(scale) and STRESS.at_limit(below(scale))
    assert not LATCH.at_limit(1.0, sampled_yield=AT_LIMIT_YIELD)
    assert LATCH.at_limit(1.0, sampled_yield=below(AT_LIMIT_YIELD))
    assert not LATCH.at_limit(1.0, sampled_yield=None)
    (failing,) = check([TRAVEL], {"rod_travel_mm": 18.3}, {"rod travel": Spread(1.0, 0.0)})
    assert failing.passed is False and failing.at_limit is False


def test_yields_shares_and_spreads_exactly():
    """A requirement's yield is the share of samples passing; half_spread half the 5-95 %
    spread of its quantity; margins at their 5th and 50th percentiles (101 evenly spaced
    samples, whose percentiles are exact)."""
    v = np.linspace(1144.0, 1244.0, 101)  # 1 MPa apart; 1194 passes, 1195 does not
    (s,) = yields([STRESS], {"tau_max_mpa": v})
    assert s["yield"] == 51 / 101
    assert s["half_spread"] == pytest.approx(45.0, abs=1e-9)
    assert s["margin_p5"] == pytest.approx(-45.0, abs=1e-9)
    assert s["margin_p50"] == pytest.approx(0.0, abs=1e-9)
    ok = all_pass([TRAVEL, STRESS], {"tau_max_mpa": v, "rod_travel_mm": np.full(101, 18.0)})
    assert ok.sum() == 51 and ok[:51].all()


@pytest.mark.parametrize("verdict_, at_limit, expected, target, graded", [
    ("pass", False, 0.95, 0.95, "pass"),             # the yield's lower end at the target
    ("pass", False, 0.9499, 0.95, "pass at nominal"),
    ("pass", True, 0.99, 0.95, "pass at nominal"),   # a requirement at its limit
    ("pass", False, None, 0.95, "pass at nominal"),  # no estimate
    ("pass", False, 0.99, None, "pass at nominal"),  # no target
    ("fail", False, 0.99, 0.95, "fail"),
    (None, False, 0.99, 0.95, None),
])
def test_the_grade_rule(verdict_, at_limit, expected, target, graded):
    """Green only for a nominal pass with no requirement at its limit and the yield (the
    caller's interval lower end) at or above the target."""
    assert grade(verdict_, at_limit, expected, target) == graded
