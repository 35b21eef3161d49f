"""Tolerance classes and their allocation (camopt/engine/allocation.py, ``camopt tolerance
--class`` and ``--allocate``) on a fast-switch run (configs/fast_switch_de.toml, small
budget): the case's classes "standard" and "graded" (docs/tolerance.md)."""

from __future__ import annotations

import json

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
