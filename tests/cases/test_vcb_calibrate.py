"""Calibration of the VCB dynamics on travel curves (camopt/cases/vcb/calibrate.py) against
synthetic "vendor" curves: made by an independent simulation (tests/cases/vcb_ode.py,
scipy's solve_ivp on Lagrange's equation, not camopt's work-energy quadrature) with known
parameters, a 3.4 ms latch delay and 0.02 mm white noise (tests/data/curves/)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.calibrate import (
    Calibration,
    CurveCase,
    Design,
    calibrate,
    sample_travel,
)
from camopt.cases.vcb.curves import read_curve
from camopt.cases.vcb.forms import get_form
from camopt.cases.vcb.problem import VcbProblem
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


def test_sample_travel_interpolates_holds_and_rests():
    """Rows with their own time grids: linear between nodes, 0 before the first, the last
    value after the latch, the last finite value after a stall (inf times), and a row
    that never moves (inf from the start) at 0."""
    time = np.array([[1.0, 2.0, 3.0], [0.5, 1.0, np.inf], [np.inf, np.inf, np.inf]])
    rod = np.array([[0.0, 1.0, 3.0], [0.0, 2.0, 2.5], [0.0, 1.0, 2.0]])
    query = np.array([[0.0, 1.5, 2.5, 9.0]] * 3)
    out = sample_travel(time, rod, query)
    np.testing.assert_allclose(out[0], [0.0, 0.5, 2.0, 3.0])
    np.testing.assert_allclose(out[1], [0.0, 2.0, 2.0, 2.0])
    np.testing.assert_allclose(out[2], [0.0, 0.0, 0.0, 0.0])


def test_remembered_kinematics_give_the_same_bits(problem):
    """The calibration's model remembers kinematics by input: residuals at two parameter
    batches are bit-identical to the plain model's (the same computation repeated)."""
    from camopt.cases.vcb.model import VcbModel

    curves = [_curve(problem, "vendor"), _curve(problem, "stiff")]
    cal = Calibration(problem.config, FORM, curves)
    q = cal.start()
    Q = np.vstack([q, q + 0.01])
    memo = [cal.residuals(q), cal.residuals(Q), cal.residuals(q)]
    cal.model = VcbModel(problem.config)
    plain = [cal.residuals(q), cal.residuals(Q), cal.residuals(q)]
    for a, b in zip(memo, plain):
        assert np.array_equal(a, b)


def test_fit_many_solves_fits_side_by_side_with_fixed_coordinates_and_bounds(problem):
    """The profiles' batched Levenberg-Marquardt on a linear model r = A q - b reaches
    scipy's robust least squares (soft-l1, f_scale 3, within bounds): a free row, a row
    with coordinate 0 fixed, and a row whose optimum lies past a bound (it stops on it,
    the rest re-fitted: the active set)."""
    from scipy.optimize import least_squares

    cal = Calibration(problem.config, FORM, [_curve(problem, "vendor")])
    n = len(cal.lower)
    rng = np.random.default_rng(1)
    A = rng.normal(size=(40, n))
    truth = 0.5 * (cal.lower + cal.upper)
    b = A @ truth + 0.5 * rng.normal(size=40)
    cal.residuals = lambda Q: np.atleast_2d(Q) @ A.T - b  # type: ignore[method-assign]

    def scipy_fit(free, base, upper):
        def fun(z):
            q = base.copy()
            q[free] = z
            return A @ q - b
        return least_squares(fun, base[free], bounds=(cal.lower[free], upper[free]),
                             loss="soft_l1", f_scale=3.0, ftol=1e-12, xtol=1e-12,
                             gtol=1e-12).x

    q0 = truth + 0.1
    fixed = np.r_[truth[0] + 0.3, q0[1:]]
    Q, _ = cal.fit_many(np.vstack([q0, fixed]), np.array([-1, 0]), max_iter=200)
    every = np.ones(n, dtype=bool)
    np.testing.assert_allclose(Q[0], scipy_fit(every, q0, cal.upper), atol=1e-6)
    np.testing.assert_allclose(Q[1, 1:], scipy_fit(every & (np.arange(n) > 0), fixed,
                                                   cal.upper), atol=1e-6)
    assert Q[1, 0] == fixed[0]
    upper = cal.upper.copy()
    upper[-1] = Q[0, -1] - 0.5  # the delay's bound below its optimum
    cal.upper = upper
    (q,), _ = cal.fit_many(q0[None, :] - 1.0, max_iter=200)
    assert q[-1] == upper[-1]
    np.testing.assert_allclose(q, scipy_fit(every, np.minimum(q0 - 1.0, upper), upper),
                               atol=1e-6)


def test_kept_forms_rule():
    """Kept: RMS at most 1.5 x the larger of the best form's and the noise."""
    from camopt.cases.vcb.calibrate import keep

    assert keep([0.02, 0.029, 0.031, 0.4], noise=0.01) == [True, True, False, False]
    assert keep([0.005, 0.014, 0.016], noise=0.01) == [True, True, False]
    assert keep([], noise=0.01) == []


def test_a_parameter_the_curves_do_not_see_is_open_without_warnings(problem):
    """The profile-likelihood walk divided column j of the covariance by its variance:
    for a coordinate the curves do not see (a zero Jacobian column, so zero variance in
    the pseudo-inverse) that was 0 / 0, a RuntimeWarning and NaN starts. Residuals here
    are a stand-in, linear in every coordinate but the first (the fit's machinery, not
    the dynamics, is under test): that coordinate's profile is open to both search
    bounds and not identified; the others' intervals are closed and finite."""
    import warnings

    from camopt.cases.vcb.calibrate import Optimum

    cal = Calibration(problem.config, FORM, [_curve(problem, "vendor")])
    centre, width = 0.5 * (cal.lower + cal.upper), cal.upper - cal.lower

    def residuals(Q):
        d = (np.atleast_2d(Q) - centre) / width * 40.0
        d[:, 0] = 0.0  # the first coordinate changes nothing
        return np.repeat(d, 5, axis=1) + 1.0

    cal.residuals = residuals  # type: ignore[method-assign]
    cal._curve_fits = lambda q: ()  # type: ignore[method-assign]
    J = cal._jacobian(centre)
    cov = np.linalg.pinv(J.T @ J)
    assert cov[0, 0] == 0.0
    optimum = Optimum(centre, float(cal._costs(centre)[0]), cov, 1.0, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = cal.fit(optimum, profiled=True)
        linear = cal.fit(optimum, profiled=False)
    unseen = fit.parameters[0]
    assert unseen.low == pytest.approx(np.exp(cal.lower[0]), rel=1e-12)
    assert unseen.high == pytest.approx(np.exp(cal.upper[0]), rel=1e-12)
    assert not unseen.identified
    for p in (*fit.parameters[1:], *linear.parameters):
        assert np.isfinite([p.low, p.value, p.high]).all() and p.low < p.value < p.high, p
