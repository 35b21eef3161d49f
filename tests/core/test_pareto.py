"""Pareto fronts from archives: ``show``'s ``pareto`` rows, ``compare``'s hypervolume
(pymoo's indicator, one reference point) and ``plot``'s front."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from camopt.core import pareto
from camopt.reporting import plots

runner = CliRunner()
SPHERE = """
[case]
kind = "sphere"
n_var = 2
[solver]
name = "nsga2"
objectives = ["f", "norm"]
population = 20
generations = {generations}
[run]
name = "front"
seed = 1
"""


def _run(folder, generations: int, name: str):
    case = folder / f"{name}.toml"
    case.write_text(SPHERE.format(generations=generations))
    out = folder / f"{name}.h5"
    r = runner.invoke(app, ["run", str(case), "--out", str(out), "--quiet"])
    assert r.exit_code == 0, r.output
    return out


@pytest.fixture(scope="module")
def fronts(tmp_path_factory):
    d = tmp_path_factory.mktemp("fronts")
    return _run(d, 2, "early"), _run(d, 80, "late")


def test_show_json_has_pareto_rows_of_objectives_and_feasible(fronts):
    r = runner.invoke(app, ["show", str(fronts[1]), "--format", "json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert list(doc) == ["verdict", "verdict_sentence", "requirements", "at_limit",
                         "expected_yield", "next", "case", "solver", "best", "repeats",
                         "table", "pareto", "pareto_summary", "verdict_grade",
                         "verdict_headline", "yield_target"]
    assert len(doc["pareto"]) == 20
    assert all(list(row) == ["f", "norm", "feasible"] for row in doc["pareto"])
    assert [row["f"] for row in doc["pareto"]] == [row["f"] for row in doc["table"]]


def test_hypervolume_with_a_common_reference_point(fronts):
    """The converged front scores higher than the two-generation one; by hand: the union
    normalised to [0, 1], reference 1.1, and pymoo's HV of each front agree with compare's."""
    early, late = (archive.load_run(p) for p in fronts)
    hv = pareto.compare_fronts([early, late])
    assert hv["values"][1] > hv["values"][0] > 0
    union = np.concatenate([pareto.front(early), pareto.front(late)])
    lo, hi = union.min(axis=0), union.max(axis=0)
    np.testing.assert_allclose(hv["reference_point"], lo + 1.1 * (hi - lo), rtol=1e-12)
    # 2-D hypervolume by the staircase sum, independent of pymoo
    f = (pareto.front(late) - lo) / (hi - lo)
    f = f[np.argsort(f[:, 0])]
    best_y = np.minimum.accumulate(f[:, 1])
    widths = np.diff(np.r_[f[:, 0], 1.1])
    staircase = np.sum(widths * (1.1 - best_y))
    assert hv["values"][1] == pytest.approx(staircase, rel=1e-9)
    r = runner.invoke(app, ["compare", str(fronts[0]), str(fronts[1])])
    assert r.exit_code == 0 and "hypervolume" in r.stdout and f"{hv['values'][1]:.4f}" in r.stdout


def test_single_objective_runs_have_no_pareto(tmp_path):
    case = tmp_path / "one.toml"
    case.write_text(SPHERE.format(generations=3).replace('objectives = ["f", "norm"]\n', ""))
    r = runner.invoke(app, ["run", str(case), "--out", str(tmp_path / "one.h5"), "--quiet"])
    assert r.exit_code == 0, r.output
    view = archive.load_run(tmp_path / "one.h5")
    assert pareto.rows(view) is None and pareto.compare_fronts([view, view]) is None
    assert "pareto" not in plots.run_figures(view)


def test_plot_draws_the_front(fronts):
    fig = plots.run_figures(archive.load_run(fronts[1]))["pareto"]
    ax = fig.axes[0]
    assert ax.get_xlabel() == "f" and ax.get_ylabel() == "norm"
    assert len(ax.collections[0].get_offsets()) == 20


def test_plot_marks_a_finite_initial_design(fronts):
    from dataclasses import replace

    view = archive.load_run(fronts[1])
    marked = replace(view, best=replace(view.best, metrics={
        **view.best.metrics, "initial_f": 0.1, "initial_norm": 0.2}))
    ax = plots.pareto_front(marked).axes[0]
    labels = [c.get_label() for c in ax.collections]
    assert "reference: initial design" in labels
    pts = ax.collections[labels.index("reference: initial design")].get_offsets()
    np.testing.assert_array_equal(pts, [[0.1, 0.2]])
    unknown = replace(view, best=replace(view.best, metrics={
        **view.best.metrics, "initial_f": float("nan"), "initial_norm": 0.2}))
    ax = plots.pareto_front(unknown).axes[0]
    assert "reference: initial design" not in [c.get_label() for c in ax.collections]


def test_summary_names_objectives_extent_knee_and_the_headline(fronts):
    import dataclasses
    import math

    run = archive.load_run(fronts[1])
    doc = pareto.summary(run)
    assert [o["name"] for o in doc["objectives"]] == ["f", "norm"]
    pts = [(r["f"], r["norm"]) for r in run.table if r["feasible"]]
    assert doc["front_size"] == len(pts)
    assert doc["extent"]["f"] == [min(p[0] for p in pts), max(p[0] for p in pts)]
    # the knee by hand: nearest (0, 0) after scaling each objective to [0, 1]
    lo = [min(p[i] for p in pts) for i in (0, 1)]
    hi = [max(p[i] for p in pts) for i in (0, 1)]
    dist = [math.hypot(*((p[i] - lo[i]) / (hi[i] - lo[i]) for i in (0, 1))) for p in pts]
    knee = pts[dist.index(min(dist))]
    assert (doc["knee"]["f"], doc["knee"]["norm"]) == knee
    # a headline that the front dominates is said to be so
    worse = dataclasses.replace(run, best=dataclasses.replace(run.best, metrics={
        **run.best.metrics, "f": hi[0] + 1, "norm": hi[1] + 1}))
    said = pareto.summary(worse)
    assert said["headline_dominated_by"] == len(pts)
    assert f"dominated by {len(pts)} of the {len(pts)} front designs" in said["headline"]
    shown = runner.invoke(app, ["show", str(fronts[1])], env={"COLUMNS": "80"})
    assert "Pareto front:" in shown.stdout and "knee" in shown.stdout
    assert "headline design below: " in shown.stdout


def test_plot_marks_knee_and_headline_and_says_why_a_marker_is_absent(fronts):
    """The knee at pareto.summary's knee, the headline design at the best's metrics; a
    reference with an unbounded value is named in a note with the reason, not dropped."""
    from dataclasses import replace

    view = archive.load_run(fronts[1])
    doc = pareto.summary(view)
    ax = plots.pareto_front(view).axes[0]
    by = {c.get_label(): c.get_offsets() for c in ax.collections}
    np.testing.assert_array_equal(by["knee"], [[doc["knee"]["f"], doc["knee"]["norm"]]])
    headline = [k for k in by if k.startswith("headline")]
    assert headline == ["headline (best f)"]
    # the objective itself is the run's objective, not among its metrics
    np.testing.assert_array_equal(by[headline[0]], [[view.best.objective,
                                                     view.best.metrics["norm"]]])
    unbounded = replace(view, best=replace(view.best, metrics={
        **view.best.metrics, "initial_f": float("inf"), "initial_norm": 0.2}))
    ax = plots.pareto_front(unbounded).axes[0]
    notes = " ".join(t.get_text() for t in ax.texts)
    assert "reference: initial design not drawn: f unbounded, norm 0.2" in notes
