"""The VCB's parts as made, per row (issue #33): the closing springs' free lengths, the
opening and contact springs, friction and efficiency, the cam profile; and its kept model
forms as variants (capability HasVariants) that robust design and tolerance draw over."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases import build_problem
from camopt.core.capabilities import HasVariants, VariesCase
from tests.conftest import CONFIGS
from tests.helpers import load

CONFIG = CONFIGS / "vcb_velocity_robust.toml"


@pytest.fixture(scope="module")
def problem():
    return build_problem(load(CONFIG).case)


@pytest.fixture(scope="module")
def X(problem):
    """Four designs near the shipped robust search's region (release offset 18.5 deg)."""
    rng = np.random.default_rng(7)
    X = problem.sample(rng, 4)
    X[:, problem.names.index("release_offset_deg")] = np.deg2rad(18.5)
    return X


def _close(a, b):
    np.testing.assert_allclose(np.nan_to_num(a.g, posinf=1e300),
                               np.nan_to_num(b.g, posinf=1e300), rtol=1e-10, atol=1e-12)
    for k, v in b.extras.items():
        np.testing.assert_allclose(a.extras[k], v, rtol=1e-10, atol=1e-12, err_msg=k)


def test_the_parts_are_case_fields_and_the_forms_variants(problem):
    assert isinstance(problem, VariesCase) and isinstance(problem, HasVariants)
    assert {"kc1_precompression_mm", "kc2_precompression_mm", "opening_k_n_per_mm",
            "wipe_k_n_per_mm", "cam_friction_nm", "efficiency",
            "cam_profile_error_mm"} <= set(problem.case_fields())
    # configs/vcb.toml's band: 2 sets of the shipped form, 7 of Coulomb-only friction
    assert problem.variants() == ("efficiency_coulomb", "coulomb")
    # coulomb's fit is its nominal; each form has its link-mass set
    assert [f.count for f in problem.forms] == [3, 7]


def test_nominal_parts_change_nothing(problem, X):
    c = problem.config
    fields = {f: np.full(len(X), float(getattr(c, f))) for f in problem.case_fields()}
    _close(problem.describe_with(X, fields), problem.describe(X))
    # every variant at once (-1) is the case's own evaluation
    _close(problem.describe_variants(X, fields, np.full(len(X), -1)), problem.describe(X))


@pytest.mark.parametrize("field, value", [
    ("kc1_precompression_mm", 141.5), ("kc2_precompression_mm", 98.5),
    ("opening_k_n_per_mm", 18.26), ("wipe_k_n_per_mm", 74.16),
    ("cam_profile_error_mm", 0.03)])
def test_a_part_per_row_is_a_config_with_that_value(problem, X, field, value):
    """Row by row the same as a case file with the part's value: the springs' energy,
    torque and loads take one value per design."""
    made = build_problem(load(CONFIG, f"case.{field}={value}").case)
    ev = problem.describe_with(X, {field: np.full(len(X), value)})
    _close(ev, made.describe(X))


def test_friction_and_efficiency_per_row(problem, X):
    """Friction 25 % high takes latch energy in every form; the efficiency moves only the
    forms that have one (Coulomb-only sets keep eps = 1)."""
    n = len(X)
    base = problem.describe_variants(X, {}, np.ones(n, dtype=int))
    c = problem.config
    high = problem.describe_with(X, {"cam_friction_nm": np.full(n, 1.25 * c.cam_friction_nm)})
    nominal = problem.describe(X)
    ok = nominal.extras["latched"] == 1
    assert (high.extras["latch_kinetic_energy_low_j"][ok]
            < nominal.extras["latch_kinetic_energy_low_j"][ok]).all()
    eff = {"efficiency": np.full(n, c.efficiency - 0.03)}
    coulomb = problem.describe_variants(X, eff, np.ones(n, dtype=int))
    for k in ("latch_kinetic_energy_low_j", "closing_velocity_low_m_s"):
        np.testing.assert_array_equal(coulomb.extras[k], base.extras[k])
    shipped = problem.describe_variants(X, eff, np.zeros(n, dtype=int))
    plain = problem.describe_variants(X, {}, np.zeros(n, dtype=int))
    assert (shipped.extras["surplus_work_j"] < plain.extras["surplus_work_j"]).all()


def test_each_form_is_judged_under_its_own_sets(problem, X):
    """A row in form f gets f's band alone: the band over every form is the extremes of
    the forms' bands, row by row (the identified set belongs to the shipped form)."""
    n = len(X)
    every = problem.describe(X)
    forms = [problem.describe_variants(X, {}, np.full(n, v)) for v in range(2)]
    mixed = problem.describe_variants(X, {}, np.array([0, 1, 0, 1]))
    for i in range(n):
        _close(mixed.take(i), forms[i % 2].take(i))
    low = np.minimum(*(f.extras["closing_velocity_low_m_s"] for f in forms))
    high = np.maximum(*(f.extras["closing_velocity_high_m_s"] for f in forms))
    closes = np.isfinite(every.extras["closing_velocity_low_m_s"])
    np.testing.assert_allclose(every.extras["closing_velocity_low_m_s"][closes], low[closes])
    np.testing.assert_allclose(every.extras["closing_velocity_high_m_s"][closes], high[closes])
    assert list(forms[0].extras["band_sets"]) == [4.0] * n  # identified + 2 + link masses
    assert list(forms[1].extras["band_sets"]) == [8.0] * n  # coulomb's fit + 6 + links


def test_robust_vcb_draws_over_its_forms_and_screens_per_form():
    """The robust VCB problem takes the case's forms as its plan's variants (the engine
    names no case kind), samples exactly the designs that meet every constraint in some
    form (tests/engine/test_robust.py shows one feasible in one form only sampled), and its
    check gives the yield per form on half the draws each."""
    from camopt.engine import robust
    from camopt.engine.driver import prepare

    cfg = load(CONFIG, "robust.samples=8", "robust.check_samples=200")
    rp, _ = prepare(cfg)
    assert isinstance(rp, robust.RobustProblem)
    assert rp.plan.variants == ("efficiency_coulomb", "coulomb")
    assert "case.cam_friction_nm" in [v.name for v in rp.plan.varies]
    rng = np.random.default_rng(11)
    X = rp.base.sample(rng, 200)
    X[:, rp.base.names.index("release_offset_deg")] = np.deg2rad(18.5)
    each = [rp.base.describe_variants(X, {}, np.full(len(X), v)) for v in (0, 1)]
    rp.reseed(np.random.SeedSequence(2))
    rp.new_generation()
    ev = rp.evaluate(X)
    sampled = ev.g[:, -1] < robust.SCREENED
    np.testing.assert_array_equal(sampled, each[0].feasible | each[1].feasible)
    (checked,) = robust.check(rp, [X[0]], seed=1)
    assert [f["samples"] for f in checked["per_form"]] == [100, 100]


def test_the_latch_energy_falls_with_friction_at_least_the_bound_of_the_equations(problem):
    """The bound docs/tolerance.md derives ("VCB: what the friction tolerance leaves"):
    with everything else held, the kinetic energy left at the latch is affine in the
    friction scale s while the cam latches, and falls by T_f (theta_end - r theta_touch)
    + c0 (1 - r) T_fr L_free per unit s (dynamics.closing_state: r the share of the
    touch's kinetic energy the contacts' impact takes, c0 the pick-up impact's share of
    the free rotation, both in [0, 1]; eps never multiplies T_f). r is at most m_c / (m_rod
    + m_c), so the slope is at least T_f theta_end m_rod / (m_rod + m_c) whatever the
    design: 1.37 rad x 11.445 N m in form efficiency_coulomb, 1.30 rad x 15.69 N m in
    coulomb (the least over each form's sets). Checked on 600 random designs in each form;
    the least slope seen there (2.3 x T_f, the sample's) is no bound."""
    rng = np.random.default_rng(20261127)
    X = problem.sample(rng, 600)
    c = problem.config
    scales = np.array([0.95, 1.05])
    rows = np.repeat(X, 2, axis=0)
    fields = {"cam_friction_nm": c.cam_friction_nm * np.tile(scales, len(X))}
    theta_end = np.deg2rad(140.0)  # the cam's stroke from the pick-up to the latch
    for v, form in enumerate(problem.forms):
        sets = [form.nominal] + ([] if form.members is None else [form.members])
        friction = min(float(np.min(np.ravel(s.friction_nm))) for s in sets)
        rod_share = min(float(np.min(np.ravel(s.rod_kg) / (np.ravel(s.rod_kg)
                                                          + np.ravel(s.contacts_kg))))
                        for s in sets)
        ev = problem.describe_variants(rows, fields, np.full(len(rows), v))
        energy = ev.extras["latch_kinetic_energy_low_j"].reshape(-1, 2)
        latched = (energy > 0.5).all(axis=1)  # both ends close, away from a stall
        assert latched.sum() >= 5, form.name  # the property is tested on real closings
        slope = -(energy[latched, 1] - energy[latched, 0]) / (scales[1] - scales[0])
        assert slope.min() >= friction * theta_end * rod_share, (form.name, slope.min())


def test_draws_without_the_descriptive_metrics_keep_the_verdict(problem, X):
    """``detail=False`` (robust design's draws) leaves the descriptive metrics out and
    every constraint and the objective as they are, row by row."""
    c = problem.config
    fields = {"cam_friction_nm": c.cam_friction_nm * np.array([0.9, 1.0, 1.1, 1.2])}
    variant = np.array([0, 1, 1, 0])
    full = problem.describe_variants(X, fields, variant)
    lean = problem.describe_variants(X, fields, variant, detail=False)
    np.testing.assert_array_equal(lean.g, full.g)
    np.testing.assert_array_equal(lean.f, full.f)
    assert "curvature_min_mm" in full.extras and "curvature_min_mm" not in lean.extras


def test_rows_of_both_forms_in_one_call_are_each_form_s_own(problem):
    """Robust draws mix the forms row by row; one call judges them all (the statics and
    the verdict once, each form's closing in one call of its own): every row as the call
    of its form alone, parts per row, with and without the descriptive metrics. rtol
    1e-12: the same arithmetic row by row, only the rows sharing a call differ."""
    rng = np.random.default_rng(11)
    n = 9
    X = problem.sample(rng, n)
    X[:, problem.names.index("release_offset_deg")] = np.deg2rad(18.5)
    c = problem.config
    fields = {"cam_friction_nm": c.cam_friction_nm * rng.uniform(0.8, 1.2, n),
              "efficiency": c.efficiency + rng.uniform(-0.03, 0.03, n)}
    variant = rng.integers(0, 2, n)
    assert len(np.unique(variant)) == 2
    for detail in (False, True):
        mixed = problem.describe_variants(X, fields, variant, detail=detail)
        for v in range(2):
            rows = np.flatnonzero(variant == v)
            alone = problem.describe_variants(
                X[rows], {k: a[rows] for k, a in fields.items()}, variant[rows],
                detail=detail)
            got = mixed.take(rows)
            np.testing.assert_allclose(np.nan_to_num(got.f, posinf=1e300),
                                       np.nan_to_num(alone.f, posinf=1e300), rtol=1e-12)
            np.testing.assert_allclose(np.nan_to_num(got.g, posinf=1e300),
                                       np.nan_to_num(alone.g, posinf=1e300), rtol=1e-12)
            assert got.extras.keys() == alone.extras.keys()
            for k, a in alone.extras.items():
                np.testing.assert_allclose(got.extras[k], a, rtol=1e-12, err_msg=k)
        # each row counts its own form's sets: identified + 2 + link masses, coulomb's 8
        assert list(mixed.extras["band_sets"]) == [4.0 if v == 0 else 8.0 for v in variant]
