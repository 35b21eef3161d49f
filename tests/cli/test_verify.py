"""``camopt verify``: the multibody cross-check's command line (JSON with both numbers and
the ratio; one error line without the extra or for a run of another kind)."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from camopt.cases.vcb import multibody
from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args], env={"COLUMNS": "80"})


@pytest.fixture(scope="module")
def vcb_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("verify") / "vcb.h5"
    r = invoke("run", CONFIGS / "vcb.toml", "--out", out, "--quiet", "--set",
               "solver.generations=5", "--set", "solver.population=10", "--repeats", "1")
    assert r.exit_code == 0, r.output
    return out


def test_without_the_extra_one_error_line(vcb_run, monkeypatch):
    monkeypatch.setattr(multibody, "exu", None)
    r = invoke("verify", vcb_run, "--design", "reference")
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "pip install 'camopt[multibody]'" in lines[0]
    assert r.stdout == ""


def test_another_kind_is_refused(fast_run):
    r = invoke("verify", fast_run)
    assert r.exit_code == 2
    assert r.stderr.startswith("error: ") and "VCB" in r.stderr


@pytest.mark.skipif(not multibody.available(), reason="camopt[multibody] not installed")
@pytest.mark.slow  # a multibody simulation: ~4 s of CPU, more on a loaded machine
def test_reference_design_in_json(vcb_run):
    """The vendor's design: both numbers, their ratio and the verdict, stdout pure JSON."""
    r = invoke("verify", vcb_run, "--design", "reference", "--format", "json", "--sets",
               "identified")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert [(s["form"], s["set"]) for s in doc["sets"]] == [("efficiency_coulomb", 0)]
    assert doc["sets"][0]["quantities"] == doc["quantities"]
    rows = {q["name"]: q for q in doc["quantities"]}
    touch = rows["release_to_touch"]
    assert touch["ratio"] == pytest.approx(touch["multibody"] / touch["camopt"], rel=1e-12)
    assert touch["limit"] == 0.02 and touch["within"] is True
    assert rows["touch_velocity"]["within"] is True
    assert doc["agree"] is True and doc["design"] == "reference"


@pytest.mark.skipif(not multibody.available(), reason="camopt[multibody] not installed")
def test_a_failed_simulation_is_one_error_line(vcb_run, monkeypatch):
    import exudyn

    def fail(*args, **kwargs):
        raise exudyn.SolverError("SolveDynamic terminated")

    monkeypatch.setattr(multibody, "run", fail)
    r = invoke("verify", vcb_run, "--design", "reference")
    assert r.exit_code == 2 and r.stdout == ""
    assert r.stderr == (f"error: {vcb_run}: verify: the multibody simulation failed "
                        "(SolveDynamic terminated)\n")
