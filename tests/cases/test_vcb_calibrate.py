"""Calibration of the VCB dynamics on travel curves (camopt/cases/vcb/calibrate.py) against
synthetic "vendor" curves: made by an independent simulation (tests/cases/vcb_ode.py,
scipy's solve_ivp on Lagrange's equation, not camopt's work-energy quadrature) with known
parameters, a 3.4 ms latch delay and 0.02 mm white noise (tests/data/curves/)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.calibrate import Calibration, CurveCase, calibrate
from camopt.cases.vcb.calibration_model import Design
from camopt.cases.vcb.curves import read_curve
from camopt.cases.vcb.forms import get_form
from camopt.cases.vcb.problem import VcbProblem
from camopt.core.capabilities import Fittable
from camopt.units import MM, MS, N_PER_MM
from tests.cases import vcb_ode
from tests.conftest import CONFIGS
from tests.helpers import load

TRUTH = {"cam_inertia_kg_m2": vcb_ode.TRUTH.cam_kg_m2, "rod_mass_kg": vcb_ode.TRUTH.rod_kg,
         "contacts_mass_kg": vcb_ode.TRUTH.contacts_kg,
         "release_offset_deg": vcb_ode.TRUTH.release_offset_deg,
         "cam_friction_nm": vcb_ode.TRUTH.friction_nm,
         "latch_delay_ms": vcb_ode.LATCH_DELAY_S / MS}
FORM = get_form("efficiency_coulomb")


@pytest.fixture(scope="module")
def problem():
    return VcbProblem(load(CONFIGS / "vcb.toml").case)


def _design(problem, name):
    kc = vcb_ode.SPRING_SETS[name]
    return Design(name, problem.model.vendor_a, np.array(kc) * N_PER_MM)


def _curve(problem, name):
    return CurveCase(read_curve(vcb_ode.CURVES / f"{name}.csv"), _design(problem, name))


@pytest.fixture(scope="module")
def two(problem):
    """Both spring sets, jointly: one fit."""
    (fit,) = calibrate(problem.config, [_curve(problem, "vendor"), _curve(problem, "stiff")],
                       [FORM])
    return fit


@pytest.fixture(scope="module")
def one(problem):
    """The vendor's springs alone, predicting the stiff set."""
    (fit,) = calibrate(problem.config, [_curve(problem, "vendor")], [FORM],
                       [_design(problem, "vendor"), _design(problem, "stiff")])
    return fit


def test_the_shipped_curves_are_the_independent_simulation(problem):
    """tests/data/curves/vendor.csv is what vcb_ode writes (to its 1e-4 mm rounding)."""
    rod, _, _ = vcb_ode.closing(problem, vcb_ode.SPRING_SETS["vendor"])
    t, s = vcb_ode.sample(rod, seed=0)
    data = np.loadtxt(vcb_ode.CURVES / "vendor.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(data[:, 0], t / MS, atol=1e-9)
    np.testing.assert_allclose(data[:, 1], s / MM, atol=0.6e-4)


def test_two_spring_sets_recover_every_identified_parameter_within_5_percent(two):
    """Parameters the two curves identify within 5 % of the truth (the delay within 0.17
    ms, 5 % of 3.4 ms), and every true value inside its 95 % profile interval."""
    est = {p.name: p for p in two.parameters}
    assert set(est) == set(TRUTH)
    identified = [n for n, p in est.items() if p.identified]
    assert {"cam_inertia_kg_m2", "release_offset_deg", "cam_friction_nm",
            "latch_delay_ms"} <= set(identified)
    for name in identified:
        assert est[name].value == pytest.approx(TRUTH[name], rel=0.05), name
    for name, p in est.items():
        assert p.low <= TRUTH[name] <= p.high, (name, p)
    assert two.rms == pytest.approx(vcb_ode.NOISE_M, rel=0.1)  # the fit is at the noise


@pytest.mark.slow
def test_one_curve_cannot_separate_friction_release_and_delay_two_can(one, two):
    """One spring set identifies none of the release offset, the friction and the latch
    delay (the delay trades against the free rotation's time, the friction with both);
    the second set identifies all three and narrows their intervals at least 2.5-fold.
    The truth stays inside every interval. (One curve's friction interval is the edge of
    a nearly flat profile: 1.32 N m wide in one build, 1.80 in another whose arithmetic
    differs in round-off only, against 0.45 with two curves; threefold held in one.)"""
    a = {p.name: p for p in one.parameters}
    b = {p.name: p for p in two.parameters}
    for name in ("release_offset_deg", "cam_friction_nm", "latch_delay_ms"):
        assert not a[name].identified and b[name].identified, name
    for name in ("release_offset_deg", "cam_friction_nm", "latch_delay_ms"):
        width_one = a[name].high - a[name].low
        width_two = b[name].high - b[name].low
        assert width_two < width_one / 2.5, name
    for name, p in a.items():
        assert p.low <= TRUTH[name] <= p.high, (name, p)


@pytest.mark.slow
def test_second_design_closing_velocity_predicted_within_2_percent(problem, one):
    """Calibrated on the vendor's springs alone, the stiff set's average closing velocity
    (last third of the contact stroke, Sec 2.1) within 2 % of the independent ODE's, and
    the ODE's value inside the predicted band."""
    _, _, v_true = vcb_ode.closing(problem, vcb_ode.SPRING_SETS["stiff"])
    (pred,) = [p for p in one.predictions if p.design == "stiff"]
    assert pred.closing_velocity == pytest.approx(v_true, rel=0.02)
    assert pred.closing_velocity_low <= v_true <= pred.closing_velocity_high


def test_analyser_quantities_agree_between_measured_and_fitted_curves(two):
    """On each curve the fitted model's closing time within 0.1 ms and contact velocity
    within 1 % of the measured curve's, both computed by the same function."""
    for c in two.curves:
        m, s = c.measured_quantities, c.fitted_quantities
        assert s.closing_time == pytest.approx(m.closing_time, abs=0.1 * MS)
        assert s.contact_velocity == pytest.approx(m.contact_velocity, rel=0.01)
        assert s.over_travel is None and m.over_travel is not None


def test_the_fit_does_not_depend_on_the_integration_grid(problem):
    """The simulated travel at the truth on 400 (the case's) and 1,600 graded steps differs
    by under 5 % of the noise (1 um; it is 0.45 um, the linear interpolation in time
    between the grid's nodes): the fit sees the model, not its grid."""
    curves = [_curve(problem, "vendor")]
    q = np.r_[np.log([TRUTH[name] for name in FORM.parameters]), TRUTH["latch_delay_ms"]]
    a = Calibration(problem.config, FORM, curves).simulate(q)[0]
    fine = Calibration(problem.config.model_copy(update={"dynamics_steps": 1600}), FORM,
                       curves).simulate(q)[0]
    assert np.max(np.abs(a - fine)) < 0.05 * vcb_ode.NOISE_M


def test_remembered_kinematics_give_the_same_bits(problem):
    """The calibration's model remembers kinematics by input: residuals at two parameter
    batches are bit-identical to the plain model's (the same computation repeated)."""
    from camopt.cases.vcb.model import VcbModel

    curves = [_curve(problem, "vendor"), _curve(problem, "stiff")]
    cal = Calibration(problem.config, FORM, curves)
    assert isinstance(cal, Fittable)  # the seam the core fitting runs on
    q = cal.start()
    Q = np.vstack([q, q + 0.01])
    memo = [cal.residuals(q), cal.residuals(Q), cal.residuals(q)]
    cal.model = VcbModel(problem.config)
    plain = [cal.residuals(q), cal.residuals(Q), cal.residuals(q)]
    for a, b in zip(memo, plain):
        assert np.array_equal(a, b)


def test_in_model_curves_are_explained(two):
    """The shipped curves (made in this form) are explained: residuals at the noise,
    d within 3 standard errors of 2, no parameter at a search bound."""
    t = two.residuals
    assert two.explains and t.passes()
    assert t.rms_ratio == pytest.approx(1.0, abs=0.1)
    assert not any(p.at_bound for p in two.parameters)


@pytest.mark.slow
@pytest.mark.parametrize("physics, term, truth", [
    ({"spring_kg": 1.2}, "spring_mass_kg", 0.8),  # a third of each 1.2 kg spring moves
    ({"dashpot_n_s_per_m": 250.0}, "rod_damping_n_s_per_m", 250.0)])
def test_curves_with_physics_the_rigid_forms_lack(problem, physics, term, truth):
    """Curves from the independent ODE with the closing springs' own mass (1.2 kg each)
    or a rod dashpot (250 N s/m), two spring sets, 0.03 mm noise: the rigid forms do not
    explain them (Durbin-Watson 1.2 and 1.65: 12 and 5 standard errors below 2); either
    the verdict is NOT EXPLAINED, or every kept form predicts a third design's closing
    velocity (the ODE's, same physics) inside its interval. Measured: explained by the
    form with the missing term, its value within 20 % of the truth (the dashpot's curves
    are explained by the springs' mass too, both forms' predictions holding the truth)."""
    from camopt.cases.vcb.calibration_verdict import verdict
    from camopt.cases.vcb.curves import TravelCurve, noise_level
    from camopt.cases.vcb.forms import CURVE_FORMS

    curves = []
    for seed, name in enumerate(("vendor", "stiff")):
        rod, _, _ = vcb_ode.closing(problem, vcb_ode.SPRING_SETS[name], **physics)
        t, s = vcb_ode.sample(rod, seed=seed + 10, noise=0.03e-3)
        curves.append(CurveCase(TravelCurve(name, t, s, noise_level(s)),
                                _design(problem, name)))
    third = Design("third", problem.model.vendor_a, np.array([8.5, 8.5]) * N_PER_MM)
    forms = [f for f in CURVE_FORMS if "driven" not in f.name and f.name != "fitted_efficiency"]
    fits = {f.form: f for f in calibrate(problem.config, curves, forms, [third])}
    for name in ("efficiency_coulomb", "coulomb"):
        assert not fits[name].explains and fits[name].residuals.structure_z > 3, name
    v = verdict(list(fits.values()), problem.config.contact_gap_mm * MM)
    if not v.explained:
        assert "NOT EXPLAINED" in v.headline
        return
    _, _, v_true = vcb_ode.closing(problem, (8.5, 8.5), **physics)
    kept = [f for f in fits.values() if f.kept]
    assert kept and all(f.explains for f in kept)
    for f in kept:
        (p,) = f.predictions
        assert p.closing_velocity_low <= v_true <= p.closing_velocity_high, (f.form, p)
    (extended,) = [f for f in kept if any(p.name == term for p in f.parameters)]
    (value,) = [p for p in extended.parameters if p.name == term]
    # within 20 % (this noise draw: spring mass 0.92 [0.84, 0.99] for 0.8, an interval
    # that misses; the dashpot 264 [222, 305] for 250)
    assert value.value == pytest.approx(truth, rel=0.2)


def test_a_200_hz_curve_reads_the_contact_velocity_of_a_10_khz_one(problem, two):
    """Both spring sets sampled at 200 Hz (one sample between the velocity's calculation
    points; 60 ms, 0.02 mm noise): the contact velocity is read from the fit (resampled,
    said in the notes) within 2 % of the 10 kHz curves' reading (linear interpolation
    between the 200 Hz samples reads ~20 % low)."""
    curves = []
    for seed, name in enumerate(("vendor", "stiff")):
        rod, _, _ = vcb_ode.closing(problem, vcb_ode.SPRING_SETS[name])
        t, s = vcb_ode.sample(rod, seed=seed + 20, rate_hz=200.0, duration=0.06)
        from camopt.cases.vcb.curves import TravelCurve, noise_level

        curves.append(CurveCase(TravelCurve(name, t, s, noise_level(s)),
                                _design(problem, name)))
    (fit,) = calibrate(problem.config, curves, [FORM])
    for coarse, fine in zip(fit.curves, two.curves):
        q = coarse.measured_quantities
        assert any("resampled from the fit" in n for n in q.notes)
        assert q.contact_velocity == pytest.approx(
            fine.measured_quantities.contact_velocity, rel=0.02)


COVERAGE_REPLICATES = 20


@pytest.mark.slow
def test_95_percent_intervals_cover_the_truth_in_noisy_model_curves(problem):
    """A coverage study: COVERAGE_REPLICATES pairs of curves (both spring sets) made by the
    model itself at known parameters (the form's closing at the truth, a 3.4 ms delay),
    each with its own 0.02 mm white noise (seeded); every replicate calibrated. The 95 %
    intervals of the six parameters and of a third design's closing velocity must hold
    the truth in at least 90 % of the 7 x 20 cases (a 95 % interval holds it in 95 % on
    average; 90 % leaves room for the chance of 140 draws, ~1.8 % standard error;
    measured 138 of 140, ~17 s CPU). Curves of the model: the study tests the intervals,
    not the model."""
    from camopt.cases.vcb.calibration_model import sample_travel, travel
    from camopt.cases.vcb.curves import TravelCurve

    truth = np.array([TRUTH[name] for name in FORM.parameters])
    delay = vcb_ode.LATCH_DELAY_S
    designs = [_design(problem, "vendor"), _design(problem, "stiff")]
    third = Design("third", problem.model.vendor_a, np.array([8.5, 8.5]) * N_PER_MM)
    from camopt.cases.vcb.calibration_model import KinematicsMemo, velocity

    model = KinematicsMemo(problem.config)
    steps = problem.config.dynamics_steps
    time, rod = travel(FORM, model, designs, truth[None, :], steps)
    v_true = velocity(FORM, model, [third], truth[None, :], steps)[0][0, 0]
    t = np.arange(0.0, 0.045, 1e-4)
    clean = [sample_travel(time[:, i], rod[:, i], (t - delay)[None, :])[0] for i in range(2)]
    rng = np.random.default_rng(2046)
    held, total = 0, 0
    misses = []
    for _ in range(COVERAGE_REPLICATES):
        curves = []
        for i, d in enumerate(designs):
            s = clean[i] + vcb_ode.NOISE_M * rng.standard_normal(t.size)
            curves.append(CurveCase(TravelCurve(d.label, t, s, vcb_ode.NOISE_M), d))
        (fit,) = calibrate(problem.config, curves, [FORM], [third])
        for p in fit.parameters:
            ok = p.low <= TRUTH[p.name] <= p.high
            held, total = held + ok, total + 1
            misses += [] if ok else [p.name]
        (pred,) = fit.predictions
        ok = pred.closing_velocity_low <= v_true <= pred.closing_velocity_high
        held, total = held + ok, total + 1
        misses += [] if ok else ["velocity"]
    assert held / total >= 0.9, (held, total, misses)


def test_a_form_with_one_more_term_is_kept_on_its_likelihood_ratio():
    """The dashpot form over its base: a cost 4 lower at s^2 = 1.2 is a ratio of 6.67,
    above chi2(1, 0.99) = 6.63: kept; 3.9 lower (6.5) is not, and says why. A base form
    and a form already not kept pass through unchanged."""
    from camopt.cases.vcb.calibrate import nested_keep
    from camopt.core.fitting import Optimum

    forms = [get_form("efficiency_coulomb"), get_form("efficiency_coulomb_dashpot")]

    def opt(cost, s2=1.2):
        return Optimum(np.zeros(1), cost, np.eye(1), s2, 0.0)

    assert nested_keep(forms, [opt(10.0), opt(6.0)], [True, True]) == [(True, ""),
                                                                       (True, "")]
    (base, (kept, why)) = nested_keep(forms, [opt(10.0), opt(6.1)], [True, True])
    assert base == (True, "") and not kept and "likelihood ratio 6.50 < 6.63" in why
    assert nested_keep(forms, [opt(10.0), opt(0.0)], [False, False]) == [(False, ""),
                                                                        (False, "")]
