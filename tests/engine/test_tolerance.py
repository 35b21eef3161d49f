"""Tolerance analysis (camopt/engine/tolerance.py) and ``camopt tolerance`` on a VCB run with
its closing dynamics (configs/reference/vcb_velocity_paper.toml, small budget)."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.cases import build_problem
from camopt.cli import app
from camopt.core.plotting import readable
from camopt.engine.driver import validate
from camopt.engine.tolerance import Distribution, analyse, average_ranks, parse_vary
from camopt.reporting.tolerance_figures import figures
from tests.conftest import CONFIGS, VELOCITY_PAPER

runner = CliRunner()
VARY = ["--vary", "kc1_n_per_mm=±5%", "--vary", "case.l1_mm=±0.1"]


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def vcb_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("tol") / "vcb.h5"
    r = invoke("run", VELOCITY_PAPER, "--out", path, "--quiet", "--repeats", 1,
               "--set", "solver.generations=120", "--set", "solver.population=40")
    assert r.exit_code == 0, r.output
    return path


def _json(run, *extra):
    r = invoke("tolerance", run, "--samples", 2000, "--seed", 0, *extra, "--format", "json")
    assert r.exit_code == 0, r.output
    return r.stdout


def test_yield_percentiles_sensitivity_and_same_seed_same_json(vcb_run):
    text = _json(vcb_run, *VARY)
    doc = json.loads(text)
    assert doc["samples"] == 2000 and 0.0 <= doc["yield"] <= 1.0
    spread = [m for m, p in doc["metrics"].items()
              if None not in p.values() and p["p05"] < p["p95"]]
    assert len(spread) >= 3
    assert all(p["p05"] <= p["p50"] <= p["p95"] for p in doc["metrics"].values()
               if None not in p.values())
    for name in ("closing_velocity_avg_m_s", "tau_max_mpa", "rod_travel_mm"):
        assert name in spread
        assert {s["input"] for s in doc["sensitivity"][name]} == {"kc1_n_per_mm",
                                                                   "case.l1_mm"}
    # the spring rate drives the speed and the stress; the fixed link the rod travel
    assert doc["sensitivity"]["closing_velocity_avg_m_s"][0]["input"] == "kc1_n_per_mm"
    assert doc["sensitivity"]["tau_max_mpa"][0]["spearman"] > 0.99
    assert doc["sensitivity"]["rod_travel_mm"][0]["input"] == "case.l1_mm"
    assert _json(vcb_run, *VARY) == text
    assert _json(vcb_run, *VARY, "--seed", 1) != text


def test_zero_tolerance_collapses_every_metric_to_nominal_in_each_form(vcb_run):
    """At ±0 % every sample is the nominal design judged in its model form: the samples
    of form f are the design's metrics under f's sets alone (bit for bit), each form's
    yield is the design's feasibility in it, and a metric the forms do not touch is the
    nominal row's (judged under every form at once)."""
    from camopt.engine.tolerance import problem_of

    run = archive.load_run(vcb_run)
    t = analyse(run, [parse_vary("r", "kc1_n_per_mm=±0%")], 40, 0)
    problem = problem_of(run)
    forms = problem.variants()
    assert t.variants == forms == ("efficiency_coulomb", "coulomb")
    assert list(t.variant[:4]) == [0, 1, 0, 1]  # stratified: each form every other draw
    x0 = problem.from_display(run.best.x)
    each = problem.describe_variants(np.tile(x0, (len(forms), 1)), {}, np.arange(len(forms)))
    expected = t.metric_columns(each)
    for name, column in t.metric_columns(t.samples).items():
        # to rounding: numpy's kernels differ with the row count
        np.testing.assert_allclose(column, expected[name][t.variant], rtol=1e-12, atol=1e-12,
                                   err_msg=name)
    for name in ("tau_max_mpa", "rod_travel_mm", "surplus_work_j"):
        np.testing.assert_allclose(t.metric_columns(t.samples)[name],
                                   t.summary["nominal"][name], rtol=1e-12)
    per_form = t.summary["per_form"]
    assert [r["form"] for r in per_form] == list(forms)
    assert [r["samples"] for r in per_form] == [20, 20]
    assert [r["yield"] for r in per_form] == [float(ok) for ok in each.feasible]
    assert t.summary["yield"] == pytest.approx(np.mean([r["yield"] for r in per_form]))
    # the nominal row is judged under every form: it passes only if every form passes
    assert t.summary["nominal_feasible"] == bool(each.feasible.all())


def test_nominal_is_the_run_optimum(vcb_run):
    """The analysis' nominal row reproduces the archived optimum's metrics (1e-12)."""
    run = archive.load_run(vcb_run)
    t = analyse(run, [parse_vary("r", "kc1_n_per_mm=±1%")], 10, 0)
    for name in ("closing_velocity_avg_m_s", "tau_max_mpa", "rod_travel_mm"):
        assert t.summary["nominal"][name] == pytest.approx(run.best.metrics[name], rel=1e-12)


def test_draws_uniform_within_and_normal_with_sigma_a_third(vcb_run):
    run = archive.load_run(vcb_run)
    varies = [parse_vary("r", "kc1_n_per_mm=±5%"), parse_vary("r", "case.l1_mm=±0.1")]
    nominal = np.array([run.best.x["kc1_n_per_mm"], run.case["l1_mm"]])
    half = np.array([0.05 * nominal[0], 0.1])
    u = analyse(run, varies, 4000, 7).inputs
    assert np.all(np.abs(u - nominal) <= half)
    np.testing.assert_allclose(np.ptp(u, axis=0), 2 * half, rtol=2e-3)
    n = analyse(run, varies, 4000, 7, Distribution.normal).inputs
    # sigma = X / 3; standard error of a sample std from 4000 draws ~1.1 %: 5 % is 4.5 se
    np.testing.assert_allclose(n.std(axis=0), half / 3, rtol=0.05)


def test_case_field_per_sample_matches_a_problem_built_with_that_field(vcb_run):
    """The rod travel (kinematics only) with l1 varied per row equals that of Problems
    built from configs with those l1 values, to 1e-12; varying nothing changes nothing."""
    run = archive.load_run(vcb_run)
    data = {"case": dict(run.case), "solver": run.solver, "run": run.run}
    problem = build_problem(validate(data, "r").case)
    x = problem.from_display(run.best.x)
    l1 = run.case["l1_mm"] + np.array([-0.3, 0.0, 0.2])
    X = np.tile(x, (3, 1))
    ev = problem.describe_with(X, {"l1_mm": l1})
    for i, value in enumerate(l1):
        alone = build_problem(validate({**data, "case": {**data["case"], "l1_mm": value}},
                                       "r").case)
        ref = alone.describe(x[None, :]).extras["rod_travel_mm"][0]
        assert ev.extras["rod_travel_mm"][i] == pytest.approx(ref, rel=1e-12, abs=0)
    same, tiled = problem.describe(X), problem.describe_with(X, {})
    for k in same.extras:  # the config's linkage tiled per row vs broadcast: to rounding
        a, b = np.asarray(tiled.extras[k]), np.asarray(same.extras[k])
        if a.dtype.kind == "f":
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=k)
        else:
            np.testing.assert_array_equal(a, b, err_msg=k)


@pytest.mark.parametrize(("vary", "message"), [
    ("speed=±5%", "--vary: speed: not a design variable of the run"),
    ("case.rf_mm=±0.1", "--vary: case.rf_mm: case 'vcb' cannot vary it per design"),
    ("kc1_n_per_mm=5%", "--vary: 'kc1_n_per_mm=5%': expected NAME=±X%"),
    ("kc1_n_per_mm=±-5%", "--vary: 'kc1_n_per_mm=±-5%': expected"),
])
def test_bad_vary_is_one_line_exit_2(vcb_run, vary, message):
    r = invoke("tolerance", vcb_run, "--vary", vary)
    assert r.exit_code == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {vcb_run}: ") and message in lines[0]


def test_out_writes_samples_that_show_report_and_plot_read(vcb_run, tmp_path):
    """A tolerance archive can be handed over: ``show`` prints what ``tolerance`` did
    (its JSON is the stored summary), ``report`` writes its page with the figures drawn
    from the stored samples, ``plot`` its PNGs; ``compare``, which needs runs, refuses."""
    out = tmp_path / "tol.h5"
    r = invoke("tolerance", vcb_run, "--samples", 300, *VARY, "--out", out)
    assert r.exit_code == 0, r.output
    with h5py.File(out, "r") as f:
        assert f.attrs["archive_kind"] == "tolerance"
        assert f["inputs/case.l1_mm"].shape == (300,) and f["feasible"].shape == (300,)
        assert json.loads(f.attrs["summary"])["samples"] == 300
        assert float(np.mean(f["feasible"][()])) == json.loads(f.attrs["summary"])["yield"]
    with h5py.File(out, "r") as f:
        stored = json.loads(f.attrs["summary"])
    r = invoke("show", out)
    assert r.exit_code == 0, r.output
    assert f"yield (feasible share): {stored['yield']:.1%}" in r.stdout
    shown = json.loads(invoke("show", out, "--format", "json").stdout)
    assert shown["yield"] == stored["yield"] and shown["vary"] == stored["vary"]
    page = tmp_path / "tol.html"
    r = invoke("report", out, "--out", page)
    assert r.exit_code == 0, r.output
    html = page.read_text()
    assert f"yield (feasible share) {100 * stored['yield']:.1f} % over 300 samples" in html
    assert html.count('<img src="data:image/svg+xml;base64,') == 3
    r = invoke("plot", out, "--out", tmp_path / "p")
    assert r.exit_code == 0 and len(r.stdout.split()) == 3
    r = invoke("compare", out, vcb_run)
    assert r.exit_code == 2 and r.stderr.startswith("error: ")
    assert invoke("tolerance", vcb_run, *VARY, "--out", out).exit_code == 2  # exists


def test_figures_mark_limits_and_swings(vcb_run, tmp_path):
    run = archive.load_run(vcb_run)
    t = analyse(run, [parse_vary("r", "kc1_n_per_mm=±5%"),
                      parse_vary("r", "case.l1_mm=±0.1")], 500, 0)
    figs = figures(t, "closing_velocity_avg_m_s")
    assert set(figs) == {"constraints", "metrics", "tornado"}
    # requirements in their units, each limit a line at its value
    by_label = {ax.get_xlabel(): ax for ax in figs["constraints"].axes if ax.get_visible()}
    travel = by_label[readable("rod_travel_mm")]
    limits = sorted(line.get_xdata()[0] for line in travel.lines
                    if line.get_label().endswith("limit"))
    tol = run.case["rod_travel_tolerance_mm"]
    assert limits == pytest.approx([18.0 - tol, 18.0 + tol])
    ax = figs["tornado"].axes[0]
    # both inputs drawn with their tolerance (which swings most depends on the design)
    assert {t.get_text() for t in ax.get_yticklabels()} == {"kc1_n_per_mm ±5%",
                                                            "case.l1_mm ±0.1"}
    assert ax.get_xlabel() == readable("closing_velocity_avg_m_s")
    r = invoke("tolerance", vcb_run, "--samples", 200, *VARY, "--plot", tmp_path / "p",
               "--tornado", "tau_max_mpa")
    assert r.exit_code == 0 and len(list((tmp_path / "p").glob("*.png"))) == 3


def test_default_tolerances_are_the_cases_documented_ones(vcb_run):
    """Without --vary the case's CaseSpec.tolerances apply (those for this run's inputs);
    every built-in case's defaults parse."""
    doc = json.loads(invoke("tolerance", vcb_run, "--samples", 100, "--format", "json").stdout)
    assert [v["input"] for v in doc["vary"]] == [
        "kc1_n_per_mm", "kc2_n_per_mm", "case.l1_mm", "case.l3_mm", "case.l4_mm",
        "case.l5_mm", "case.theta1_deg",
        # the parts beyond the closing springs' rates (issue #33): free lengths, the
        # opening and contact springs, friction and efficiency, the cam profile
        "case.kc1_precompression_mm", "case.kc2_precompression_mm",
        "case.opening_k_n_per_mm", "case.wipe_k_n_per_mm", "case.cam_friction_nm",
        "case.efficiency", "case.cam_profile_error_mm"]
    assert [r["form"] for r in doc["per_form"]] == doc["forms"] == ["efficiency_coulomb",
                                                                    "coulomb"]
    assert sum(r["samples"] for r in doc["per_form"]) == 100
    # the default class "standard": ungraded closing springs, ±10 % on rate (issue #33)
    assert doc["vary"][0]["tolerance"] == 10.0 and doc["vary"][0]["unit"] == "%"
    assert doc["tolerance_class"] == "standard"
    assert doc["yield_low"] <= doc["yield"] <= doc["yield_high"]
    graded = json.loads(invoke("tolerance", vcb_run, "--samples", 100, "--class", "graded",
                               "--format", "json").stdout)
    assert graded["vary"][0]["tolerance"] == 5.0 and graded["tolerance_class"] == "graded"
    from camopt.cases import cases

    for spec in cases().values():
        for cls in spec.class_names():
            for name, tol in spec.tolerances_of(cls).items():
                v = parse_vary("spec", f"{name}={tol}")
                assert v.tolerance > 0 and v.name == name


def test_yield_per_requirement_raw_metrics_and_json_only_on_stdout(vcb_run, tmp_path):
    """Each requirement's yield is the share of samples within its limit (counted here
    from the samples); the objective's percentiles are over feasible samples (never the
    penalty); the tornado defaults to the quantity that limits the yield; with --format
    json stdout parses and the figures' paths are on stderr."""
    run = archive.load_run(vcb_run)
    t = analyse(run, [parse_vary("r", "kc1_n_per_mm=±5%"),
                      parse_vary("r", "case.l1_mm=±0.1")], 400, 0)
    by = {q["quantity"]: q for q in t.summary["requirements"]}
    travel = t.samples.extras["rod_travel_mm"]
    tol = run.case["rod_travel_tolerance_mm"]
    # judged at its printed resolution: half a unit of the 6th digit of 18.2 mm
    assert by["rod_travel_mm"]["yield"] == np.mean(np.abs(travel - 18.0) <= tol + 0.5e-4)
    assert by["feasible"]["yield"] == t.summary["yield"]
    limiting = min((q for q in t.summary["requirements"] if q["quantity"] != "feasible"),
                   key=lambda q: q["yield"])
    assert t.summary["limiting"] == limiting["quantity"]
    f = t.samples.f[t.samples.feasible]
    p95 = t.summary["metrics"][t.objective_name]["p95"]
    if f.size:
        assert p95 == pytest.approx(np.percentile(f, 95)) and p95 <= f.max()
    ax = figures(t)["tornado"].axes[0]
    assert ax.get_xlabel() == readable(t.summary["limiting"])
    r = runner.invoke(app, ["tolerance", str(vcb_run), "--samples", "100", *VARY, "--format",
                            "json", "--plot", str(tmp_path / "p")])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["requirements"]
    assert r.stderr.count(".png") == 3


# --- Spearman ranks computed once per column (issue #36) -------------------------------
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from scipy import stats  # noqa: E402

from camopt.engine.tolerance import spearman_columns  # noqa: E402


def _pairwise(inputs, values):
    """scipy.stats.spearmanr per (input, metric) pair, NaN rows dropped: the reference."""
    out = []
    for j in range(inputs.shape[1]):
        ok = ~np.isnan(values)
        a, b = inputs[ok, j], values[ok]
        if a.size < 3 or np.all(a == a[0]) or np.all(b == b[0]):
            out.append(None)
        else:
            out.append(float(stats.spearmanr(a, b).statistic))
    return out


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 60), k=st.integers(1, 4),
       ties=st.booleans(), nan_share=st.sampled_from([0.0, 0.2, 0.9]))
def test_spearman_columns_equal_scipy_per_pair(seed, n, k, ties, nan_share):
    """Ranks once per column give scipy's spearmanr of each pair to 1e-12: with ties
    (rounded draws), NaN rows in some metrics, constant inputs and metrics."""
    rng = np.random.default_rng(seed)
    inputs = rng.normal(size=(n, k))
    if ties:
        inputs = np.round(inputs, 1)
    inputs[:, -1] = 0.5 if k > 1 else inputs[:, -1]  # an input at +-0
    a = inputs[:, 0] ** 3 + rng.normal(scale=0.3, size=n)
    columns = {"a": a, "b": np.where(rng.random(n) < nan_share, np.nan, a - inputs[:, -1]),
               "c": np.where(rng.random(n) < nan_share, np.nan, rng.normal(size=n)),
               "const": np.full(n, 2.0), "empty": np.full(n, np.nan)}
    got = spearman_columns(inputs, columns)
    for name, values in columns.items():
        want = _pairwise(inputs, values)
        assert [w is None for w in want] == [g is None for g in got[name]], name
        assert np.allclose([g for g in got[name] if g is not None],
                           [w for w in want if w is not None], rtol=0, atol=1e-12), name


def test_progress_bar_on_a_terminal_only(vcb_run, monkeypatch):
    """``tolerance`` draws a bar on stderr when it is a terminal, and not with --quiet
    (issue #36); the JSON on stdout is the same either way."""
    import io

    from rich.console import Console

    from camopt.cli import console

    def run(*extra):
        buffer = io.StringIO()
        monkeypatch.setattr(console, "err", Console(file=buffer, force_terminal=True,
                                                    width=100))
        r = invoke("tolerance", vcb_run, "--samples", 600, "--seed", 0, *VARY, *extra,
                   "--format", "json")
        assert r.exit_code == 0, r.output
        return r.stdout, buffer.getvalue()

    shown, bar = run()
    quiet, nothing = run("--quiet")
    assert "tolerance samples" in bar and "605/605" in bar  # nominal + 2 x 2 ends + 600
    assert nothing == ""
    assert json.loads(shown) == json.loads(quiet)


def test_average_ranks_are_scipy_rankdata():
    """The ranks Spearman's rho reads (no scipy.stats import at show time) equal
    scipy.stats.rankdata's average ranks exactly, ties included."""
    from scipy.stats import rankdata

    rng = np.random.default_rng(0)
    for a in (rng.random(1000), rng.integers(0, 10, 1000).astype(float), np.array([1.0]),
              np.full(3, 2.0), rng.integers(0, 3, 17) * 0.5):
        assert np.array_equal(average_ranks(a), rankdata(a))


# --- 10^6 samples under 1 GiB (issue #36) ----------------------------------------------
from camopt.engine import tolerance as tolerance_module  # noqa: E402


def _exact_rho(x, y):
    """Spearman's rho of two columns from scipy's average ranks, its sums in Python's
    exact integers (twice the centred ranks are whole), the ratio rounded once."""
    import math
    import operator

    from scipy.stats import rankdata

    rx, ry = ((2 * rankdata(v) - (len(v) + 1)).astype(np.int64).tolist() for v in (x, y))
    p = sum(map(operator.mul, rx, ry))
    return math.copysign(math.sqrt(p * p / (sum(map(operator.mul, rx, rx))
                                            * sum(map(operator.mul, ry, ry)))), p)


def test_spearman_sums_are_exact_and_rho_rounded_once():
    """rho is the exact ratio of the rank sums rounded once, to the bit, over 100,000
    rows with ties and NaN-dropped rows (sums from scipy's ranks in Python integers)."""
    rng = np.random.default_rng(21)
    n = 100_000
    inputs = np.column_stack([rng.uniform(size=n), np.round(rng.normal(size=n), 1)])
    a = inputs @ [1.0, 0.3] + rng.normal(scale=0.2, size=n)
    b = np.where(rng.random(n) < 0.3, np.nan, np.round(a, 2))
    got = spearman_columns(inputs, {"a": a, "b": b})
    for name, values in (("a", a), ("b", b)):
        keep = ~np.isnan(values)
        assert got[name] == [_exact_rho(inputs[keep, j], values[keep]) for j in range(2)]


def test_a_perfect_rank_correlation_over_a_million_rows_is_exactly_one():
    """At 10^6 rows (``camopt tolerance``'s most) a metric that rises or falls with an
    input alone has rho exactly +-1: float sums of the rank products, past 2^53, read
    1.0000000000007 (review 74 found 0.9999999999987 in the CLI)."""
    x = np.random.default_rng(22).uniform(size=(10**6, 2))
    got = spearman_columns(x, {"up": 2 * x[:, 0] + 1, "down": -np.exp(x[:, 1])})
    assert got["up"][0] == 1.0 and got["down"][1] == -1.0


def test_spearman_refuses_more_rows_than_its_sums_hold_exactly(monkeypatch):
    """Past :data:`EXACT_RANK_ROWS` an int64 sum could overflow: refused, not wrapped."""
    monkeypatch.setattr(tolerance_module, "EXACT_RANK_ROWS", 10)
    rng = np.random.default_rng(1)
    with pytest.raises(ValueError, match="exact for at most 10"):
        spearman_columns(rng.normal(size=(11, 2)), {"a": rng.normal(size=11)})
    assert spearman_columns(rng.normal(size=(10, 2)), {"a": rng.normal(size=10)})["a"]


def test_the_exact_rank_sums_stay_below_int64_up_to_the_limit():
    """What :data:`EXACT_RANK_ROWS` rests on: the largest sum, of the squared doubled
    ranks of 1..n without ties, is (n^3 - n) / 3, below 2^63 at n = 2^21 and not at 2^22;
    doubled ranks are the integers -(n - 1), -(n - 3), ..., n - 1."""
    from camopt.engine.tolerance import EXACT_RANK_ROWS, doubled_ranks

    def largest(n):
        return (n**3 - n) // 3

    assert largest(EXACT_RANK_ROWS) < 2**63 <= largest(2 * EXACT_RANK_ROWS)
    r = doubled_ranks(np.array([0.5, -1.0, 7.0, 2.0]))
    assert r.dtype == np.int64 and r.tolist() == [-1, -3, 3, 1]
    assert int(r @ r) == largest(4)
    tied = doubled_ranks(np.array([3.0, 1.0, 3.0, 2.0, 3.0]))
    assert tied.tolist() == [2, -4, 2, -2, 2]


def test_inputs_are_the_draws_and_the_ends_rows_of_one_array(vcb_run):
    """The samples' inputs are :func:`draw_inputs` of the seed, bit for bit, held as a
    view of the one array of every evaluated row (no stacked copy)."""
    from camopt.engine.tolerance import draw_inputs, nominal_inputs, problem_of

    run = archive.load_run(vcb_run)
    varies = [parse_vary("t", v) for v in ("kc1_n_per_mm=±5%", "case.l1_mm=±0.1")]
    t = analyse(run, varies, 50, 9)
    nominal = nominal_inputs(run, problem_of(run), varies)
    half = np.array([v.half_width(x) for v, x in zip(varies, nominal)])
    assert np.array_equal(t.inputs, draw_inputs(9, 50, nominal, half, Distribution.uniform))
    assert t.inputs.base is not None and t.inputs.base.shape == (1 + 2 * 2 + 50, 2)
    assert np.array_equal(t.nominal_inputs, nominal)


def test_constant_metrics_are_held_once_and_read_the_same():
    """A metric with one value on every row, to the bit (NaN included), is one value
    broadcast to the rows; a metric that differs anywhere, if only in the sign of a
    zero, keeps its rows."""
    from camopt.core.problem import Evaluation
    from camopt.engine.tolerance import shared_constants

    varying = np.array([1.0, 2.0, 1.0])
    extras = {"coefficient": np.full(3, 0.25), "absent": np.full(3, np.nan),
              "zeros": np.array([0.0, -0.0, 0.0]), "varying": varying,
              "flag": np.ones(3, dtype=bool)}
    ev = shared_constants(Evaluation(np.zeros(3), np.zeros((3, 1)), extras))
    for name in ("coefficient", "absent", "flag"):
        column = ev.extras[name]
        assert column.strides == (0,) and not column.flags.writeable, name
        assert np.array_equal(column, extras[name], equal_nan=name == "absent"), name
    assert np.signbit(ev.extras["zeros"]).tolist() == [False, True, False]
    assert ev.extras["varying"] is varying


# --- review 74: what the tests above left unpinned ---------------------------------------
def test_spearman_at_5000_rows_is_scipy_s():
    """At 5,000 rows the sums of rank products (~10^10) are past float32's 2^24: rho is
    still scipy's to 1e-12 (review 74: products summed in float32 were off by ~1e-7),
    with ties and NaN-dropped rows."""
    rng = np.random.default_rng(17)
    n = 5000
    inputs = rng.uniform(-1, 1, (n, 3))
    inputs[:, 1] = np.round(inputs[:, 1], 1)
    a = inputs @ [1.0, -0.5, 0.2] + rng.normal(scale=0.3, size=n)
    columns = {"a": a, "b": np.where(rng.random(n) < 0.3, np.nan, np.round(a, 1))}
    got = spearman_columns(inputs, columns)
    for name, values in columns.items():
        assert np.allclose(got[name], _pairwise(inputs, values), rtol=0, atol=1e-12), name


def test_a_shared_constant_holds_its_own_value_not_the_column():
    """The broadcast constant is a copy of one value: it keeps no reference to the
    column's n rows (else the memory it is there to save stays allocated)."""
    from camopt.core.problem import Evaluation
    from camopt.engine.tolerance import shared_constants

    column = np.full(1000, 0.25)
    ev = shared_constants(Evaluation(np.zeros(1000), np.zeros((1000, 1)), {"c": column}))
    assert ev.extras["c"].strides == (0,) and not np.shares_memory(ev.extras["c"], column)


def test_analyse_holds_the_constant_metrics_once(vcb_run):
    """analyse applies :func:`shared_constants`: every metric that is one value on every
    evaluated row, to the bit, is a stride-0 column of the samples (the VCB has some)."""
    run = archive.load_run(vcb_run)
    varies = [parse_vary("t", v) for v in ("kc1_n_per_mm=±5%", "case.l1_mm=±0.1")]
    t = analyse(run, varies, 50, 9)
    constant = []
    for name, values in t.samples.extras.items():
        rows = np.concatenate([np.asarray(e.extras[name], dtype=float)
                               for e in (t.nominal, t.swings, t.samples)])
        if np.all(rows.view("u8") == rows.view("u8")[0]):
            constant.append(name)
            assert values.strides == (0,), name
    assert constant


def test_the_expected_yield_command_pastes_as_one_path(vcb_run, tmp_path):
    """The command the expected yield names (stored, shown in JSON and HTML) quotes the
    run's path for a shell: a space or ';' in it stays one argument."""
    import shlex
    import shutil

    from camopt.engine.tolerance import expected_yield

    path = tmp_path / "sp ace;x.h5"
    shutil.copy(vcb_run, path)
    command = expected_yield(archive.load_run(path), samples=20)["command"]
    assert shlex.split(command)[:3] == ["camopt", "tolerance", str(path)]


def test_one_at_a_time_ends_are_each_computed_at_its_own_end(fast_run):
    """The tornado's rows pinned at the engine: input j's 'low' swing is every metric of
    the run's design with input j at nominal - X (the others nominal), its 'high' at
    nominal + X, each against one row evaluated on its own (rtol 1e-12: the same model
    on a row alone vs in a batch). A '+X' computed at -X (issue #49's surviving mutant)
    swaps them, and the inputs here move the objective unevenly enough that it shows."""
    from camopt.engine.tolerance import (
        default_varies,
        evaluate_inputs,
        nominal_inputs,
        problem_of,
    )

    run = archive.load_run(fast_run)
    problem = problem_of(run)
    varies = default_varies(run)
    t = analyse(run, varies, 2, 0)
    nominal = nominal_inputs(run, problem, varies)
    half = np.array([v.half_width(x) for v, x in zip(varies, nominal)])
    swings = t.metric_columns(t.swings)
    uneven = 0
    for j, v in enumerate(varies):
        for row, sign in ((2 * j, -1.0), (2 * j + 1, 1.0)):
            inputs = nominal.copy()
            inputs[j] += sign * half[j]
            ev, _ = evaluate_inputs(run, problem, varies, inputs[None, :], describe=True,
                                    variant=np.array([-1]))
            alone = t.metric_columns(ev)
            for name, column in swings.items():
                np.testing.assert_allclose(column[row], alone[name][0], rtol=1e-12,
                                           atol=1e-300, err_msg=f"{v.name} {sign:+} {name}")
        low, high = swings[t.objective_name][2 * j], swings[t.objective_name][2 * j + 1]
        uneven += bool(abs(high - low) > 1e-6 * abs(high))
        by_input = {r["input"]: r for r in t.summary["one_at_a_time"][t.objective_name]}
        assert np.array_equal([by_input[v.name]["low"], by_input[v.name]["high"]], [low, high],
                              equal_nan=True)
    assert uneven >= 2  # the test can tell the ends apart


def test_the_expected_yield_counts_draws_meeting_every_requirement_inside_range(
        fast_run, monkeypatch):
    """The expected yield is the share of draws that meet every requirement of the run
    and whose inputs lie inside their physical ranges (docs/tolerance.md). With stand-ins
    (every other draw meets the requirements; the first 10 of 60 draws outside their
    range) it is exactly 25 / 60, and its interval Clopper-Pearson's on 25 of 60."""
    from camopt.core import requirements
    from camopt.core.stats import success_rate
    from camopt.engine import tolerance

    run = archive.load_run(fast_run)
    real, seen = tolerance.analyse, []

    def outside_first(*args, **kwargs):
        t = real(*args, **kwargs)
        t.outside = np.arange(len(t.inputs)) < 10
        seen.append(t)
        return t

    monkeypatch.setattr(tolerance, "analyse", outside_first)
    monkeypatch.setattr(requirements, "all_pass",
                        lambda reqs, columns: np.arange(60) % 2 == 0)
    y = tolerance.expected_yield(run, samples=60)
    assert len(seen) == 1 and y["samples"] == 60
    assert y["value"] == 25 / 60  # 30 meet them, 5 of those outside their range
    rate = success_rate(25, 60)
    assert (y["low"], y["high"]) == (rate["ci_low"], rate["ci_high"])


def test_a_robust_run_short_of_its_target_keeps_its_expected_yield(tmp_path):
    """A robust run whose best design misses its yield target is infeasible as a run, but
    each of its breakers passes or fails on its own: the expected yield counts the draws
    that pass (the robust check does the same), it is not zeroed by the run's verdict. The
    fast switch's shipped robust case at a 99.9 % target, a short search (seed 1: 99.8 %
    of 10,000 draws)."""
    from camopt.engine.tolerance import expected_yield

    out = tmp_path / "short.h5"
    r = CliRunner().invoke(app, ["run", str(CONFIGS / "fast_switch_robust.toml"), "--out",
                                 str(out), "--quiet", "--repeats", "1",
                                 "--set", "robust.yield_target=0.999",
                                 "--set", "solver.generations=60"])
    assert r.exit_code == 0, r.output
    run = archive.load_run(out)
    assert not run.best.feasible  # the target is out of reach ...
    checked = run.robust_check["robust"]["yield"]
    assert checked > 0.5  # ... of a design most breakers pass
    y = expected_yield(run, samples=200)
    feasible = analyse(run, tolerance_module.default_varies(run), 200, y["seed"])
    assert 0.5 < y["value"] <= feasible.samples.feasible.mean()  # each draw as it passes
