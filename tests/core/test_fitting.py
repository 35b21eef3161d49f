"""The fitting machinery (camopt/core/fitting.py) on stand-in models: the batched robust
least squares against scipy's, the profile-likelihood interval's threshold, and each
decision rule (identified, at a bound, kept, nested term, explains, determined) pinned
with exact values on both sides of its limit."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from numpy.typing import NDArray

from camopt.core import fitting
from camopt.core.capabilities import Fittable
from camopt.core.fitting import (
    CHI2_95_1DOF,
    WINSOR,
    Optimum,
    estimate,
    fit_many,
    identifiability,
    identified,
    jacobian,
    keep,
    likelihood_ratio,
    near_bound,
    residual_test,
)


class Linear:
    """r = (A q - b) / sigma: a model whose profile is an exact parabola."""

    def __init__(self, A: NDArray, b: NDArray, lower: NDArray, upper: NDArray,
                 log: NDArray | None = None, sigma: float = 1.0) -> None:
        self.A, self.b, self.sigma = A, b, sigma
        self.lower, self.upper = lower, upper
        self.log = np.zeros(len(lower), dtype=bool) if log is None else log
        self.accuracy = np.where(self.log, fitting.IDENTIFIED_WITHIN, 0.25)
        self.bound_room = np.full(len(lower), 0.1)

    def residuals(self, Q: NDArray) -> NDArray:
        return (np.atleast_2d(Q) @ self.A.T - self.b) / self.sigma

    def rms(self, q: NDArray) -> float:
        return float(np.sqrt(np.mean((self.residuals(q)[0] * self.sigma) ** 2)))


def test_a_stand_in_is_fittable():
    """The capability is declared by the Protocol's members: a model with them is one."""
    model = Linear(np.eye(2), np.zeros(2), np.zeros(2), np.ones(2))
    assert isinstance(model, Fittable)
    assert not isinstance(object(), Fittable)


def test_fit_many_solves_fits_side_by_side_with_fixed_coordinates_and_bounds():
    """The profiles' batched Levenberg-Marquardt on a linear model reaches scipy's robust
    least squares (soft-l1, f_scale 3, within bounds) to 1e-6: a free row, a row with
    coordinate 0 fixed, and a row whose optimum lies past a bound (it stops on it, the
    rest re-fitted: the active set)."""
    from scipy.optimize import least_squares

    n = 5
    rng = np.random.default_rng(1)
    A = rng.normal(size=(40, n))
    lower, upper = np.full(n, -3.0), np.full(n, 4.0)
    truth = 0.5 * (lower + upper)
    b = A @ truth + 0.5 * rng.normal(size=40)
    model = Linear(A, b, lower, upper)

    def scipy_fit(free, base, upper):
        def fun(z):
            q = base.copy()
            q[free] = z
            return A @ q - b
        return least_squares(fun, base[free], bounds=(lower[free], upper[free]),
                             loss="soft_l1", f_scale=3.0, ftol=1e-12, xtol=1e-12,
                             gtol=1e-12).x

    q0 = truth + 0.1
    fixed = np.r_[truth[0] + 0.3, q0[1:]]
    Q, _ = fit_many(model, np.vstack([q0, fixed]), np.array([-1, 0]), max_iter=200)
    every = np.ones(n, dtype=bool)
    np.testing.assert_allclose(Q[0], scipy_fit(every, q0, upper), atol=1e-6)
    np.testing.assert_allclose(Q[1, 1:], scipy_fit(every & (np.arange(n) > 0), fixed,
                                                   upper), atol=1e-6)
    assert Q[1, 0] == fixed[0]
    model.upper = upper.copy()
    model.upper[-1] = Q[0, -1] - 0.5  # a bound below the optimum
    (q,), _ = fit_many(model, q0[None, :] - 1.0, max_iter=200)
    assert q[-1] == model.upper[-1]
    np.testing.assert_allclose(q, scipy_fit(every, np.minimum(q0 - 1.0, model.upper),
                                            model.upper), atol=1e-6)


def _one_coordinate(width: float) -> tuple[Linear, Optimum]:
    """One coordinate q, 100 residuals (q - 1) / width: cost 0.5 sum rho, quadratic
    where |r| << 3. The optimum q = 1 with cost 0 and s^2 = 1 (held at its floor)."""
    model = Linear(np.ones((100, 1)) / width, np.full(100, 1.0 / width), np.array([-50.0]),
                   np.array([50.0]))
    q = np.array([1.0])
    J = jacobian(model, q)
    return model, Optimum(q, 0.0, np.linalg.pinv(J.T @ J), 1.0, 0.0)


def test_the_profile_interval_ends_where_the_cost_rises_by_chi2_over_two():
    """The threshold: the 95 % interval ends where the robust cost has risen by
    chi2(1, 0.95) / 2 s^2 = 1.92. For 100 equal residuals d / w the cost is
    100 C^2 (sqrt(1 + (d / (w C))^2) - 1) (C = 3): solved for a rise of 1.92, the end lies
    at d = w C sqrt((1 + 1.92 / (100 C^2))^2 - 1). The profile's end matches it to 1e-3
    relative (the parabola placed in the last bracket); with the threshold inverted or
    doubled it would miss by 40 % or more."""
    width = 10.0
    model, opt = _one_coordinate(width)
    (p,) = estimate(model, opt, [("x", "-")]).parameters
    rise, C = 0.5 * CHI2_95_1DOF, fitting.ROBUST_SCALE
    d = width * C * np.sqrt((1 + rise / (100 * C**2)) ** 2 - 1)
    assert d == pytest.approx(1.9610, abs=1e-4)
    assert p.high - 1.0 == pytest.approx(d, rel=1e-3)
    assert 1.0 - p.low == pytest.approx(d, rel=1e-3)
    # a profile stays under the threshold up to the bound: that end is the bound, open
    model.upper = np.array([2.5])
    (p,) = estimate(model, opt, [("x", "-")]).parameters
    assert p.high == 2.5 and not p.identified


def test_linearised_intervals_are_1_96_standard_deviations():
    """A model not profiled: q +- sqrt(chi2(1, 0.95)) sd, and nothing identified."""
    model, opt = _one_coordinate(1.0)
    (p,) = estimate(model, opt, [("x", "-")], profiled=False).parameters
    sd = np.sqrt(opt.cov[0, 0])
    assert p.high - 1.0 == pytest.approx(np.sqrt(CHI2_95_1DOF) * sd, rel=1e-12)
    assert not p.identified


def test_identified_rule():
    """A closed interval reaching at most 5 % of the value (a log coordinate) or the
    stated accuracy in the unit (others); an open one is never identified."""
    assert identified(10.0, 9.5, 10.5, True, True, 0.05)
    assert not identified(10.0, 9.5, 10.51, True, True, 0.05)
    assert not identified(10.0, 9.49, 10.0, True, True, 0.05)
    assert not identified(10.0, 9.9, 10.1, False, True, 0.05)
    assert identified(3.4, 3.15, 3.65, True, False, 0.25)
    assert not identified(3.4, 3.14, 3.4, True, False, 0.25)


def test_an_identified_profile_and_one_that_is_not():
    """Through the profiles: 100 residuals (q - 1) / w put the ends at +-0.1961 w (the
    threshold's solution above), so the linear coordinate is identified to 0.25 at
    w = 1.2 (reach 0.235) and not at w = 1.3 (0.255)."""
    for width, expected in ((1.2, True), (1.3, False)):
        model, opt = _one_coordinate(width)
        (p,) = estimate(model, opt, [("x", "-")]).parameters
        assert p.identified is expected, (width, p)


def test_near_bound_rule():
    """A log parameter within a factor 1.5 (or a tenth of its log range, if less) of a
    bound is at it; another coordinate within its room."""
    lo, hi = np.log(0.05), np.log(30.0)  # factor 1.5: 0.075
    assert near_bound(np.log(0.074), lo, hi, True, 0.1)
    assert not near_bound(np.log(0.076), lo, hi, True, 0.1)
    assert near_bound(np.log(20.1), lo, hi, True, 0.1)
    assert not near_bound(np.log(19.9), lo, hi, True, 0.1)
    lo, hi = np.log(0.2), np.log(1.0)  # a tenth of ln 5: factor 1.175
    assert near_bound(np.log(0.86), lo, hi, True, 0.1)
    assert not near_bound(np.log(0.84), lo, hi, True, 0.1)
    assert near_bound(0.09, 0.0, 100.0, False, 0.1)
    assert not near_bound(0.11, 0.0, 100.0, False, 0.1)
    assert near_bound(99.91, 0.0, 100.0, False, 0.1)


def test_at_bound_flag_through_estimate():
    """A fit at 0.05 of its room from the upper bound is flagged; 0.2 away is not."""
    for q, flagged in ((4.95, True), (4.8, False)):
        model, _ = _one_coordinate(1.0)
        model.upper = np.array([5.0])
        model.b = np.full(100, q)
        J = jacobian(model, np.array([q]))
        opt = Optimum(np.array([q]), 0.0, np.linalg.pinv(J.T @ J), 1.0, 0.0)
        (p,) = estimate(model, opt, [("x", "-")], profiled=False).parameters
        assert p.at_bound is flagged


def test_kept_rule():
    """Kept: RMS at most 1.5 x the larger of the best model's and the noise."""
    assert keep([0.02, 0.029, 0.031, 0.4], noise=0.01) == [True, True, False, False]
    assert keep([0.005, 0.014, 0.016], noise=0.01) == [True, True, False]
    assert keep([0.02, 0.03], noise=0.01) == [True, True]  # exactly 1.5 x is kept
    assert keep([], noise=0.01) == []


def test_likelihood_ratio_of_a_nested_term():
    """2 (cost_base - cost) / s^2: 2 (10 - 6) / 1.2 = 6.667, above chi2(1, 0.99) = 6.635;
    a gain of 3.9 is 6.5, below."""
    base = Optimum(np.zeros(1), 10.0, np.eye(1), 1.0, 0.0)
    assert likelihood_ratio(base, Optimum(np.zeros(1), 6.0, np.eye(1), 1.2, 0.0)) \
        == pytest.approx(20 / 3, rel=1e-12)
    assert likelihood_ratio(base, Optimum(np.zeros(1), 6.1, np.eye(1), 1.2, 0.0)) \
        == pytest.approx(6.5, rel=1e-12)
    assert 6.5 < fitting.CHI2_99_1DOF < 20 / 3


def test_residual_test_values_and_verdict_limits():
    """Hand-built residuals, exact: alternating +-1 sigma (N = 4) have RMS ratio 1 and
    d = 3 * 4 / 4 = 3, z = (2 - 3) sqrt(4) / 2 = -1: passes. A constant offset of
    1.5 sigma: ratio 1.5 exactly (the limit, passes), d = 0, z = sqrt(N) = 2. Over
    N = 9, z = 3 (the limit, passes); N = 10, z = 3.16 (fails). A ratio of 1.51 fails."""
    s = 2.0
    t = residual_test([np.array([1.0, -1.0, 1.0, -1.0]) * s], [s])
    assert (t.rms_ratio, t.durbin_watson, t.structure_z, t.samples, t.noise) == (
        1.0, 3.0, -1.0, 4, 2.0)
    assert t.passes()
    t = residual_test([np.full(4, 1.5 * s)], [s])
    assert (t.rms_ratio, t.durbin_watson, t.structure_z) == (1.5, 0.0, 2.0)
    assert t.passes()
    assert not residual_test([np.full(4, 1.51 * s)], [s]).passes()
    # structure alone: a 0.1-sigma offset (ratio 0.1) with d = 0
    assert residual_test([np.full(9, 0.1 * s)], [s]).structure_z == 3.0
    assert residual_test([np.full(9, 0.1 * s)], [s]).passes()
    assert not residual_test([np.full(10, 0.1 * s)], [s]).passes()


def test_residual_test_pools_within_sets_and_winsorises():
    """Two sets: no difference is taken across them; a 1,000-sigma spike counts as
    WINSOR sigma."""
    t = residual_test([np.array([1.0, 1.0]), np.array([-1.0, -1.0])], [1.0, 1.0])
    assert t.durbin_watson == 0.0  # across the sets it would be 4 / 4 = 1
    spiked = residual_test([np.array([0.0, 1000.0, 0.0, 0.0])], [1.0])
    assert spiked.rms_ratio == pytest.approx(np.sqrt(WINSOR**2 / 4), rel=1e-12)


def test_white_noise_passes_and_a_smooth_misfit_is_flagged():
    """White noise: RMS ratio within 5 % of 1 (N = 2,000: standard error 1.6 %) and d
    within 3 standard errors of 2. A smooth misfit of 0.5 sigma under the same noise:
    its ratio, 1.12, passes, but d falls ~9 standard errors below 2: flagged."""
    rng = np.random.default_rng(3)
    sigma = 0.02e-3
    white = [sigma * rng.standard_normal(1000) for _ in range(2)]
    t = residual_test(white, [sigma, sigma])
    assert t.rms_ratio == pytest.approx(1.0, rel=0.05) and t.passes()
    smooth = [w + 0.5 * sigma * np.sin(np.linspace(0, 3 * np.pi, 1000)) for w in white]
    s = residual_test(smooth, [sigma, sigma])
    assert s.rms_ratio < 1.5 and s.structure_z > 3 and not s.passes()


def test_identifiability_determined_rule():
    """Singular values 10, 0.1 and 0.099 (a diagonal Jacobian): 0.1 is exactly 1 % of the
    largest, determined; 0.099 is not. Each combination's largest exponent is +1."""
    jac = np.diag([10.0, -0.1, 0.099])
    ident = identifiability(jac, ("a", "b", "c"))
    assert [c["singular_value"] for c in ident.determined] == [10.0, 0.1]
    assert [c["singular_value"] for c in ident.undetermined] == [0.099]
    assert ident.determined[1]["exponent_b"] == 1.0
    assert ident.to_json()["condition"] == pytest.approx(10.0 / 0.099, rel=1e-12)


def test_a_coordinate_the_data_do_not_see_is_open_without_warnings():
    """A zero Jacobian column (zero variance in the pseudo-inverse): its profile is open
    to both search bounds and not identified, with no 0 / 0 warning; the others'
    intervals are closed and finite, profiled or linearised."""
    n = 4
    lower, upper = np.full(n, -5.0), np.full(n, 5.0)
    A = np.repeat(np.eye(n), 5, axis=0) * 4.0
    A[:, 0] = 0.0  # the first coordinate changes nothing
    model = Linear(A, -np.ones(5 * n), lower, upper, log=np.array([True] * 3 + [False]))
    centre = np.zeros(n)
    J = jacobian(model, centre)
    cov = np.linalg.pinv(J.T @ J)
    assert cov[0, 0] == 0.0
    opt = Optimum(centre, float(fitting.robust_cost(model.residuals(centre))[0]), cov, 1.0,
                  1.0)
    names = [(f"p{j}", "-") for j in range(n)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        profiled = estimate(model, opt, names).parameters
        linear = estimate(model, opt, names, profiled=False).parameters
    unseen = profiled[0]
    assert unseen.low == pytest.approx(np.exp(-5.0), rel=1e-12)
    assert unseen.high == pytest.approx(np.exp(5.0), rel=1e-12)
    assert not unseen.identified
    for p in (*profiled[1:], *linear):
        assert np.isfinite([p.low, p.value, p.high]).all() and p.low < p.value < p.high, p
