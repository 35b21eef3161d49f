"""Tolerance classes and their allocation (camopt/engine/allocation.py, ``camopt tolerance
--class`` and ``--allocate``) on a fast-switch run (configs/fast_switch_de.toml, small
budget): the case's classes "standard" and "graded" (docs/tolerance.md)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cases import get_case
from camopt.cli import app
from camopt.engine.allocation import allocate
from camopt.engine.tolerance import analyse, default_varies
from tests.conftest import CONFIGS

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def switch_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("alloc") / "fs.h5"
    r = invoke("run", CONFIGS / "fast_switch_de.toml", "--out", path, "--quiet",
               "--set", "solver.generations=150")
    assert r.exit_code == 0, r.output
    return archive.load_run(path)


def test_a_class_gives_its_own_tolerances_and_an_unknown_one_is_refused(switch_run):
    spec = get_case("fast_switch")
    standard = {v.name: v.tolerance for v in default_varies(switch_run)}
    graded = {v.name: v.tolerance for v in default_varies(switch_run, "graded")}
    assert standard["case.wire_diameter_mm"] == 0.02 and graded["case.wire_diameter_mm"] == 0.01
    assert standard["r2_mm"] == graded["r2_mm"]  # the links are machined alike
    assert spec.class_names() == ("standard", "graded")  # cheapest first
    r = invoke("tolerance", switch_run.path, "--class", "grade", "--samples", 10)
    assert r.exit_code == 2
    assert r.output.strip().splitlines() == [
        f"error: {switch_run.path}: --class: 'grade': not a tolerance class of case "
        "'fast_switch' (classes: standard, graded)"]


def test_each_class_yield_is_the_tolerance_analysis_on_the_same_draws(switch_run):
    """The allocation evaluates every class on one set of unit draws, the draws
    ``camopt tolerance --class C`` makes with the same seed: its yields are those."""
    result = allocate(switch_run, 0.95, 600, 3)
    by_name = {c.name: c for c in result.classes}
    for name in ("standard", "graded"):
        t = analyse(switch_run, default_varies(switch_run, name), 600, 3)
        assert by_name[name].yield_ == pytest.approx(t.summary["yield"], abs=1e-12)
        assert by_name[name].low <= by_name[name].yield_ <= by_name[name].high
    reaching = [c.name for c in result.classes if c.low >= 0.95]
    assert result.chosen == (reaching[0] if reaching else None)
    assert {t.input for t in result.tightenings} <= {
        "sud_mm", "case.wire_diameter_mm", "case.spring_diameter_mm"}
    for t in result.tightenings:  # each gain is against the cheapest class's yield
        assert t.gain == pytest.approx(t.yield_ - result.classes[0].yield_, abs=1e-12)


def test_allocate_json_names_classes_costs_and_the_choice(switch_run):
    r = invoke("tolerance", switch_run.path, "--allocate", "--samples", 300, "--seed", 1,
               "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert [c["name"] for c in doc["classes"]] == ["standard", "graded"]
    assert [c["relative_cost"] for c in doc["classes"]] == [1.0, 1.3]
    assert doc["target"] == 0.95 and set(doc["classes"][0]) >= {"yield", "low", "high"}
    r = invoke("tolerance", switch_run.path, "--allocate", "--class", "graded")
    assert r.exit_code == 2 and r.output.startswith("error: ")


@pytest.mark.parametrize("lows, target, chosen", [
    ((0.97, 0.99), 0.95, 0),    # both reach: the cheaper, not the higher yield
    ((0.50, 0.95), 0.95, 1),    # a lower bound equal to the target reaches it
    ((0.50, 0.9499), 0.95, None),  # none reaches: no class chosen
    ((0.96, 0.50), 0.95, 0),
])
def test_the_chosen_class_is_the_cheapest_that_reaches_the_target(fast_run, monkeypatch,
                                                                   lows, target, chosen):
    """The allocation's decision pinned with stand-ins: every draw passes (a trivial
    evaluation) and the classes' interval lower bounds are given, in the case's order
    (cheapest first, by documented cost). Chosen: the first whose lower bound is at or
    above the target; the tightenings then aim at that class (the tightest without
    one)."""
    from camopt.core.problem import Evaluation
    from camopt.engine import allocation

    run = archive.load_run(fast_run)
    spec = get_case(run.kind)
    names = spec.class_names()
    assert len(names) == len(lows)
    assert [spec.class_cost(n) for n in names] == sorted(spec.class_cost(n) for n in names)
    given = iter(lows)

    def evaluate(run, problem, varies, values, describe, variant=None):
        n = len(values)
        return Evaluation(np.zeros(n), np.zeros((n, 1)), {}), np.zeros(n, dtype=bool)

    monkeypatch.setattr(allocation, "evaluate_inputs", evaluate)
    monkeypatch.setattr(allocation, "success_rate",
                        lambda ok, n, confidence: {"ci_low": next(given), "ci_high": 1.0})
    result = allocate(run, target, 20, 0)
    assert [c.reaches_target for c in result.classes] == [low >= target for low in lows]
    assert result.chosen == (None if chosen is None else names[chosen])
    aim = names[-1] if chosen is None else names[chosen]
    tight = {v.name: allocation._text(v)
             for v in allocation.class_varies(run, allocation.problem_of(run), aim)}
    loose = {v.name: allocation._text(v)
             for v in allocation.class_varies(run, allocation.problem_of(run), names[0])}
    assert {t.input for t in result.tightenings} == {k for k in tight if tight[k] != loose[k]}
    assert all(t.tolerance_to == tight[t.input] for t in result.tightenings)
    assert result.tightenings or aim == names[0]


@pytest.mark.parametrize("passed, samples, target, reaches", [
    (96, 100, 0.95, False),    # 96 % point estimate, interval [0.9007, 0.9890]
    (100, 100, 0.95, True),    # [0.9638, 1]
    (100, 100, 0.97, False),   # 100 % point estimate, lower end 0.9638
    (1979, 2000, 0.985, False),  # 98.95 % point estimate, lower end 0.98399
    (1979, 2000, 0.98, True),
])
def test_a_class_reaches_the_target_by_its_intervals_lower_end(passed, samples, target,
                                                               reaches):
    """class_yield: the yield is passed / samples exactly, its interval the Clopper-Pearson
    one (scipy.stats.binomtest's exact interval, an independent implementation: rtol
    1e-9, the two beta inversions' agreement), and "reaches" compares the interval's
    lower end with the target, never the point estimate."""
    from scipy.stats import binomtest

    from camopt.engine.allocation import class_yield

    c = class_yield("graded", 2.0, passed, samples, target, 0.95)
    ci = binomtest(passed, samples).proportion_ci(0.95, method="exact")
    assert c.yield_ == passed / samples and c.name == "graded" and c.relative_cost == 2.0
    assert c.low == pytest.approx(ci.low, rel=1e-9)
    assert c.high == pytest.approx(ci.high, rel=1e-9)
    assert c.reaches_target is reaches is (ci.low >= target)
