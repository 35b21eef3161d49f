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
