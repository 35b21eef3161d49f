"""One verdict everywhere: small runs of every shipped config, judged by run, show,
runs, compare, report, dashboard and export (table and JSON)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from camopt.cli import app
from tests.conftest import CONFIGS

SLOW = {"vcb_velocity_robust", "vcb_velocity_serviced"}
"""Configs left out: the robust VCBs' final checks take minutes even on a small budget
(the setting and the end of life triple the serviced one's; their robust search is tested
in tests/engine/test_robust.py)."""
SHIPPED = [p for p in sorted(CONFIGS.glob("*.toml")) + sorted((CONFIGS / "reference")
                                                              .glob("*.toml"))
           if p.stem not in SLOW]

BUDGETS = {  # per solver: the smallest budget that still runs every stage
    "de_gr": ["solver.population=10", "solver.generations=4"],
    "nsga2": ["solver.population=12", "solver.generations=3"],
    "pso": ["solver.particles=10", "solver.iterations=4"],
    "cmaes": ["solver.evaluations=200"],
    "newton_pp": ["solver.starts=3"],
    "simplex": ["solver.starts=3"],
}


def small_overrides(config: Path, folder: Path) -> list[str]:
    """``--set`` values that make ``config`` run in seconds (one repeat, a few
    generations, few robust draws); a step-2 VCB config gets a step-1 archive."""
    from camopt.engine.setup import load

    cfg = load(config, [])
    sets = list(BUDGETS.get(cfg.solver.name, []))
    if cfg.run.repeats > 1:
        sets.append("run.repeats=1")
    if getattr(cfg, "robust", None) is not None:
        sets += ["robust.samples=4", "robust.check_samples=100"]
    polish = getattr(cfg.solver, "polish", None)
    if polish is not None:
        sets.append("solver.polish.evaluations=100")
    if cfg.case.kind == "vcb" and getattr(cfg.case, "step", "") == "fourbar":
        step1 = folder / "vcb.h5"  # the cam of a small step-1 run
        sets.append(f'case.cam_archive="{step1}"')
    return sets


runner = CliRunner()
NUMBER = r"-?(?:\d+(?:\.\d*)?|inf)"


def meets(value_cell: str, limit: str) -> bool | None:
    """Whether a printed value meets a printed limit, read as a person reads them (None:
    not a number, such as n/a, or a flag)."""
    value = re.match(NUMBER, value_cell)
    if value is None or limit == "yes":
        return None
    v = float(value.group())
    nums = [float(x) for x in re.findall(NUMBER, limit)]
    if limit.startswith("<="):
        return v <= nums[0]
    if limit.startswith(">="):
        return v >= nums[0]
    if "±" in limit:
        return abs(v - nums[0]) <= nums[1] * (1 + 1e-12)
    return nums[0] <= v <= nums[1]  # 'lo to hi'


@pytest.fixture(scope="module")
def archives(tmp_path_factory):
    """Small runs of every shipped config."""
    folder = tmp_path_factory.mktemp("shipped")
    for config in SHIPPED:
        sets = [a for o in small_overrides(config, folder) for a in ("--set", o)]
        r = runner.invoke(app, ["run", str(config), "--out", str(folder / f"{config.stem}.h5"),
                                "--quiet", *sets])
        assert r.exit_code == 0, (config, r.output)
    return folder


@pytest.mark.slow
def test_no_green_pass_below_target_nor_a_fail_that_meets_its_limit(archives):
    """Every shipped config's show (JSON and table cells): a pass is green only with its
    yield's interval at or above the target, every pass carries the expected yield, and a
    FAIL's printed value never meets its printed limit (nor a pass's miss it); margins
    never in e- notation."""
    from camopt import archive
    from camopt.reporting import report

    for path in sorted(archives.glob("*.h5")):
        doc = json.loads(runner.invoke(app, ["show", str(path), "--format", "json"]).stdout)
        grade, y = doc["verdict_grade"], doc.get("robust_yield") or doc["expected_yield"]
        if grade == "pass":
            low = y.get("low") if "low" in y else y.get("value")
            assert low is not None and low >= doc["yield_target"], path
        if doc["verdict"] == "pass":
            assert "expected yield" in doc["verdict_headline"], path
        if doc["verdict"] == "fail":
            assert grade == "fail", path
        view = archive.load_run(path)
        judged = report.verdict(view)
        for c, cells in zip(judged.checks, report.verdict_rows(judged.checks)):
            shown = meets(cells[2], cells[1])
            if shown is not None and c.passed is not None:
                assert shown is c.passed, (path.name, cells)
            assert "e-" not in cells[3] and "e+" not in cells[3], (path.name, cells)
        assert_closes_on_the_verdict(runner.invoke(app, ["show", str(path)]).stdout,
                                     doc["next"], path.name)


RULE = "─"
"""The character of the rule before the closing lines (rich's ``Console.rule``)."""


def assert_closes_on_the_verdict(text: str, next_line: str, name: str) -> None:
    """``text`` ends with the closing block: after its last rule, the ``verdict:`` line,
    then (a robust run's yield), then ``next_line`` and nothing after it; however many
    lines each wraps to (a fixed count of last lines missed a long verdict's first
    line)."""
    lines = text.splitlines()
    rules = [i for i, line in enumerate(lines) if line and set(line) == {RULE}]
    assert rules, (name, lines[-8:])
    closing = lines[rules[-1] + 1:]
    starts = [line.split(":")[0] for line in closing
              if line.startswith(("verdict: ", "robust: ", "next: "))]
    assert closing and closing[0].startswith("verdict: "), (name, closing)
    assert starts in (["verdict", "next"], ["verdict", "robust", "next"]), (name, closing)
    assert " ".join(closing).split()[-len(next_line.split()):] == next_line.split(), \
        (name, closing)  # the next step, whole, ends the output


def test_a_long_verdict_still_closes_the_output(capsys):
    """A verdict, yield and next step each wrapping over several lines at 80 columns: the
    check above still finds the verdict after the last rule, and fails when something is
    printed after the closing lines (so it can fail)."""
    from camopt.cli.layout import print_closing
    from camopt.reporting.views import RobustYield

    headline = "FAIL: " + ", ".join(f"requirement_{i}_with_a_long_name" for i in range(12))
    y = RobustYield(value=0.5, low=0.4, high=0.6, samples=200, target=0.95,
                    meets_target=False)
    print("the table before")
    next_line = "next: " + "camopt run configs/x.toml; " * 10
    print_closing(headline, "red", next_line, y)
    text = capsys.readouterr().out
    assert len(text.splitlines()) > 9  # the verdict's first line is not among the last 8
    assert_closes_on_the_verdict(text, next_line, "long")
    with pytest.raises(AssertionError):
        assert_closes_on_the_verdict(text + "a line after the verdict\n", next_line, "long")
    with pytest.raises(AssertionError):  # the verdict not first after the rule
        assert_closes_on_the_verdict(text.replace("verdict: ", "verdict- "), next_line,
                                     "long")


@pytest.mark.slow
def test_runs_and_dashboard_grade_as_show(archives):
    """``camopt runs`` and the dashboard show each run's yield and grade as show does: no
    green pass below the yield target."""
    rows = json.loads(runner.invoke(app, ["runs", str(archives), "--format", "json"]).stdout)
    for row in rows:
        show = json.loads(runner.invoke(app, ["show", row["path"], "--format",
                                              "json"]).stdout)
        assert row["verdict_grade"] == show["verdict_grade"], row["path"]
        y = show.get("robust_yield") or show["expected_yield"]
        if y.get("value") is not None:  # every archive that stores a yield lists it
            assert row["expected_yield"] == pytest.approx(y["value"]), row["path"]
    r = runner.invoke(app, ["dashboard", str(archives), "--out", str(archives / "i.html")])
    assert r.exit_code == 0, r.output
    page = (archives / "i.html").read_text()
    green = re.findall(r'<td class="pass"[^>]*>', page)
    passes = [r for r in rows if r.get("verdict_grade") == "pass"]
    assert len(green) == len(passes)
    for r in passes:
        assert r["expected_yield"] >= r["yield_target"]


@pytest.mark.slow
def test_compare_report_and_export_grade_as_show(archives, tmp_path):
    """compare (table and JSON), the HTML report and export's JSON carry show's grade: the
    report's verdict is green (class ok) only for a green pass, every pass has its
    expected yield beside it."""
    from camopt.reporting.html_report import render

    grades = {}
    for path in sorted(archives.glob("*.h5")):
        show = json.loads(runner.invoke(app, ["show", str(path), "--format", "json"]).stdout)
        grades[path.stem] = show["verdict_grade"]
        r = runner.invoke(app, ["export", str(path), "--format", "json", "--out",
                                str(tmp_path / path.stem)])
        assert r.exit_code == 0, r.output
        exported = json.loads(Path(r.stdout.split()[0]).read_text())
        assert exported["verdict_grade"] == show["verdict_grade"]
    for stem in [s for s, g in grades.items() if g != "fail"] + ["vcb", "opening_spring_pp4"]:
        page = render(archives / f"{stem}.h5")
        cls, words = re.search(r'<p class="(\w*)" id="verdict-sentence">([^<]*)</p>',
                               page).groups()
        assert cls == {"pass": "ok", "pass at nominal": "limit", "fail": "bad"}[grades[stem]]
        if words.startswith("PASS"):
            assert "expected yield" in words, stem
    pair = [str(archives / "vcb.h5"), str(archives / "vcb_initial.h5")]
    doc = json.loads(runner.invoke(app, ["compare", *pair, "--format", "json"]).stdout)
    assert doc["verdict_grade"] == [grades["vcb"], grades["vcb_initial"]]
    text = runner.invoke(app, ["compare", *pair]).stdout
    assert "PASS" not in text or "expected yield" in text
