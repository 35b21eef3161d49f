"""The VCB's factory setting (issue #33): each breaker's closing springs' compression moved
by a nut until the analyser's average closing velocity is the design's reference,
``velocity_setting_m_s`` (:meth:`camopt.cases.vcb.problem.VcbProblem.as_set`)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases import build_problem
from camopt.errors import ConfigError
from tests.conftest import CONFIGS
from tests.helpers import load

CONFIG = CONFIGS / "vcb_velocity_robust.toml"
SET = ("case.velocity_setting_bounds_m_s=[0.75, 1.05]", "case.preload_setting_range_mm=10.0")
"""The shipped robust case with its breakers set (as its comment shows)."""


@pytest.fixture(scope="module")
def config():
    return load(CONFIG, *SET).case


@pytest.fixture(scope="module")
def problem(config):
    return build_problem(config)


@pytest.fixture(scope="module")
def unset(config):
    """The same case without the setting: every breaker as its parts are made."""
    return build_problem(config.model_copy(update={"velocity_setting_bounds_m_s": None}))


@pytest.fixture(scope="module")
def X(problem):
    rng = np.random.default_rng(11)
    X = problem.sample(rng, 256)
    X[:, problem.names.index("release_offset_deg")] = np.deg2rad(19.0)
    return X


def _parts(problem, n, rng, friction=0.1):
    c = problem.config
    fields = {"kc1_precompression_mm": c.kc1_precompression_mm + rng.uniform(-1, 1, n),
              "kc2_precompression_mm": c.kc2_precompression_mm + rng.uniform(-1, 1, n),
              "cam_friction_nm": c.cam_friction_nm * (1 + rng.uniform(-friction, friction, n))}
    return fields


def test_the_setting_is_a_design_variable_with_its_constraint(problem, unset):
    assert problem.names[-1] == "velocity_setting_m_s"
    assert "preload_setting" in problem.constraint_names
    assert "velocity_setting_m_s" not in unset.names
    assert "preload_setting" not in unset.constraint_names


def test_a_set_breaker_closes_at_its_reference_velocity_under_every_set(problem, X):
    """Where the setting passes, the breaker closes at the setting under every parameter
    set of its form, each at its own nut travel (the secant's step leaves < 1e-3 m/s: the
    docstring's claim), in every form and with parts drawn; where it fails, the nut's end
    or a velocity the secant missed says why."""
    rng = np.random.default_rng(3)
    fields = _parts(problem, len(X), rng)
    for form in range(len(problem.forms)):
        ev = problem.describe_variants(X, fields, np.full(len(X), form))
        within = ev.g[:, problem.constraint_names.index("preload_setting")] <= 0
        assert within.sum() >= 5  # the check below is not vacuous
        reach = np.abs(ev.extras["preload_setting_mm"]) > problem.config.preload_setting_range_mm
        low, high = (ev.extras[f"closing_velocity_{e}_m_s"] for e in ("low", "high"))
        with np.errstate(invalid="ignore"):
            missed = ~((np.abs(low / X[:, -1] - 1) <= 0.01) & (np.abs(high / X[:, -1] - 1) <= 0.01))
        np.testing.assert_array_equal(~within, reach | missed)
        for v in (low, high, ev.extras["closing_velocity_avg_m_s"]):
            np.testing.assert_allclose(v[within], X[within, -1], rtol=0, atol=1e-3)


@pytest.mark.parametrize("form", [0, 1])
def test_each_set_moves_both_springs_by_its_own_travel(problem, X, form):
    """One nut: both springs' compressions move by the same travel, each set's own
    needed travel clipped to the nut's reach; the fit's in the parts, the band's other
    sets' in the setting, set-major."""
    rng = np.random.default_rng(5)
    X = X[:64]
    parts = problem.parts(len(X), _parts(problem, len(X), rng))
    set_parts, setting = problem.as_set(X, parts, form)
    k = problem.forms[form].count
    assert setting.needed.shape == (k + 1, len(X))
    reach = problem.config.preload_setting_range_mm * 1e-3
    moved = np.vstack([set_parts.pre, setting.member_pre]) - np.tile(parts.pre, (k + 1, 1))
    np.testing.assert_allclose(moved[:, 0], moved[:, 1], rtol=0, atol=1e-15)
    np.testing.assert_allclose(moved[:, 0], np.clip(setting.needed.ravel(), -reach, reach),
                               rtol=0, atol=1e-15)
    # the sets need different travels: judging them at the fit's would not set them
    assert np.ptp(setting.needed[:, np.isfinite(setting.needed).all(axis=0)], axis=0).max() > 1e-3


@pytest.mark.parametrize("form", [0, 1])
def test_the_band_with_every_sets_own_compressions_is_the_band(unset, X, form):
    """The band's per-set compressions (one row per set and design) give the band the
    shared compressions give when every set has the design's: the same closings."""
    X = X[:32, :-1]
    rng = np.random.default_rng(9)
    pre = np.column_stack([140 + rng.uniform(-1, 1, len(X)), 100 + rng.uniform(-1, 1, len(X))])
    parts = unset.parts(len(X), {"kc1_precompression_mm": pre[:, 0],
                                 "kc2_precompression_mm": pre[:, 1]})
    nominal = unset.motion(X, parts=parts, form=form)
    shared = unset.motion_band(X, nominal, parts=parts, form=form)
    k = unset.forms[form].count
    each = unset.motion_band(X, nominal, parts=parts, form=form,
                             member_pre=np.tile(parts.pre, (k, 1)))
    for name in ("velocity_low", "velocity_high", "kinetic_low", "kinetic_high",
                 "release_ratio_low"):
        np.testing.assert_allclose(getattr(each, name), getattr(shared, name), rtol=1e-12,
                                   err_msg=name)


def test_the_case_verdict_is_each_forms_own_setting_at_its_worst(problem, X):
    """The case's own evaluation of a set breaker is every form set with its own fit, each
    constraint at its worst form; the band's ends over both forms."""
    X = X[:32]
    own = problem.describe(X)
    each = [problem.describe_variants(X, {}, np.full(len(X), f)) for f in (0, 1)]
    np.testing.assert_array_equal(own.g, np.maximum(each[0].g, each[1].g))
    # a form in which a set never closes has no velocity (NaN): nor has the breaker
    np.testing.assert_array_equal(own.extras["closing_velocity_high_m_s"], np.maximum(
        each[0].extras["closing_velocity_high_m_s"], each[1].extras["closing_velocity_high_m_s"]))
    # 3 + 7 sets and each form's link-mass set
    np.testing.assert_array_equal(own.extras["band_sets"], 12.0)
    np.testing.assert_array_equal(own.extras["closing_velocity_avg_m_s"],
                                  each[0].extras["closing_velocity_avg_m_s"])


@pytest.mark.parametrize("scale", [1.2, 3.0])
def test_beyond_the_nuts_reach_the_breaker_fails_and_stays_at_the_end(problem, X, scale):
    """A setting the nut cannot reach (friction 20 % high: a finite travel beyond it;
    three times: a stall at both trials, +inf) fails its constraint, and the breaker is
    judged at the nut's end."""
    x = X[:64].copy()
    x[:, -1] = problem.variables[-1].upper
    # a design the nut sets with room under the fit at nominal parts (the band's heavier
    # links may need more)
    _, nominal = problem.as_set(x, None)
    room = np.isfinite(nominal.needed[0]) & (np.abs(nominal.needed[0]) < 5e-3)
    x = x[np.flatnonzero(room)[:1]]
    assert len(x) == 1
    fields = {"cam_friction_nm": np.array([problem.config.cam_friction_nm * scale])}
    parts = problem.parts(1, fields)
    set_parts, setting = problem.as_set(x, parts)
    reach = problem.config.preload_setting_range_mm * 1e-3
    assert setting.needed[0, 0] > reach
    assert np.isfinite(setting.needed[0, 0]) == (scale < 2)
    base = problem.config.kc1_precompression_mm * 1e-3
    assert set_parts.pre[0, 0] == pytest.approx(base + reach, rel=1e-12)
    ev = problem.describe_with(x, fields)
    assert ev.g[0, problem.constraint_names.index("preload_setting")] > 0
    assert not ev.feasible[0]


def test_a_fourbar_step_refuses_the_setting(config):
    data = load(CONFIGS / "vcb_fourbar.toml").case.model_dump()
    data["velocity_setting_bounds_m_s"] = {"lower": 0.8, "upper": 1.0}
    with pytest.raises((ConfigError, ValueError), match="velocity_setting_bounds_m_s"):
        type(config).model_validate(data)
    bad = {**config.model_dump(), "velocity_setting_bounds_m_s": {"lower": -1.0, "upper": 1.0}}
    with pytest.raises(ValueError, match="velocity_setting_bounds_m_s"):
        type(config).model_validate(bad)


def test_the_unset_case_reports_no_setting(unset, X):
    """No setting: no nut column among the metrics."""
    extras = unset.describe(X[:3, :-1]).extras
    assert "preload_setting_mm" not in extras and "preload_setting_fit_mm" not in extras


def test_step_two_refuses_a_cam_set_at_the_factory(tmp_path):
    """A step-1 archive whose breakers are set (velocity_setting_m_s) is refused by step
    'fourbar', which has no setting: it would judge the cam unset, silently."""
    from camopt import archive
    from camopt.engine.driver import execute

    run = execute(load(CONFIG, *SET, "run.repeats=1", "solver.population=6", "solver.generations=2",
                       "robust.samples=2", "robust.check_samples=100", "robust.finalists=1",
                       "robust.centre_generations=0"))
    step1 = archive.write_run(run, tmp_path / "set.h5")
    with pytest.raises(ConfigError, match="set at the factory"):
        archive.resolve_references(load(CONFIGS / "vcb_fourbar.toml",
                                        f'case.cam_archive="{step1}"'))


def test_a_weak_breaker_the_nut_can_still_set_is_set(config, X):
    """A breaker that stalls as made and at the 2 mm trial (friction twice the case's) is
    not off the secant's line but off the closing: the nut is tried at its end and set
    there, each set at its own travel (~49 mm of a 60 mm reach), the velocity within
    1e-3 m/s. Before, one stalling trial made it "not settable" whatever the reach."""
    problem = build_problem(config.model_copy(update={"preload_setting_range_mm": 60.0}))
    x = X[16:17].copy()
    x[:, -1] = problem.variables[-1].upper
    fields = {"cam_friction_nm": np.array([config.cam_friction_nm * 2.0])}
    parts = problem.parts(1, fields)
    made = problem.describe_variants(x, fields, np.zeros(1, dtype=int))
    _, setting = problem.as_set(x, parts, 0)
    assert np.all(np.isfinite(setting.needed)) and np.all(setting.needed > 0.03)
    assert np.all(setting.needed < 0.06)
    # the same breaker as made stalls at both trials (the case this test is about)
    bare = build_problem(config.model_copy(update={"velocity_setting_bounds_m_s": None}))
    for trial in (0.0, 2.0):
        unset = {**fields, **{f"kc{i}_precompression_mm": np.array(
            [getattr(config, f"kc{i}_precompression_mm") + trial]) for i in (1, 2)}}
        assert np.isnan(bare.describe_variants(x[:, :-1], unset, np.zeros(1, dtype=int))
                        .extras["closing_velocity_avg_m_s"][0])
    assert made.g[0, problem.constraint_names.index("preload_setting")] <= 0
    for end in ("low", "high"):
        assert made.extras[f"closing_velocity_{end}_m_s"][0] == pytest.approx(x[0, -1], abs=1e-3)


def test_a_long_travel_takes_a_second_step(config, X):
    """A setting 13 mm away (friction 20 % high) is a long extrapolation from the 0 and
    2 mm trials (0.04 % off in one step, 0.7 % at 26 mm): the second step from the nearest
    point sets it within 1e-5 m/s."""
    problem = build_problem(config.model_copy(update={"preload_setting_range_mm": 30.0}))
    x = X[16:17].copy()
    x[:, -1] = problem.variables[-1].upper
    fields = {"cam_friction_nm": np.array([config.cam_friction_nm * 1.2])}
    made = problem.describe_variants(x, fields, np.zeros(1, dtype=int))
    assert made.extras["preload_setting_fit_mm"][0] > 10.0
    for end in ("low", "high"):
        assert made.extras[f"closing_velocity_{end}_m_s"][0] == pytest.approx(x[0, -1], abs=1e-5)


def test_the_nut_turns_by_whole_steps(config, X):
    """With a resolution, every set's travel is a whole number of steps (the nearest to
    the exact setting), and the set velocity moves off the setting by at most what half a
    step does: here under 1 % at 0.5 mm, while the exact setting is within 1e-3 m/s."""
    wide = {"preload_setting_range_mm": 30.0}  # room for random designs' settings
    stepped = build_problem(config.model_copy(update={**wide,
                                                      "preload_setting_resolution_mm": 0.5}))
    exact = build_problem(config.model_copy(update=wide))
    x = X[:48]
    parts = stepped.parts(len(x), {})
    _, fine = exact.as_set(x, parts)
    _, coarse = stepped.as_set(x, parts)
    both = np.isfinite(fine.needed) & np.isfinite(coarse.needed)
    assert both.sum() > 20
    steps = coarse.needed[both] / 5e-4
    np.testing.assert_allclose(steps, np.round(steps), rtol=0, atol=1e-9)
    assert np.abs(coarse.needed[both] - fine.needed[both]).max() <= 2.5e-4 + 1e-9
    assert np.any(np.abs(coarse.needed[both] - fine.needed[both]) > 1e-4)  # rounding happened
    ev = stepped.describe(x)
    ok = ev.g[:, stepped.constraint_names.index("preload_setting")] <= 0
    assert ok.sum() >= 5
    off = np.abs(ev.extras["closing_velocity_avg_m_s"][ok] / x[ok, -1] - 1)
    assert off.max() < 0.01 and off.max() > 1e-4
