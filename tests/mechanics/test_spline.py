"""The batched spline equals scipy's CubicSpline with the same end conditions."""

from __future__ import annotations

import numpy as np
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
