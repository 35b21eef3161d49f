"""``camopt compare``: config differences name the seed; different kinds are refused."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()
PP3 = str(CONFIGS / "opening_spring_pp3.toml")


def run(tmp_path, name, case, *args):
    out = tmp_path / name
    r = runner.invoke(app, ["run", case, "--out", str(out), "--quiet", *args])
    assert r.exit_code == 0, r.output
    return str(out)


def test_seed_from_the_command_line_is_a_config_difference(tmp_path):
    a = run(tmp_path, "s7.h5", PP3, "--seed", "7")
    b = run(tmp_path, "s8.h5", PP3, "--seed", "8")
    r = runner.invoke(app, ["compare", a, b, "--format", "json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["config_differences"] == {"run.seed": [7, 8]}
    r = runner.invoke(app, ["compare", a, b], env={"COLUMNS": "80"})
    assert "run.seed" in r.stdout


def test_runs_of_different_kinds_are_refused(tmp_path):
    a = run(tmp_path, "os.h5", PP3)
    b = run(tmp_path, "fs.h5", str(CONFIGS / "fast_switch.toml"))
    r = runner.invoke(app, ["compare", a, b])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {b}: case_kind: 'fast_switch', but {a} has "
                        "'opening_spring': runs of different kinds are not comparable\n")


VCB_SMALL = ["--set", "solver.generations=20", "--set", "solver.population=20",
             "--repeats", "1"]


def test_compare_leads_with_verdicts_and_repeats_no_row(tmp_path):
    import dataclasses

    from camopt import archive
    from camopt.reporting import report

    a = run(tmp_path, "a.h5", str(CONFIGS / "vcb.toml"), "--seed", "1", *VCB_SMALL)
    b = run(tmp_path, "b.h5", str(CONFIGS / "vcb.toml"), "--seed", "2", *VCB_SMALL)
    r = runner.invoke(app, ["compare", a, b], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    # labelled once, at the top; a path is one word, never wrapped
    assert lines[0] == f"A = {a}" and lines[1] == f"B = {b}"
    assert lines[2].startswith("A: ") and "requirement" in r.stdout.split("\ncompare\n")[0]
    assert sum(a in line or b in line for line in lines) == 2
    names = [line.strip("│").split("│")[0].strip() for line in lines if line.startswith("│")]
    names = [n for n in names if n]
    for name in ("a1", "a2", "a3", "feasible"):
        assert names.count(name) == 1, name  # not again as a metric (a1, feasible as 1)
    assert not any(n.startswith("initial_") for n in names)  # the same vendor in both
    assert "True" not in r.stdout and "e-14" not in r.stdout
    doc = json.loads(runner.invoke(app, ["compare", a, b, "--format", "json"]).stdout)
    assert doc["verdict"] == ["fail", "fail"]  # the paper's problem never asks to latch
    # two designs with one objective are noticed; the same design is not
    va, vb = archive.load_run(a), archive.load_run(b)
    vb = dataclasses.replace(vb, best=dataclasses.replace(
        vb.best, objective=va.best.objective, feasible=True))
    va = dataclasses.replace(va, best=dataclasses.replace(va.best, feasible=True))
    (same,) = report.same_objective_different_designs([va, vb])
    assert same.runs == (0, 1) and "a1" in same.differ
    assert report.same_objective_different_designs([va, va]) == ()


def test_three_repeats_each_are_too_few_to_decide(tmp_path):
    """Issue #34: 3 against 3 repeats cannot give a Mann-Whitney p below 0.05 (at best
    2 / C(6, 3) = 0.1), so compare says the test cannot decide, whatever the medians; the
    success rates get Fisher's exact test; two runs fit about 40 lines at 80 columns."""
    small = ["--set", "solver.generations=10", "--set", "solver.population=20",
             "--set", "solver.polish.maxiter=5", "--repeats", "3"]  # the polish is no subject
    fs = str(CONFIGS / "fast_switch_de.toml")
    a = run(tmp_path, "a.h5", fs, "--seed", "1", *small)
    b = run(tmp_path, "b.h5", fs, "--seed", "2", *small)
    r = runner.invoke(app, ["compare", a, b], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    assert "too few repeats to decide: 3 against 3 can give no p-value below 0.1" in r.stdout
    assert "run at least 4 each" in r.stdout and "Fisher exact p" in r.stdout
    assert len(r.stdout.splitlines()) <= 50
    assert max(len(line) for line in r.stdout.splitlines()[2:]) <= 80
    doc = json.loads(runner.invoke(app, ["compare", a, b, "--format", "json"]).stdout)
    (test,) = doc["tests"]
    assert test["decidable"] is False and test["verdict"].startswith("too few repeats")
    assert doc["labels"] == ["A", "B"]
    # --equivalence sets the threshold, in the objective's unit (ms)
    doc = json.loads(runner.invoke(app, ["compare", a, b, "--format", "json",
                                         "--equivalence", "0.5"]).stdout)
    assert doc["tests"][0]["threshold"] == 0.5
