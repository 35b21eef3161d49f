"""Plots (figure objects: axes, labels) and exports, for every case."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive, plots
from camopt.cli import app
from camopt.driver import execute
from camopt.plotting import close
from tests.conftest import CONFIGS, DATA
from tests.helpers import load

runner = CliRunner()
CASES = {
    "vcb": ("vcb.toml", ["run.repeats=3", "solver.generations=30"],
            {"cam_profile": ("x (mm)", "y (mm)"),
             "pressure_angle": ("cam angle theta_c (deg)", "pressure angle (deg)"),
             "curvature": ("cam angle theta_c (deg)", "radius of curvature (mm)"),
             "tau_max": ("cam angle theta_c (deg)", "tau_max (MPa)"),
             "forces": ("rod travel s1 (mm)", "force (N)")}),
    "emb_cam": ("emb.toml", ["solver.iterations=40", "solver.particles=30"],
                {"torque_force": ("cam rotation angle phi (rad)", "drive torque (N m)"),
                 "profile": ("x (mm)", "y (mm)")}),
    "opening_spring": ("opening_spring_pp3.toml", [],
                       {"theta_thetadot": ("follower angle theta (rad)",
                                           "angular velocity theta' (rad/s)")}),
    "fast_switch": ("fast_switch.toml", [],
                    {"closure_time": ("number of coils", "closure time (ms)")}),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def case_run(request, tmp_path_factory):
    name = request.param
    file, overrides, _ = CASES[name]
    path = tmp_path_factory.mktemp(name) / f"{name}.h5"
    archive.write_run(execute(load(CONFIGS / file, *overrides)), path)
    return name, path


def test_case_figures_have_labelled_axes(case_run):
    name, path = case_run
    figs = plots.run_figures(archive.load_run(path))
    assert "convergence" in figs
    conv = figs["convergence"].axes[0]
    assert conv.get_xlabel().startswith("iteration") and conv.get_ylabel().startswith("best")
    for fig_name, (xlabel, ylabel) in CASES[name][2].items():
        ax = figs[fig_name].axes[0]
        assert ax.get_xlabel() == xlabel and ax.get_ylabel() == ylabel, fig_name
        assert ax.get_title() and ax.lines, fig_name
    for fig in figs.values():
        close(fig)


def test_paper_values_are_marked(tmp_path, reported):
    """The paper's values appear on the figures where the paper gives them (Table 1 of
    Clauss & Papalambros, from the test data, not from the plotting code)."""
    fs = CASES["fast_switch"]
    run = archive.load_run(archive.write_run(execute(load(CONFIGS / fs[0])),
                                             tmp_path / "fs.h5"))
    ax = plots.run_figures(run)["closure_time"].axes[0]
    labels = [line.get_label() for line in ax.lines]
    assert "paper, Table 1" in labels
    paper = next(line for line in ax.lines if line.get_label() == "paper, Table 1")
    table1 = np.loadtxt(DATA / "fast_switch_table1.csv", delimiter=",", skiprows=2)
    assert np.allclose(paper.get_ydata(), table1[:, -1] * 1e3, atol=0.006)


def test_plot_cli_writes_pngs(case_run, tmp_path):
    name, path = case_run
    r = runner.invoke(app, ["plot", str(path), "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    pngs = sorted(tmp_path.glob("*.png"))
    assert len(pngs) >= 1 + len(CASES[name][2])
    for png in pngs:
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 5000


def test_export_csv_and_json(case_run, tmp_path):
    name, path = case_run
    assert runner.invoke(app, ["export", str(path), "--out", str(tmp_path)]).exit_code == 0
    rows = list(csv.reader((tmp_path / f"{path.stem}-summary.csv").open()))
    assert rows[0] == ["section", "name", "value"] and len(rows) > 3
    assert runner.invoke(app, ["export", str(path), "--format", "json", "--out",
                               str(tmp_path)]).exit_code == 0
    doc = json.loads((tmp_path / f"{path.stem}.json").read_text())
    assert {"case", "best", "analysis"} <= set(doc)
    if name in ("vcb", "emb_cam"):
        pts = np.loadtxt(tmp_path / f"{path.stem}-cam-profile.txt", delimiter=",")
        assert pts.shape[1] == 3 and len(pts) > 100 and np.all(pts[:, 2] == 0)


def test_sweep_convergence_has_one_line_per_point(tmp_path):
    out = tmp_path / "s.h5"
    r = runner.invoke(app, ["sweep", str(CONFIGS / "vcb.toml"), "--out", str(out), "--quiet",
                            "--seeds", "0:2", "--grid", "solver.population=10,20",
                            "--set", "solver.generations=10", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    from camopt.archive.sweeps import load_sweep

    fig = plots.sweep_figures(*load_sweep(out))["convergence"]
    assert len(fig.axes[0].lines) == 2
