"""Requirements as data (camopt/core/requirements.py): limits as read, margins in the unit,
round-off at a limit passes, NaN and infinities fail, the verdict in words."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camopt.core.requirements import Requirement, check, sentence, verdict, yields

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
    assert verdict(ok) == "pass" and sentence(ok) == "PASS: meets all 2 requirements"


def test_a_quantity_not_reported_is_not_judged():
    (c,) = check([STRESS], {})
    assert c.value is None and c.passed is None
    assert verdict([c]) == "fail"  # nothing evaluated is no pass


def test_yield_per_requirement():
    samples = {"rod_travel_mm": np.array([17.7, 17.9, 18.0, 18.1, 18.25]),
               "tau_max_mpa": np.full(5, 100.0)}
    (travel, stress) = yields([TRAVEL, STRESS, LATCH], samples)  # latched not sampled
    assert travel["yield"] == pytest.approx(3 / 5) and stress["yield"] == 1.0
