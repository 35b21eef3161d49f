"""Robust design (camopt/engine/robust.py): the yield column against an independent count of the
samples, chunking, reproducibility, draws outside the physical range, bad [robust] input.
The fast switch (configs/fast_switch_de.toml) keeps it fast: a closed-form model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camopt.config.models import RobustSection
from camopt.core.capabilities import HasFamily, HasResiduals, Repairable, Stochastic
from camopt.core.problem import FEASIBILITY_TOL, deb_best
from camopt.engine import robust
from camopt.engine.driver import execute, prepare
from camopt.errors import ConfigError
from tests.conftest import CONFIGS
from tests.helpers import load

SMALL = ("solver.population=12", "solver.generations=6", "run.repeats=1")


def _problem(*overrides):
    cfg = load(CONFIGS / "fast_switch_de.toml", "robust.samples=8", *overrides)
    problem, _ = prepare(cfg)
    assert isinstance(problem, robust.RobustProblem)
    return problem


def _near_optimum(problem, n=6, seed=3):
    """Designs around fast_switch_robust.toml's optimum (18.3 ms, near its limits R4 and
    R14), 0.3 % apart."""
    x = problem.from_display({"coils": 17, "sf_mm": 98.78, "sud_mm": 170.41, "s0_mm": 46.48,
                              "r3_mm": 256.32, "r2_mm": 54.98})
    rng = np.random.default_rng(seed)
    X = x * (1 + 0.003 * rng.standard_normal((n, len(x))))
    X[:, 0] = 17
    return X


def test_yield_column_counts_the_samples():
    """g[:, -1] <= 0 exactly when at least ceil(target S) samples pass, and the estimate is
    the share of passing samples, both against a loop of one-design evaluations of the
    same draws (an independent count)."""
    problem = _problem("robust.screen=false", "robust.yield_target=0.75",
                       'robust.vary={sud_mm="±1", s0_mm="±0.1", r2_mm="±0.05"}')
    problem.new_generation()
    X = _near_optimum(problem)
    ev = problem.evaluate(X)
    base, plan = problem.base, problem.plan
    need = math.ceil(0.75 * 8)
    for i, x in enumerate(X):
        passed = 0
        for u in problem.unit:
            xs = x.copy()
            for j, v in enumerate(plan.varies):
                k = base.names.index(v.name)
                xs[k] = x[k] + u[j] * v.tolerance / base.variables[k].scale
            one = base.evaluate(xs[None, :])
            passed += bool(one.feasible[0])
        assert ev.extras["yield"][i] == pytest.approx(passed / 8, abs=1e-12)
        assert (ev.g[i, -1] <= FEASIBILITY_TOL) == (passed >= need)
    assert np.isfinite(ev.extras["yield"]).all()
    assert ((ev.extras["yield"] > 0) & (ev.extras["yield"] < 1)).any()  # not all-or-nothing


def test_fast_switch_spring_fields_per_row():
    """describe_with of the wire diameter: row by row the same as a config with that
    diameter (the rate of R13 scales with d^4, Eq 21)."""
    from camopt.cases import build_problem

    base = load(CONFIGS / "fast_switch_de.toml")
    problem = build_problem(base.case)
    X = np.tile(_near_optimum(problem, n=1), (2, 1))
    ev = problem.describe_with(X, {"wire_diameter_mm": np.array([2.0, 2.02])})
    thick = build_problem(load(CONFIGS / "fast_switch_de.toml",
                               "case.wire_diameter_mm=2.02").case).describe(X[:1])
    np.testing.assert_allclose(ev.g[1], thick.g[0], rtol=1e-12, atol=1e-12)  # (n,) vs scalar d
    assert ev.extras["k_n_per_m"][1] / ev.extras["k_n_per_m"][0] == pytest.approx(1.01**4)


def test_chunks_change_nothing():
    a, b = _problem("robust.chunk_rows=5"), _problem()
    for p in (a, b):
        p.reseed(np.random.SeedSequence(1))
        p.new_generation()
    X = _near_optimum(a)
    ea, eb = a.evaluate(X), b.evaluate(X)
    # the same draws in chunks of 5 rows vs whole: to rounding (SIMD kernels by length)
    np.testing.assert_allclose(ea.g, eb.g, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ea.f, eb.f, rtol=1e-12, atol=1e-12)


def test_repeat_draws_keep_one_set_until_the_next_repeat():
    """draws = "repeat": the first generation's draws stay for every later generation of
    the repeat (the search sees one function), and a new repeat draws again from its own
    seed, the same first set as draws = "generation" from that seed."""
    fixed, fresh = _problem("robust.draws=repeat"), _problem()
    for p in (fixed, fresh):
        p.reseed(np.random.SeedSequence(5))
        p.new_generation()
    first = fixed.unit.copy()
    np.testing.assert_array_equal(first, fresh.unit)
    for p in (fixed, fresh):
        p.new_generation()
    np.testing.assert_array_equal(fixed.unit, first)
    assert not np.array_equal(fresh.unit, first)
    fixed.reseed(np.random.SeedSequence(6))
    fixed.new_generation()
    assert not np.array_equal(fixed.unit, first)


def test_margin_objective_is_the_yield_column():
    """objective = "margin": the objective is the yield column itself (the worst sample's
    worst normalised constraint at the target's order statistic), named yield_margin, so
    that of two designs that both meet the target the one with more margin ranks first;
    constraints and the yield estimate are those of the same draws under any objective."""
    margin = _problem("robust.screen=false", "robust.objective=margin")
    mean = _problem("robust.screen=false", "robust.objective=mean")
    assert margin.objective_name == "yield_margin" != mean.objective_name
    for p in (margin, mean):
        p.reseed(np.random.SeedSequence(4))
        p.new_generation()
    X = _near_optimum(margin)
    a, b = margin.evaluate(X), mean.evaluate(X)
    np.testing.assert_array_equal(a.f, a.g[:, -1])
    np.testing.assert_array_equal(a.g, b.g)
    np.testing.assert_array_equal(a.extras["yield"], b.extras["yield"])
    assert not np.array_equal(a.f, b.f)


def test_objective_statistics():
    f = np.array([[1.0, 3.0, np.inf, 2.0], [np.nan, np.nan, np.nan, np.nan]])
    np.testing.assert_allclose(robust.statistic(f, "mean", 0.5), [2.0, np.inf])
    q = robust.statistic(f, "quantile", 0.5)
    assert q[0] == 3.0 and q[1] == np.inf  # the higher middle of 1, 2, 3, inf
    assert robust.order_index(0.95, 20) == 18 and robust.order_index(0.95, 16) == 15
    assert robust.order_index(1.0, 8) == 7


def test_run_is_reproducible_and_checked():
    cfg = load(CONFIGS / "fast_switch_de.toml", *SMALL, "robust.samples=8",
               "robust.check_samples=200")
    heard: list[tuple[int, int]] = []
    a, b = execute(cfg), execute(cfg, check_progress=lambda d, n: heard.append((d, n)))
    np.testing.assert_array_equal(a.best.x, b.best.x)
    assert a.robust_check == b.robust_check  # the progress callback changes nothing
    designs = 1 + ("nominal" in a.robust_check)  # the check's rows: designs x draws
    assert heard and heard[-1] == (designs * 200, designs * 200)
    assert [d for d, _ in heard] == sorted(d for d, _ in heard)
    check = a.robust_check["robust"]
    assert check["samples"] == 200 and 0 <= check["yield_low"] <= check["yield"] <= 1
    # the stored keys and their order (scripts read the archive's JSON): the quantile's
    # key names the config's quantile (0.9 by default)
    assert list(check) == ["samples", "yield", "yield_low", "yield_high", "confidence",
                           "case_objective", "objective_nominal", "objective_mean",
                           "objective_q90", "nominal_feasible", "margins"]
    assert a.problem.constraint_names[-1] == "yield" and len(a.best.g) == a.problem.n_constr


def test_draws_outside_the_physical_range_fail():
    """r2 ±200 mm from ~55 mm: about a third of the draws give a negative crank; each such
    sample counts as failed, so the yield never exceeds the share of draws inside."""
    problem = _problem("robust.screen=false", 'robust.vary={r2_mm="±200"}')
    problem.new_generation()
    X = _near_optimum(problem, n=3)
    s = robust.sample(problem.base, problem.plan, X, problem.unit)
    r2 = X[:, 5, None] * 1e3 + problem.unit[None, :, 0] * 200
    inside = r2 > 0
    assert (~inside).any()
    assert not s.feasible[~inside].any()
    assert np.isnan(s.f[~inside]).all()


@pytest.mark.parametrize("override, what", [
    ('robust.vary={speed="±1"}', "speed: not a design variable of the case"),
    ('robust.vary={coils="±1"}', "coils: an integer variable"),
    ('robust.vary={"case.m2_kg"="±1%"}', "cannot vary it per design"),
    ('robust.vary={sf_mm="1mm"}', "expected NAME=±X%"),
])
def test_bad_vary_names_robust_vary(override, what):
    cfg = load(CONFIGS / "fast_switch_de.toml", override)
    with pytest.raises(ConfigError) as err:
        prepare(cfg)
    assert err.value.where == "robust.vary" and what in err.value.what


def test_the_confident_index_is_the_least_count_whose_lower_bound_reaches_the_target():
    """The order statistic that decides "yield >= target" is the least passing count whose
    interval's lower bound (:func:`camopt.core.stats.share_interval`) reaches the target."""
    from camopt.core.stats import share_interval

    i = robust.confident_index(0.95, 4000, 0.95)
    low, _ = share_interval([i, i + 1], 4000, 0.95)
    assert low[1] >= 0.95 > low[0]
    assert robust.confident_index(0.95, 32, 0.95) == 31  # 32 of 32 is not enough: all


@pytest.mark.parametrize("name", ["vcb_velocity_robust", "emb_robust", "fast_switch_robust"])
def test_shipped_robust_configs_validate(name):
    problem, _ = prepare(load(CONFIGS / f"{name}.toml"))
    assert isinstance(problem, robust.RobustProblem) and problem.plan.varies


def test_show_and_report_give_the_robust_check(tmp_path):
    """A robust archive: show prints the check beside the nominal best seen, its JSON adds
    ``robust`` (settings and check), the HTML report has the table."""
    from typer.testing import CliRunner

    from camopt import archive
    from camopt.cli import app
    from camopt.reporting import report

    out = tmp_path / "r.h5"
    r = CliRunner().invoke(app, ["run", str(CONFIGS / "fast_switch_robust.toml"), "--out",
                                 str(out), "--quiet", "--set", "solver.generations=8",
                                 "--set", "solver.population=12", "--set",
                                 "robust.check_samples=200", "--set", "robust.samples=8"])
    assert r.exit_code == 0, r.output
    view = archive.load_run(out)
    doc = report.show(view).to_json()
    check = doc["robust"]["check"]["robust"]
    assert doc["robust"]["settings"]["samples"] == 8 and check["samples"] == 200
    assert 0 <= check["yield_low"] <= check["yield"] <= check["yield_high"] <= 1
    shown = CliRunner().invoke(app, ["show", str(out)])
    assert shown.exit_code == 0 and "robust check (200 fresh draws" in shown.output
    summary = report.robust_summary(view)
    assert summary is not None and summary.rows[0].name == "yield"
    html = CliRunner().invoke(app, ["report", str(out), "--out", str(tmp_path / "r.html")])
    assert html.exit_code == 0, html.output
    assert 'id="robust-check"' in (tmp_path / "r.html").read_text()


def test_margin_run_names_the_case_objective_in_its_check(tmp_path):
    """A run that minimised yield_margin still reports the case's objective (its nominal,
    mean and quantile values) under the case's name: in the check's table, and in the
    summary beside the reference's objective, which is never set beside the margin."""
    from typer.testing import CliRunner

    from camopt import archive
    from camopt.cli import app
    from camopt.reporting import report

    out = tmp_path / "m.h5"
    r = CliRunner().invoke(app, ["run", str(CONFIGS / "fast_switch_robust.toml"), "--out",
                                 str(out), "--quiet", "--set", "solver.generations=8",
                                 "--set", "solver.population=12", "--set",
                                 "robust.check_samples=200", "--set", "robust.samples=8",
                                 "--set", "robust.objective=margin"])
    assert r.exit_code == 0, r.output
    view = archive.load_run(out)
    assert view.objective_name == "yield_margin"
    check = view.robust_check["robust"]
    assert check["case_objective"] == "closure_time_ms"
    assert check["objective_nominal"] > 0  # a closure time, not a margin
    robust = report.robust_summary(view)
    assert robust is not None
    names = [row.name for row in robust.rows]
    assert "closure_time_ms nominal" in names and not any("yield_margin" in n for n in names)
    rows = {row.name: row for row in report.summary(view).rows}
    assert rows["yield_margin"].optimum == view.best.objective
    assert rows["yield_margin"].reference is None
    assert rows["closure_time_ms"].optimum == pytest.approx(check["objective_nominal"],
                                                           rel=1e-12)
    assert rows["closure_time_ms"].reference > 0  # the reference design's closure time


@pytest.mark.parametrize("config, capability", [
    ("emb.toml", Repairable), ("fast_switch_de.toml", HasFamily),
    ("opening_spring_pp3.toml", HasResiduals), ("vcb.toml", None)])
def test_a_robust_problem_offers_its_cases_capability_by_a_declared_class(config, capability):
    """wrap picks a class written in robust.py (none built at run time with type()): it is
    Stochastic, offers the case's capability and forwards it to the case."""
    from camopt.cases import build_problem

    cfg = load(CONFIGS / config)
    base = build_problem(cfg.case)
    plan = robust.Plan(RobustSection(), (), (), {})
    problem = robust.wrap(base, plan)
    assert isinstance(problem, Stochastic)
    assert type(problem).__module__ == "camopt.engine.robust"
    assert type(problem) in (robust.RobustProblem, *robust.FORWARDED.values())
    if capability is None:
        assert type(problem) is robust.RobustProblem
        return
    assert isinstance(problem, capability)
    if capability is HasFamily:
        np.testing.assert_array_equal(problem.family(), base.family())
    elif capability is Repairable:
        assert problem.repair_schedule() == base.repair_schedule()
    else:
        X = (base.lower + base.upper)[None, :] / 2
        np.testing.assert_array_equal(problem.residuals(X), base.residuals(X))


def test_a_screened_candidate_ranks_behind_every_sampled_one():
    """With screen, a candidate whose nominal design breaks a constraint is not sampled:
    its columns are its nominal constraints and its yield column its nominal worst
    constraint plus SCREENED (1e6, engine/robust.py's docstring), so by Deb's rules it
    ranks behind a nominally feasible candidate however badly that one's draws fail."""
    problem = _problem("robust.screen=true")
    problem.new_generation()
    X = np.vstack([_near_optimum(problem, n=4), problem.sample(np.random.default_rng(5), 40)])
    X[:, 0] = np.rint(X[:, 0])
    nominal = problem.base.evaluate(X)
    out = np.flatnonzero(~nominal.feasible)
    sampled = np.flatnonzero(nominal.feasible)
    assert out.size and sampled.size
    ev = problem.evaluate(X)
    g = np.where(np.isnan(nominal.g), np.inf, nominal.g)  # NaN: infinitely violated
    worst = np.where(np.isfinite(nominal.f), g.max(axis=1), np.inf)  # no objective: worst
    np.testing.assert_array_equal(ev.g[out, -1],
                                  robust.SCREENED + np.maximum(worst[out], 0.0))
    np.testing.assert_array_equal(ev.g[out, :-1], g[out])
    assert np.isnan(ev.extras["yield"][out]).all()
    assert ev.violation[out].min() > ev.violation[sampled][
        np.isfinite(ev.violation[sampled])].max()
    assert deb_best(ev.f, ev.violation) in sampled


def test_a_case_with_two_forwarded_capabilities_is_refused_as_bad_input():
    """No declared class offers repair and a family together: bad input naming both,
    never a class made up at run time."""
    from camopt.core.problem import Problem

    class Both(Problem, Repairable, HasFamily):
        def repair(self, X, rng, probability):
            return X

        def repair_schedule(self):
            return {}

        def family(self):
            return np.zeros((0, 0))

    with pytest.raises(ConfigError, match=r"case\.toml: robust: a case offering repair, "
                       "family together"):
        robust.wrap(Both(), robust.Plan(RobustSection(), (), (), {}), "case.toml")


def test_racing_stages():
    assert robust.stages(32, 8) == [slice(0, 8), slice(8, 16), slice(16, 32)]
    assert robust.stages(32, 0) == robust.stages(32, 32) == [slice(0, 32)]
    assert robust.stages(100, 10)[-1] == slice(80, 100)


@pytest.mark.parametrize("search_yield", [0.99, 0.75])
def test_racing_decides_as_every_draw_does(search_yield):
    """Racing (robust.race) stops a candidate once it has failed more draws than the order
    statistic allows: every candidate's feasibility is the same as with all draws at once,
    a candidate that ran every draw gets the same numbers, and fewer draws are evaluated."""
    common = ("robust.screen=false", "robust.samples=32", f"robust.search_yield={search_yield}",
              'robust.vary={sud_mm="±1", s0_mm="±0.1", r2_mm="±0.05"}')
    raced, full = _problem(*common, "robust.race=4"), _problem(*common, "robust.race=0")
    for p in (raced, full):
        p.reseed(np.random.SeedSequence(5))
        p.new_generation()
    X = _near_optimum(raced, n=12)
    a, b = raced.evaluate(X), full.evaluate(X)
    np.testing.assert_array_equal(a.feasible, b.feasible)
    np.testing.assert_array_equal(a.g[:, -1] <= FEASIBILITY_TOL, b.g[:, -1] <= FEASIBILITY_TOL)
    ran_all = np.isclose(a.extras["yield"], b.extras["yield"], rtol=0, atol=0)
    np.testing.assert_array_equal(a.g[a.feasible], b.g[b.feasible])
    assert (a.g[~a.feasible, -1] > 0).all()
    assert full.draws_evaluated == 12 * 32 > raced.draws_evaluated
    assert ran_all.any()


class _TwoForms:
    """A one-variable case with two model variants of known yield: the part x (drawn
    ±20 % around the design) must stay below 1.0 in variant "a" and below 0.8 in "b";
    every variant at once (-1) asks both (0.8)."""

    @staticmethod
    def build():
        from camopt.core.capabilities import HasVariants
        from camopt.core.problem import Evaluation, Problem, Variable

        class TwoForms(Problem, HasVariants):
            variables = (Variable("x", 0.1, 2.0),)
            constraint_names = ("c",)

            def evaluate(self, X):
                return self.describe_variants(X, {}, np.full(len(X), -1))

            def variants(self):
                return ("a", "b")

            def describe_variants(self, X, fields, variant, detail=True):
                limit = np.where(np.asarray(variant) == 0, 1.0, 0.8)
                return Evaluation(X[:, 0].copy(), (X[:, 0] / limit - 1)[:, None])

        return TwoForms()


def test_draws_over_model_variants_give_the_yield_over_both_and_per_form():
    """Draw j is judged in variant j mod 2: x = 0.9 ± 20 % passes variant a with
    probability (1 - 0.72) / 0.36 = 7/9 and b with 2/9, so the yield over both is 1/2; the
    check reports each form's with its interval. The nominal design fails variant b (so
    the case's own verdict), but meets a: the screen samples it."""
    from camopt.core.variation import Vary

    base = _TwoForms.build()
    spec = RobustSection(samples=32, check_samples=4000, search_yield=0.5)
    plan = robust.Plan(spec, (Vary("x", 20.0, True),), ((0.0, True, math.inf),), {},
                       robust.variants_of(base))
    assert plan.variants == ("a", "b")
    problem = robust.RobustProblem(base, plan)
    problem.reseed(np.random.SeedSequence(8))
    problem.new_generation()
    ev = problem.evaluate(np.array([[0.9]]))
    assert ev.g[0, -1] < robust.SCREENED  # sampled although nominally infeasible
    assert ev.extras["yield"][0] == pytest.approx(0.5, abs=0.2)
    (checked,) = robust.check(problem, [np.array([0.9])], seed=1)
    forms = checked["per_form"]
    assert [f["form"] for f in forms] == ["a", "b"] and [f["samples"] for f in forms] == [
        2000, 2000]
    for f, true in zip(forms, (7 / 9, 2 / 9)):
        assert f["yield_low"] <= true <= f["yield_high"]
    assert checked["yield"] == pytest.approx(np.mean([f["yield"] for f in forms]))
    assert checked["yield_low"] <= 0.5 <= checked["yield_high"]


def test_the_per_variant_screen_in_a_mixed_batch():
    """In one batch: x = 0.7 meets both variants (sampled), 1.1 and 1.3 meet neither (not
    sampled: their yield column is SCREENED plus the nearest variant's violation, a's:
    0.1 and 0.3), 0.9 meets a alone (sampled). The screen is asked only of the nominally
    infeasible, and each gets its own variants' verdicts."""
    from camopt.core.variation import Vary

    base = _TwoForms.build()
    spec = RobustSection(samples=8, check_samples=100, search_yield=0.5)
    plan = robust.Plan(spec, (Vary("x", 1.0, True),), ((0.0, True, math.inf),), {},
                       robust.variants_of(base))
    problem = robust.RobustProblem(base, plan)
    problem.reseed(np.random.SeedSequence(3))
    problem.new_generation()
    ev = problem.evaluate(np.array([[1.1], [0.7], [1.3], [0.9]]))
    sampled = ev.g[:, -1] < robust.SCREENED
    np.testing.assert_array_equal(sampled, [False, True, False, True])
    np.testing.assert_allclose(ev.g[[0, 2], -1] - robust.SCREENED, [0.1, 0.3], rtol=1e-9)
    assert np.isnan(ev.extras["yield"][[0, 2]]).all()


def test_designs_evaluated_again_reuse_their_nominal_rows():
    """A design of the previous evaluation (a DE parent evaluated again on a new
    generation's draws) is not evaluated at nominal again, nor screened per variant: only
    the new designs are, and every column is what a problem without the previous call
    gives (rtol 0: the nominal evaluation reads no draw)."""
    from camopt.core.variation import Vary

    base = _TwoForms.build()
    asked: list[int] = []
    real = base.describe_variants

    def counted(X, fields, variant, detail=True):
        asked.append(len(X))
        return real(X, fields, variant, detail)
    base.describe_variants = counted
    spec = RobustSection(samples=8, check_samples=100, search_yield=0.5)
    plan = robust.Plan(spec, (Vary("x", 1.0, True),), ((0.0, True, math.inf),), {},
                       robust.variants_of(base))

    def fresh():
        p = robust.RobustProblem(base, plan)
        p.reseed(np.random.SeedSequence(3))
        p.new_generation()
        return p
    first, again = np.array([[1.1], [0.7], [1.3]]), np.array([[0.9], [1.3], [0.7], [1.2]])
    problem = fresh()
    problem.evaluate(first)
    asked.clear()
    ev = problem.evaluate(again)
    nominal = [n for n in asked if n in (2, 4)]  # the draws' calls hold 8 rows a design
    # 0.9 and 1.2 at nominal, then both (refused at nominal) screened in a, then in b
    assert nominal == [2, 2, 2]
    reference = fresh().evaluate(again)
    np.testing.assert_array_equal(ev.f, reference.f)
    np.testing.assert_array_equal(ev.g, reference.g)
    for k in ev.extras:
        np.testing.assert_array_equal(ev.extras[k], reference.extras[k])


def test_a_finalist_that_fails_new_draws_leaves():
    """A design kept as a finalist for passing one generation's draws leaves when it is
    evaluated again (a DE parent) and fails; one that passes again stays with its new
    score; a failing design that was never a finalist changes nothing."""
    from camopt.core.problem import Evaluation

    problem = _problem()
    X = _near_optimum(problem, n=3)
    passing = Evaluation(np.array([3.0, 2.0, 1.0]), np.full((3, 1), -1.0))
    problem._keep_finalists(X, passing)
    assert len(problem.finalists[0]) == 3
    other = problem.sample(np.random.default_rng(1), 1)
    again = Evaluation(np.array([5.0, 0.5, 7.0]), np.array([[1.0], [-1.0], [1.0]]))
    problem._keep_finalists(np.vstack([X[0], X[1], other[0]]), again)
    kept, scores = problem.finalists
    np.testing.assert_array_equal(kept, X[[1, 2]][np.argsort([0.5, 1.0])])
    np.testing.assert_array_equal(scores, [0.5, 1.0])
