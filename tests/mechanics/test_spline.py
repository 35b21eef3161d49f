"""The batched spline equals scipy's CubicSpline with the same end conditions."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from camopt.mechanics.spline import ClampedNaturalSpline


def test_matches_scipy_clamped_natural():
    n = 9
    u = np.linspace(0, n - 1, 257)
    spline = ClampedNaturalSpline(n, u)
    rng = np.random.default_rng(4)
    r, d0 = rng.random((6, n)), rng.normal(size=6)
    S, dS, ddS = spline(r, d0)
    M = spline.second_derivative_at_knots(r, d0)
    for i in range(6):
        ref = CubicSpline(np.arange(n), r[i], bc_type=((1, d0[i]), (2, 0.0)))
        np.testing.assert_allclose(S[i], ref(u), atol=1e-13)
        np.testing.assert_allclose(dS[i], ref(u, 1), atol=1e-12)
        np.testing.assert_allclose(ddS[i], ref(u, 2), atol=1e-12)
        np.testing.assert_allclose(M[i], ref(np.arange(n), 2), atol=1e-12)


def test_knot_warp_is_a_monotone_map_with_consistent_derivatives():
    from camopt.cases.emb_cam.problem import knot_warp

    x = np.linspace(0, 1, 2001)
    w, dw, ddw = knot_warp(x, (0.3, 6.0, 0.06))
    assert w[0] == pytest.approx(0) and w[-1] == pytest.approx(1)
    assert np.all(np.diff(w) > 0)
    np.testing.assert_allclose(np.gradient(w, x)[1:-1], dw[1:-1], rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(np.gradient(dw, x)[2:-2], ddw[2:-2], rtol=1e-3, atol=1e-3)
    u, du, ddu = knot_warp(x, None)
    assert np.array_equal(u, x) and np.all(du == 1) and np.all(ddu == 0)
