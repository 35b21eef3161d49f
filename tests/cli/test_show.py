"""``camopt show``: the run summary (best design beside the reference design, at 80
columns) and sweeps."""

from __future__ import annotations

import dataclasses
import json
import re

import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from camopt.reporting import report
from tests.conftest import CONFIGS

runner = CliRunner()
SMALL_VCB = ["--set", "solver.generations=30", "--set", "solver.population=30",
             "--repeats", "2"]


def invoke(*args, columns=80):
    return runner.invoke(app, [str(a) for a in args], env={"COLUMNS": str(columns)})


@pytest.fixture(scope="module")
def vcb_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("show") / "vcb.h5"
    r = invoke("run", CONFIGS / "vcb.toml", "--out", out, "--quiet", *SMALL_VCB)
    assert r.exit_code == 0, r.output
    return out


def best_rows(stdout: str) -> dict[str, list[str]]:
    """The cells of the best-design table's rows, by row name."""
    rows = {}
    for line in stdout.splitlines():
        cells = [c.strip() for c in line.strip("│").split("│")]
        if line.startswith("│") and len(cells) == 3:
            rows[cells[0]] = cells[1:]
    return rows


def test_summary_shows_optimum_beside_the_initial_design_in_80_columns(vcb_run):
    r = invoke("show", vcb_run)
    assert r.exit_code == 0, r.output
    assert max(len(line) for line in r.stdout.splitlines()[1:]) <= 80  # line 0: the path
    assert "best design beside the reference: vendor, Sec 2.3 and Table 2" in r.stdout
    rows = best_rows(r.stdout)
    view = archive.load_run(vcb_run)
    m = view.best.metrics
    # every number whole on one line, under the optimum and the reference columns
    for name in ("tau_max_mpa", "driving_work_j", "rod_travel_mm", "closing_velocity_avg_m_s"):
        assert rows[name][0] == report.format_value(m[name])  # NaN (never closes): n/a
    assert rows["driving_work_j"][1] == f"{m['initial_driving_work_j']:.6g}"
    assert rows["objective: objective_j"][0] == f"{view.best.objective:.6g}"
    assert rows["tau_max_mpa"][1] == "inf"  # the vendor's follower dwells: unbounded stress
    assert not any(k.startswith("initial_") for k in rows)  # folded into the column
    assert list(rows).count("feasible") == 1
    for x in view.best.x:
        assert rows[x][0] == f"{view.best.x[x]:.6g}"
    # the vendor's spring rates are the config's (Table 2), not '-'
    assert rows["kc1_n_per_mm"][1] == "7.72" and rows["kc2_n_per_mm"][1] == "9.33"


def test_verdict_leads_and_says_in_words_why_the_paper_optimum_fails(vcb_run):
    """The paper's zero-surplus problem does not ask the cam to latch: its optimum stalls
    (latched = 0) and fails the requirement, said in words on the first screen."""
    r = invoke("show", vcb_run)
    first_screen = "\n".join(r.stdout.splitlines()[:24])
    assert "FAIL: does not latch" in first_screen
    assert "requirements of the best design" in first_screen
    for name in ("rod travel", "18 ± 0.2 mm", "cam contact", "<= 1194 MPa"):
        assert name in first_screen
    doc = json.loads(invoke("show", vcb_run, "--format", "json").stdout)
    assert doc["verdict"] == "fail"
    reqs = {q["name"]: q for q in doc["requirements"]}
    latch = reqs["cam latches at the end of the stroke"]
    assert latch["value"] == 0 and latch["pass"] is False
    travel = reqs["rod travel"]
    m = archive.load_run(vcb_run).best.metrics
    assert travel["value"] == pytest.approx(m["rod_travel_mm"])
    assert travel["margin"] == pytest.approx(0.2 - abs(m["rod_travel_mm"] - 18.0))
    assert travel["pass"] is (abs(m["rod_travel_mm"] - 18.0) <= 0.2)
    for q in doc["requirements"]:
        assert set(q) >= {"name", "limit", "value", "margin", "pass"}
    assert doc["reference"]["label"] == "reference: vendor, Sec 2.3 and Table 2"
    assert doc["reference"]["verdict"] == "fail"  # the vendor closes at 1.71 m/s (ADAMS)


def test_json_keys_unchanged(vcb_run):
    doc = json.loads(invoke("show", vcb_run, "--format", "json").stdout)
    assert list(doc) == ["verdict", "verdict_sentence", "requirements", "at_limit",
                         "expected_yield", "next", "case", "solver", "best", "repeats",
                         "table", "reference", "verdict_grade", "verdict_headline",
                         "yield_target"]
    assert doc["best"]["metrics"]["initial_tau_max_mpa"] is None  # inf as null: valid JSON


def test_infeasible_best_names_what_it_violates(vcb_run):
    view = archive.load_run(vcb_run)
    broken = dataclasses.replace(view, best=dataclasses.replace(
        view.best, feasible=False, violated=["shear_yield", "rod_travel"], active=[]))
    assert report.status(broken) == "INFEASIBLE: violates shear_yield, rod_travel"
    assert report.status(view).startswith("feasible; active constraints: ")


def test_infeasible_best_without_violation_says_why(tmp_path):
    out = tmp_path / "pp4.h5"
    r = invoke("run", CONFIGS / "opening_spring_pp4.toml", "--out", out)
    assert r.exit_code == 0, r.output
    assert "INFEASIBLE: 0 distinct roots" in r.stdout
    assert "active constraints: none" not in r.stdout


def test_show_reads_a_sweep(tmp_path):
    out = tmp_path / "sweep.h5"
    r = invoke("sweep", CONFIGS / "vcb.toml", "--seeds", "0:2", "--grid",
               "solver.population=10,20", "--set", "solver.generations=10", "--set",
               "run.repeats=1", "--out", out,
               "--quiet", "--jobs", "1")
    assert r.exit_code == 0, r.output
    shown = invoke("show", out)
    assert shown.exit_code == 0, shown.output
    assert "grid points ranked" in shown.stdout
    assert max(len(line) for line in shown.stdout.splitlines()) <= 80
    doc = json.loads(invoke("show", out, "--format", "json").stdout)
    compared = json.loads(invoke("compare", out, "--format", "json").stdout)
    assert [r["label"] for r in doc["ranking"]] == [r["label"] for r in compared["ranking"]]
    assert {r["label"] for r in doc["ranking"]} == {"solver.population=10",
                                                   "solver.population=20"}
    for row in doc["ranking"]:
        assert re.search(rf"{row['successes']}/{row['runs']}", shown.stdout)


def test_show_of_a_glob_matching_two_archives_shows_each(vcb_run, tmp_path):
    """`show runs/fast_switch-*.h5` once two archives match (issue #22): each in the order
    given; --format json, a list; a bad one among them prints nothing but the error."""
    other = tmp_path / "fs.h5"
    r = invoke("run", CONFIGS / "fast_switch.toml", "--out", other, "--quiet")
    assert r.exit_code == 0, r.output
    r = invoke("show", vcb_run, other)
    assert r.exit_code == 0, r.output
    assert r.stdout.index("case vcb") < r.stdout.index("case fast_switch")
    docs = json.loads(invoke("show", vcb_run, other, "--format", "json").stdout)
    assert [d["case"]["kind"] for d in docs] == ["vcb", "fast_switch"]
    assert isinstance(json.loads(invoke("show", other, "--format", "json").stdout), dict)
    (tmp_path / "bad.h5").write_text("x")
    r = invoke("show", vcb_run, tmp_path / "bad.h5")
    assert r.exit_code == 2 and r.stdout == "" and r.stderr.startswith("error: ")


# ---- issue #34: at_limit per requirement and the expected yield, for every case kind

EVERY_KIND = {  # a cheap run of each case kind: (config, overrides)
    "vcb": ("vcb.toml", SMALL_VCB),
    "fast_switch": ("fast_switch.toml", []),
    "opening_spring": ("opening_spring_pp3.toml", []),
    "emb_cam": ("emb.toml", ["--set", "solver.iterations=10", "--set", "solver.particles=10",
                             "--repeats", "1"]),
    "vcb_identify": ("vcb_identify.toml", ["--set", "solver.generations=5", "--set",
                                           "solver.population=10", "--repeats", "1"]),
}


@pytest.mark.parametrize("kind", list(EVERY_KIND))
def test_show_json_has_at_limit_and_expected_yield_for_every_kind(kind, tmp_path):
    """``run`` stores the estimate (300 draws of the case's default tolerances from
    SeedSequence(run.seed)); ``show`` reads it: value within its Wilson interval, and
    per requirement the yield ``camopt tolerance --samples 300 --seed <run.seed>`` gives
    on the same draws. A case without tolerances for its inputs says why."""
    config, extra = EVERY_KIND[kind]
    out = tmp_path / "run.h5"
    r = invoke("run", CONFIGS / config, "--out", out, "--quiet", *extra)
    assert r.exit_code == 0, r.output
    assert archive.load_run(out).expected_yield  # stored by run, not estimated by show
    doc = json.loads(invoke("show", out, "--format", "json").stdout)
    assert all(isinstance(q["at_limit"], bool) for q in doc["requirements"])
    assert doc["at_limit"] == [q["name"] for q in doc["requirements"] if q["at_limit"]]
    y = doc["expected_yield"]
    assert {"value", "low", "high"} <= set(y) and doc["next"].startswith("next: ")
    if y["value"] is None:
        assert y["reason"] and kind == "vcb_identify"
        return
    assert 0 <= y["low"] <= y["value"] <= y["high"] <= 1 and y["samples"] == 300
    seed = archive.load_run(out).run["seed"]
    tol = json.loads(invoke("tolerance", out, "--samples", 300, "--seed", seed,
                            "--format", "json").stdout)
    assert {q["name"]: q["yield"] for q in tol["requirements"]} == {
        q["name"]: q["yield"] for q in y["requirements"]}  # the same parts, bit for bit


def test_an_archive_older_than_the_estimate_is_estimated_at_show_time():
    from tests.core.test_record import OLD_RUN

    doc = json.loads(invoke("show", OLD_RUN, "--format", "json").stdout)
    assert doc["expected_yield"].get("estimated") == "at show time"
    assert "at_limit" in doc["requirements"][0]


def test_the_reference_label_comes_from_the_case_file(vcb_run, tmp_path):
    """The reference design is named by the case file's reference_label (the paper's
    vendor unless a maker names its own breaker), in show's table and its JSON; an
    archive whose case lacks the field (written before it) keeps the case's name."""
    view = archive.load_run(vcb_run)
    assert report.reference(view).label == "reference: vendor, Sec 2.3 and Table 2"
    mine = dataclasses.replace(view, case={**view.case,
                                           "reference_label": "my breaker, drawing 4711"})
    assert report.reference(mine).label == "reference: my breaker, drawing 4711"
    old = dataclasses.replace(view, case={k: v for k, v in view.case.items()
                                          if k != "reference_label"})
    assert report.reference(old).label == "reference: vendor, Sec 2.3 and Table 2"
    out = tmp_path / "mine.h5"
    r = invoke("run", CONFIGS / "vcb.toml", "--out", out, "--quiet", "--set",
               'case.reference_label="my breaker"', "--set", "solver.generations=2",
               "--set", "solver.population=10")
    assert r.exit_code == 0, r.output
    shown = invoke("show", out, columns=120)
    assert "reference: my breaker" in shown.stdout
    assert "vendor, Sec 2.3" not in shown.stdout
