"""Table-based sincos against numpy's libm cos and sin."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.mechanics.trig import sincos


@pytest.mark.parametrize("span", [np.pi, 25.0, 1e3, 1e8])
def test_sincos_matches_numpy_within_a_few_ulp(span):
    angle = np.random.default_rng(1).uniform(-span, span, (40, 141))
    cos, sin = sincos(angle)
    assert cos.shape == angle.shape
    np.testing.assert_allclose(cos, np.cos(angle), rtol=0, atol=5e-16)
    np.testing.assert_allclose(sin, np.sin(angle), rtol=0, atol=5e-16)


def test_sincos_with_a_bound_skips_the_check_but_not_the_accuracy():
    angle = np.linspace(-3.0, 3.0, 1001)
    cos, sin = sincos(angle, bound=3.0)
    np.testing.assert_allclose(cos, np.cos(angle), rtol=0, atol=5e-16)
    np.testing.assert_allclose(sin, np.sin(angle), rtol=0, atol=5e-16)


def test_sincos_of_non_finite_angles_is_nan_like_numpy():
    with np.errstate(invalid="ignore"):
        cos, sin = sincos(np.array([np.nan, np.inf, -np.inf, 0.0]))
    assert np.isnan(cos[:3]).all() and np.isnan(sin[:3]).all()
    assert (cos[3], sin[3]) == (1.0, 0.0)


def test_sincos_of_a_scalar():
    assert sincos(0.5) == pytest.approx((np.cos(0.5), np.sin(0.5)), abs=5e-16)
