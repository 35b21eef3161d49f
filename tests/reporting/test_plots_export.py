"""Plots (figure objects: axes, labels) and exports, for every case."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from camopt.core.plotting import close
from camopt.engine.driver import execute
from camopt.reporting import plots
from tests.conftest import CONFIGS, DATA
from tests.helpers import load

runner = CliRunner()
CASES = {
    "vcb": ("vcb.toml", ["run.repeats=3", "solver.generations=30"],
            {"cam_profile": ("x (mm)", "y (mm)"),
             "pressure_angle": ("cam angle theta_c (deg)", "pressure angle (deg)"),
             "curvature": ("cam angle theta_c (deg)", "radius of curvature (mm)"),
             "tau_max": ("cam angle theta_c (deg)", "tau_max (MPa)"),
             "forces": ("rod travel s1 (mm)", "force (N)"),
             "cam_torque": ("cam angle theta_c (deg)", "torque (N m)")}),
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
    # formats write distinct files: json beside csv needs no --force; csv again does
    again = ["export", str(path), "--format", "json", "--out", str(tmp_path)]
    assert runner.invoke(app, again).exit_code == 0
    refused = runner.invoke(app, ["export", str(path), "--out", str(tmp_path)])
    assert refused.exit_code == 2 and "pass --force" in refused.output
    doc = json.loads((tmp_path / f"{path.stem}.json").read_text())
    assert {"case", "best", "analysis"} <= set(doc)
    if name in ("vcb", "emb_cam"):  # cases with cam profiles: point files with the DXF
        assert runner.invoke(app, ["export", str(path), "--format", "dxf", "--out",
                                   str(tmp_path)]).exit_code == 0
        pts = np.loadtxt(tmp_path / f"{path.stem}-cam-profile.txt", delimiter=",")
        assert pts.shape[1] == 3 and len(pts) > 100 and np.all(pts[:, 2] == 0)


def test_sweep_convergence_has_one_line_per_point(tmp_path):
    out = tmp_path / "s.h5"
    r = runner.invoke(app, ["sweep", str(CONFIGS / "vcb.toml"), "--out", str(out), "--quiet",
                            "--seeds", "0:2", "--grid", "solver.population=10,20",
                            "--set", "solver.generations=10", "--jobs", "1"])
    assert r.exit_code == 0, r.output
    from camopt.archive.sweeps import load_sweep

    spec, results = load_sweep(out)
    fig = plots.sweep_figures(spec, results)["convergence"]
    ax = fig.axes[0]
    lines = [ln for ln in ax.lines if not ln.get_label().startswith("target")]
    assert len(lines) == 2
    # by function evaluations: population 20 spends twice the evaluations per generation
    assert ax.get_xlabel() == "function evaluations" and ax.get_ylabel() == "best objective (J)"
    ends = {ln.get_label().split(" ")[0]: ln.get_xdata()[-1] for ln in lines}
    for label, end in ends.items():
        cells = [r for (p, _), r in results.items()
                 if spec.points()[p] and label.endswith(str(spec.points()[p]["solver.population"]))]
        assert end == pytest.approx(np.median([c.history["nfev"][-1] for c in cells]))
    assert ends["solver.population=20"] > 1.5 * ends["solver.population=10"]


def test_every_figure_is_labelled_with_ticks_and_legends(case_run):
    """No empty figure; both axes labelled; ticks; a legend wherever two labelled series
    share an axes."""
    _, path = case_run
    figs = plots.run_figures(archive.load_run(path))
    for name, fig in figs.items():
        # a twin axes shares the first one's x, stacked axes the bottom one's
        assert any(ax.get_xlabel() for ax in fig.axes), name
        for ax in fig.axes:
            if not ax.get_visible():
                continue
            assert ax.get_ylabel(), name
            assert len(ax.get_xticks()) and len(ax.get_yticks()), name
            drawn = ax.lines + ax.collections
            assert drawn, f"{name}: empty axes"
            labelled = [a for a in drawn if not a.get_label().startswith("_")]
            if len(labelled) >= 2 and ax is fig.axes[0]:
                assert fig.axes[0].get_legend() is not None, name
        close(fig)


def test_convergence_draws_the_target_and_never_an_empty_axes(tmp_path):
    run = tmp_path / "t.h5"
    archive.write_run(execute(load(CONFIGS / "fast_switch_de.toml", "run.repeats=2",
                                   "solver.generations=20", "run.target=18.5")), run)
    ax = plots.run_figures(archive.load_run(run))["convergence"].axes[0]
    (target,) = [ln for ln in ax.lines if ln.get_label().startswith("target")]
    assert target.get_ydata()[0] == pytest.approx(18.5)
    infeasible = tmp_path / "pp4.h5"  # no start converges: objective inf in every iteration
    archive.write_run(execute(load(CONFIGS / "opening_spring_pp4.toml")), infeasible)
    view = archive.load_run(infeasible)
    assert not np.isfinite(view.histories()[0]).any()
    ax = plots.run_figures(view)["convergence"].axes[0]
    assert ax.get_ylabel() == "best constraint violation"
    assert np.isfinite(ax.lines[0].get_ydata()).all()


def test_convergence_band_of_iterations_with_no_feasible_design_is_nan_without_a_warning():
    """Repeats that found no feasible design in their first iterations (objective inf):
    those iterations' band is NaN, with no numpy 'All-NaN slice' warning (the report of
    such an archive printed one); where some repeats are finite, the band is those
    repeats' percentiles (computed here with np.percentile on the finite values only;
    rtol 1e-12: the same interpolation, another code path)."""
    import warnings

    inf = np.inf
    curves = [np.array([inf, inf, 5.0, 3.0]), np.array([inf, 9.0, 4.0]),
              np.array([inf, inf, inf, 2.0, 1.0])]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mid, low, high = plots._band(curves)
        fig = plots.convergence({"runs": curves}, "objective_j")
    close(fig)
    assert np.isnan([mid[0], low[0], high[0]]).all()
    held = [np.array([inf, inf, 5, 3, 3]), np.array([inf, 9, 4, 4, 4]),
            np.array([inf, inf, inf, 2, 1])]  # shorter curves hold their end
    for i in range(1, 5):
        finite = [h[i] for h in held if np.isfinite(h[i])]
        np.testing.assert_allclose([mid[i], low[i], high[i]],
                                   np.percentile(finite, [50, 25, 75]), rtol=1e-12)


def test_convergence_axis_fits_what_the_data_reach():
    """Best-so-far curves from 1e6 down to 1e-5 on a log axis bounded by them (no symlog
    band of decades never reached); a one-pass solver's single point is drawn as a marker
    inside the axes (the fast switch's figure was empty)."""
    fig = plots.convergence({"runs": [np.array([1e6, 1e2, 1e-3, 1e-5])]}, "objective_j")
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    lo, hi = ax.get_ylim()
    assert 1e-5 / 2 <= lo < 1e-5 and 1e6 < hi <= 2e6
    close(fig)
    fig = plots.convergence({"runs": [np.array([18.9039])]}, "closure_time_ms")
    ax = fig.axes[0]
    (line,) = ax.get_lines()
    assert line.get_marker() == "o" and list(line.get_ydata()) == [18.9039]
    x0, x1 = ax.get_xlim()
    assert x0 < 1 < x1 and ax.get_yscale() == "linear"
    close(fig)


def test_vcb_closing_velocity_figure_reads_like_a_breaker_test(tmp_path):
    """The velocity figure shades the averaging window where the archived contact travel
    crosses 2/3 of the gap (rtol 1e-9: the same interpolation of the stored curve) and
    the contacts touch (read on the rod's curve: the contacts' stays at the gap from the
    node after the touch, which ended the window up to a step, 0.1 %, late), draws the
    requirement band, the touch instant and the average with its band over the
    parameter sets (the archived metrics)."""
    path = tmp_path / "vv.h5"
    archive.write_run(execute(load(CONFIGS / "vcb_velocity.toml", "run.repeats=1",
                                   "solver.generations=30")), path)
    run = archive.load_run(path)
    a, m = run.analysis, run.best.metrics
    gap = run.case["contact_gap_mm"]
    if not np.nanmax(a["dyn_contact_travel_mm"]) >= gap:
        pytest.skip("this short search's design never closes")
    ax = plots.run_figures(run)["closing_velocity"].axes[0]
    spans = {p.get_label(): p.get_x() for p in ax.patches}
    shaded = [p for p in ax.patches if p.get_label().startswith("closing-velocity window")]
    (window,) = shaded
    t, s = a["time_ms"], a["dyn_contact_travel_mm"]
    start = np.interp(2 * gap / 3, s[: np.argmax(s >= gap) + 1],
                      t[: np.argmax(s >= gap) + 1])
    assert window.get_x() == pytest.approx(start, rel=1e-9)
    assert window.get_x() + window.get_width() == pytest.approx(m["touch_time_ms"], rel=1e-3)
    band = [p for p in ax.patches if p.get_label().startswith("required")][0]
    assert (band.get_y(), band.get_y() + band.get_height()) == pytest.approx((0.7, 1.1))
    touch = [line for line in ax.lines if line.get_label() == "contacts touch"]
    assert touch and touch[0].get_xdata()[0] == pytest.approx(m["touch_time_ms"])
    (avg,) = [c for c in ax.containers if c.get_label().startswith("average")]
    assert avg.lines[0].get_ydata()[0] == pytest.approx(m["closing_velocity_avg_m_s"])
    assert spans


def test_plot_overlays_two_runs_of_one_case(case_run, tmp_path):
    """``camopt plot A.h5 B.h5``: every overlay figure holds one line per run, labelled by
    its archive, drawn from that archive's curves; runs of two kinds are bad input."""
    name, path = case_run
    if name != "vcb":
        pytest.skip("the VCB declares overlays (and a closed outline)")
    other = tmp_path / "other.h5"
    archive.write_run(execute(load(CONFIGS / "vcb.toml", "run.repeats=1",
                                   "solver.generations=5", "run.seed=7")), other)
    runs = [archive.load_run(p) for p in (path, other)]
    figs = plots.overlay_figures(runs, [path.stem, "other"])
    assert {"cam-profile", "closing_travel", "closing_velocity", "rod_travel"} <= set(figs)
    travel = figs["rod_travel"].axes[0]
    assert [line.get_label() for line in travel.lines] == [f"A: {path.stem}", "B: other"]
    for fig in figs.values():  # titles name the designs by letter, whole
        title = fig.axes[0].get_title()
        assert title.endswith(": A vs B") and path.stem not in title
    for line, run in zip(travel.lines, runs):
        assert np.array_equal(line.get_ydata(), run.analysis["rod_travel_mm"])
    profile = figs["cam-profile"].axes[0]
    for name in ("cam-profile", "cam-pitch-curve"):
        lines = figs[name].axes[0].lines
        assert len([line for line in lines if line.get_label().endswith("(full turn)")]) == 2
    closed = [line for line in profile.lines if line.get_label().endswith("(full turn)")]
    assert len(closed) == 2
    for line in closed:  # closed: the first point again at the end
        assert (line.get_xdata()[0], line.get_ydata()[0]) == (line.get_xdata()[-1],
                                                              line.get_ydata()[-1])
    for fig in figs.values():
        close(fig)
    r = runner.invoke(app, ["plot", str(path), str(other), "--out", str(tmp_path / "o")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "o" / f"{path.stem}-vs-other-closing_velocity.png").exists()
    fs = tmp_path / "fs.h5"
    assert runner.invoke(app, ["run", str(CONFIGS / "fast_switch.toml"), "--out", str(fs),
                               "--quiet"]).exit_code == 0
    bad = runner.invoke(app, ["plot", str(path), str(fs), "--out", str(tmp_path / "x")])
    assert bad.exit_code == 2 and "cannot be overlaid" in bad.stderr
    assert not (tmp_path / "x").exists()


def test_vcb_motion_diagram_and_full_turn(case_run):
    """The S-V-A-J diagram spans the full turn (360 deg of cam angle, to one step) in four
    rows; its velocity is the displacement's slope (a second code path: the outline's
    phi' against the numerical derivative of its phi, to 1 % of the peak, the sampling's
    error) and its jerk starts and ends at rest on the base circle. The cam profile,
    pressure angle and curvature figures draw the full turn too."""
    name, path = case_run
    if name != "vcb":
        pytest.skip("the VCB has a closed outline")
    from camopt.cases import get_case

    run = archive.load_run(path)
    figs = plots.run_figures(run)
    motion = figs["motion"]
    assert len(motion.axes) == 4
    assert [ax.get_ylabel().split("\n")[0] for ax in motion.axes] == [
        "displacement", "velocity", "acceleration", "jerk"]
    disp, vel = (ax.lines[0] for ax in motion.axes[:2])
    theta = np.radians(disp.get_xdata())
    assert theta[-1] - theta[0] == pytest.approx(2 * np.pi, abs=np.radians(1.5))
    slope = np.gradient(np.radians(disp.get_ydata()), theta)
    assert np.max(np.abs(slope - vel.get_ydata())) < 0.01 * np.max(np.abs(vel.get_ydata()))
    outline = get_case("vcb").cam_outline(run)
    for fig_name in ("pressure_angle", "curvature"):
        xs = np.concatenate([line.get_xdata() for line in figs[fig_name].axes[0].lines
                             if line.get_label() == "optimum, closing the turn"])
        assert xs.max() - xs.min() == pytest.approx(360, abs=1.5)
    profile = figs["cam_profile"].axes[0]
    drawn = [np.column_stack([line.get_xdata(), line.get_ydata()]) for line in profile.lines
             if line.get_label() == "profile, optimum"]
    assert len(drawn) == 1 and len(drawn[0]) == len(outline.theta) + 1
    for fig in figs.values():
        close(fig)
