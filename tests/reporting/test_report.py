"""The typed report views (issue #37): their ``to_json()`` is the JSON ``show``,
``compare`` and ``export`` wrote when the views were dicts read by string key.

``tests/data/json/`` holds ``show --format json`` of the run and sweep archives in
``tests/data/archives/`` and ``compare --format json`` of the run against itself, as the
dict-based ``report.py`` (70ddf76) printed them, with the verdict's wording of 28 Nov 2026
(``meets all N requirements, k at their limit``) and its grade, headline and yield target
after the older keys; the views must give the same bytes.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.archive.sweeps import load_sweep
from camopt.cli import app
from camopt.reporting import report
from camopt.reporting.comparisons import Comparison, SweepRanking
from camopt.reporting.views import ShowView, Verdict

REPO = Path(__file__).resolve().parents[2]
RUN = "tests/data/archives/run_main_52e31ad.h5"
SWEEP = "tests/data/archives/sweep_main_52e31ad.h5"
GOLDEN = REPO / "tests/data/json"


def _text(doc: object) -> str:
    return json.dumps(doc, indent=2) + "\n"


@pytest.fixture
def at_repo(monkeypatch):
    monkeypatch.chdir(REPO)  # the golden documents name the archives by relative path


def test_show_view_to_json_is_the_dict_era_document(at_repo):
    view = report.show(archive.load_run(RUN))
    assert isinstance(view, ShowView) and isinstance(view.verdict, Verdict)
    assert _text(view.to_json()) == (GOLDEN / "run_main_52e31ad.show.json").read_text()


def test_sweep_ranking_to_json_is_the_dict_era_document(at_repo):
    ranking = report.rank_sweep(*load_sweep(Path(SWEEP)))
    assert isinstance(ranking, SweepRanking)
    assert _text(ranking.to_json()) == (GOLDEN / "sweep_main_52e31ad.show.json").read_text()


def test_comparison_to_json_is_the_dict_era_document(at_repo):
    run = archive.load_run(RUN)
    comparison = report.compare([run, run])
    assert isinstance(comparison, Comparison) and comparison.tests
    assert (_text(comparison.to_json())
            == (GOLDEN / "run_main_52e31ad.compare.json").read_text())


def test_the_cli_writes_the_views_json(at_repo):
    """``show`` and ``compare --format json`` print the views' documents unchanged."""
    runner = CliRunner()
    for args, name in ((["show", RUN], "run_main_52e31ad.show.json"),
                       (["show", SWEEP], "sweep_main_52e31ad.show.json"),
                       (["compare", RUN, RUN], "run_main_52e31ad.compare.json")):
        r = runner.invoke(app, [*args, "--format", "json"])
        assert r.exit_code == 0, r.output
        assert r.stdout == (GOLDEN / name).read_text(), name


def test_views_are_frozen_and_keep_raw_values(at_repo):
    """A view is read by attribute and cannot be changed; it holds inf and NaN (tables
    print them), which only its JSON turns into null."""
    view = report.show(archive.load_run(RUN))
    with pytest.raises(dataclasses.FrozenInstanceError):
        view.next = "x"  # type: ignore[misc]
    inf_best = dataclasses.replace(view.best, objective=float("inf"))
    assert dataclasses.replace(view, best=inf_best).to_json()["best"]["objective"] is None
    summary = report.summary(archive.load_run(RUN))
    assert summary.rows[0].section == "objective"
    assert summary.to_json()["rows"][0]["name"] == summary.rows[0].name


def test_the_budget_hint_names_the_option_that_binds():
    """``next`` asks for more of the budget the solver has: cmaes stops on its
    evaluations (its generations are a ceiling), DE-gr on generations, multistart on
    starts."""
    from types import SimpleNamespace

    from camopt.reporting.report import budget_key
    for solver, key in [({"name": "cmaes", "evaluations": 30000, "generations": 100000},
                         "solver.evaluations"),
                        ({"name": "de_gr", "generations": 300}, "solver.generations"),
                        ({"name": "simplex", "starts": 8}, "solver.starts"),
                        ({"name": "evaluate"}, "solver.generations")]:
        assert budget_key(SimpleNamespace(solver=solver)) == key  # type: ignore[arg-type]


@pytest.mark.parametrize("low, target, meets", [
    (0.95, 0.95, True), (0.9499, 0.95, False), (0.99, 0.95, True), (0.5, None, None),
    (None, 0.95, None)])
def test_a_robust_yield_meets_its_target_when_its_lower_bound_reaches_it(low, target, meets):
    """The robust run's answer: the final check's interval's low end at or above the
    target (equality meets it); no target or no interval: not judged."""
    from types import SimpleNamespace

    from camopt.reporting.report import robust_yield

    run = SimpleNamespace(
        robust_check={"robust": {"yield": 0.97, "yield_low": low, "yield_high": 0.99,
                                 "samples": 2000}},
        robust={} if target is None else {"yield_target": target})
    y = robust_yield(run)  # type: ignore[arg-type]
    assert y is not None and y.meets_target is meets
    assert robust_yield(SimpleNamespace(robust_check=None, robust={})) is None  # type: ignore[arg-type]


def _run(tmp_path, *, robust=None, feasible=True, violated=(), repeats=1, next_config=None):
    """A stand-in run in ``tmp_path`` (its case file ``case.toml`` beside ``other.toml`` and
    ``case_robust.toml``) with what :func:`report.next_step` reads."""
    for name in ("case.toml", "other.toml", "case_robust.toml"):
        (tmp_path / name).write_text('[case]\nkind = "vcb"\n')
    return SimpleNamespace(
        path="r.h5", kind="vcb", config_path=str(tmp_path / "case.toml"),
        robust_check={"robust": robust} if robust else None,
        robust={"yield_target": 0.95} if robust else {},
        best=SimpleNamespace(feasible=feasible, violated=list(violated), repeat=0),
        repeats=[SimpleNamespace(index=i, notes=()) for i in range(repeats)],
        run={} if next_config is None else {"next_config": next_config},
        solver={"name": "de_gr", "generations": 300})


def _judged(verdict, grade):
    return SimpleNamespace(verdict=verdict, grade=grade)


REPORT_LINE = "next: camopt report r.h5 (or camopt export r.h5 --format dxf)"


def test_the_next_step_rule(tmp_path):
    """Each branch of the next-step rule, exact lines: a robust run by its yield's lower
    end; an infeasible best by its repeats; a nominal fail by ``run.next_config`` (a file
    other than the run's own); an amber pass to tolerance analysis; a green pass to the
    report."""
    below = {"yield": 0.97, "yield_low": 0.94, "yield_high": 0.99, "samples": 2000}
    meets = {**below, "yield_low": 0.951}
    robust = str(tmp_path / "case_robust.toml")
    assert report.next_step(_run(tmp_path, robust=below), _judged("pass", "pass")) == (
        "next: the robust yield is below its target: another tolerance_class (camopt "
        "tolerance r.h5 --allocate), a lower robust.yield_target or more budget (--set "
        "solver.generations=...)")
    assert report.next_step(_run(tmp_path, robust=meets), _judged("pass", "pass")) \
        == REPORT_LINE
    assert report.next_step(_run(tmp_path, feasible=False, violated=["a", "b", "c"],
                                 repeats=3), _judged("fail", "fail")) == (
        "next: every repeat ended infeasible (violates a, b): more budget rarely helps; "
        f"for parts made to tolerance: camopt run {robust}, else a wider bound on the "
        "variables the constraints push against")
    assert report.next_step(_run(tmp_path, feasible=False, violated=["a"]),
                            _judged("fail", "fail")) == (
        "next: no feasible design (violates a): more budget (--set solver.generations=... "
        "or --repeats) or a wider bound on the variables the constraints push against")
    other = str(tmp_path / "other.toml")
    assert report.next_step(_run(tmp_path, next_config="other.toml"),
                            _judged("fail", "fail")) == (
        f"next: camopt run {other} (requires what this run's search leaves out)")
    generic = ("next: the run's search leaves out the requirements it fails: run a case "
               "file that requires them (a config of this kind with them as constraints)")
    for named in ("case.toml", "missing.toml", None):  # its own file, none, not named
        assert report.next_step(_run(tmp_path, next_config=named),
                                _judged("fail", "fail")) == generic
    assert report.next_step(_run(tmp_path), _judged("pass", "pass at nominal")) == (
        "next: camopt tolerance r.h5 --samples 2000; for parts made to tolerance: "
        f"camopt run {robust}")
    assert report.next_step(_run(tmp_path), _judged("pass", "pass")) == REPORT_LINE


@pytest.mark.parametrize(("text", "expected"), [
    ('extends = "base.toml"\n[case]\nkind = "vcb"\n', "base.toml"),
    ('"ext\\u0065nds" = "base.toml"\n', "base.toml"),  # a quoted key's escape
    ("'extends' = 'base.toml'\n", "base.toml"),
    ('[case]\nextends = "not top-level"\n', None),
    ('# extends nothing\n[case]\nkind = "vcb"\n', None),
    ('[case]\nkind = "vcb"\n', None),  # not parsed: no word, no escape
    ("extends = \n", None),  # not TOML
])
def test_extends_of_reads_the_top_level_key_as_the_toml_reader_does(text, expected):
    """The robust sibling's ``extends``: what tomllib reads, also for text the reader is
    spared (no ``extends``, no backslash), checked against tomllib itself."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    assert report.extends_of(text) == expected
    try:
        parsed = tomllib.loads(text).get("extends")
    except ValueError:
        parsed = None
    assert parsed == expected


def test_compare_reports_each_runs_own_counts():
    """report.significance: each run's success rate from its own count, Fisher's p on
    (4 of 6, 1 of 5) as the 2x2 table [[4, 2], [1, 4]] gives it by hand: the tables at
    most as likely, with the margins fixed (5 successes of 11), sum to 8/33."""
    s = report.significance("A", np.arange(6.0), 4, "B", np.arange(5.0) + 10, 1)
    assert (s.success_a["rate"], s.success_b["rate"]) == (4 / 6, 1 / 5)
    assert s.success_p_value == pytest.approx(8 / 33, rel=1e-12)
    # (1 of 6, 4 of 5): the tables with 0, 1 or 5 of A's successes, (1 + 30 + 6) / 462
    s = report.significance("A", np.arange(6.0), 1, "B", np.arange(5.0) + 10, 4)
    assert s.success_p_value == pytest.approx(37 / 462, rel=1e-12)
