"""Slider-crank derivatives agree with finite differences of the positions (Eq 3)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.mechanics.slider_crank import coupler_angle, coupler_derivatives, crank_angle_for_span


@settings(max_examples=60, deadline=None)
@given(r2=st.floats(0.01, 0.1), r3=st.floats(0.15, 0.4), theta2=st.floats(0.2, 1.5))
def test_derivatives_match_finite_differences(r2, r3, theta2):
    h = 1e-6
    th3, d3, dd3, ds, dds = coupler_derivatives(r2, r3, theta2)
    lo, hi = coupler_derivatives(r2, r3, theta2 - h), coupler_derivatives(r2, r3, theta2 + h)

    def s(t3, t2):  # spring length up to a constant: -(r2 cos t2 + r3 cos t3)
        return -(r2 * np.cos(t2) + r3 * np.cos(t3))

    assert np.isclose(d3, (hi[0] - lo[0]) / (2 * h), rtol=1e-5, atol=1e-8)
    assert np.isclose(dd3, (hi[1] - lo[1]) / (2 * h), rtol=1e-4, atol=1e-6)
    assert np.isclose(ds, (s(hi[0], theta2 + h) - s(lo[0], theta2 - h)) / (2 * h),
                      rtol=1e-5, atol=1e-9)
    assert np.isclose(dds, (hi[3] - lo[3]) / (2 * h), rtol=1e-4, atol=1e-7)


def test_loop_closure_round_trip():
    """The crank angle found for a span closes the loop with the coupler angle."""
    r2, r3, theta2 = 0.0557, 0.2891, np.radians(30)
    th3 = coupler_derivatives(r2, r3, theta2)[0]
    span = r2 * np.cos(theta2) + r3 * np.cos(th3)
    assert np.isclose(np.arccos(crank_angle_for_span(r2, r3, span)), theta2)
    assert np.isclose(coupler_angle(r2, r3, theta2, span), th3)
    assert np.isclose(r2 * np.sin(theta2) + r3 * np.sin(th3), 0.0, atol=1e-15)


def test_the_pin_on_the_pivot_and_the_dead_centre_are_masks_not_warnings():
    """Issue #30: a zero span (the pin on the crank's pivot) cannot close the loop: inf,
    and at the dead centre (r2 sin theta2 = r3) the derivatives are NaN; neither by a
    division by zero (on main both printed a numpy RuntimeWarning onto stderr)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        cos2 = crank_angle_for_span(np.array([0.02, 0.02, 0.0]), 0.03,
                                    np.array([0.0, 0.04, 0.04]))
        _, d3, dd3, ds, dds = coupler_derivatives(0.03, 0.03, np.array([np.pi / 2, 0.3]))
        scalar = coupler_derivatives(0.03, 0.03, np.pi / 2)
    assert np.isinf(cos2[0]) and np.isinf(cos2[2]) and np.isfinite(cos2[1])
    assert np.isnan([d3[0], dd3[0], ds[0], dds[0]]).all()
    assert np.isfinite([d3[1], dd3[1], ds[1], dds[1]]).all()
    assert np.isnan(float(scalar[1]))
