"""Cubic splines for a whole swarm at once.

scipy's CubicSpline builds one object per curve, so a swarm of profiles would be
evaluated in a Python loop over particles. Here every curve has N knots at the
same normalised positions u = 0, 1, ..., N-1 (each particle's profile angles are
uniform, only their spacing differs, and derivatives rescale by it). All curves
then share one tridiagonal system, solved once; values and derivatives at fixed
sample points become two matrix products per quantity for the whole swarm.
End conditions: clamped slope at u = 0, natural (S'' = 0) at u = N - 1 — the
conditions of Yan et al. (2023), Sec 3.3.1.
"""

from __future__ import annotations

import numpy as np

from camopt.mechanics import Floats


class ClampedNaturalSpline:
    """Cubic splines through N uniform knots, sampled at fixed points ``u`` in [0, N-1]."""

    def __init__(self, n_knots: int, u: Floats) -> None:
        if n_knots < 3:
            raise ValueError("a spline needs at least 3 knots")
        n = n_knots
        self.u = np.asarray(u, dtype=float)
        A = np.zeros((n, n))
        R = np.zeros((n, n))
        q = np.zeros(n)
        A[0, :2] = 2.0, 1.0  # clamped: 2 M0 + M1 = 6 (r1 - r0 - d0)
        R[0, :2] = -6.0, 6.0
        q[0] = -6.0
        for j in range(1, n - 1):  # M_{j-1} + 4 M_j + M_{j+1} = 6 (r_{j-1} - 2 r_j + r_{j+1})
            A[j, j - 1 : j + 2] = 1.0, 4.0, 1.0
            R[j, j - 1 : j + 2] = 6.0, -12.0, 6.0
        A[n - 1, n - 1] = 1.0  # natural end: M_{N-1} = 0
        G = np.linalg.solve(A, R)  # M = G r + g d0
        g = np.linalg.solve(A, q)
        seg = np.clip(np.floor(self.u).astype(int), 0, n - 2)
        t = self.u - seg
        k = np.arange(self.u.size)
        shape = (n, self.u.size)
        Wr, WM = np.zeros(shape), np.zeros(shape)
        Dr, DM = np.zeros(shape), np.zeros(shape)
        Er, EM = np.zeros(shape), np.zeros(shape)
        s = 1 - t
        Wr[seg, k], Wr[seg + 1, k] = s, t
        WM[seg, k], WM[seg + 1, k] = (s**3 - s) / 6, (t**3 - t) / 6
        Dr[seg, k], Dr[seg + 1, k] = -1.0, 1.0
        DM[seg, k], DM[seg + 1, k] = -(3 * s**2 - 1) / 6, (3 * t**2 - 1) / 6
        EM[seg, k], EM[seg + 1, k] = s, t
        # S = r (Wr + G^T WM) + d0 (g WM), and likewise for S' and S''
        self._mats = [Wr + G.T @ WM, Dr + G.T @ DM, Er + G.T @ EM]
        self._vecs = [g @ WM, g @ DM, g @ EM]
        self.G, self.g = G, g

    def __call__(self, r: Floats, slope0: Floats) -> tuple[Floats, Floats, Floats]:
        """S, dS/du and d2S/du2 at the sample points for knot values ``r`` (P, N) and
        start slopes ``slope0`` (P,) in units of r per unit u."""
        d0 = np.asarray(slope0, dtype=float)[:, None]
        S, dS, ddS = (r @ m + d0 * v[None, :] for m, v in zip(self._mats, self._vecs))
        return S, dS, ddS

    def second_derivative_at_knots(self, r: Floats, slope0: Floats) -> Floats:
        """M_j = S''(j) at every knot, (P, N)."""
        return r @ self.G.T + np.asarray(slope0, dtype=float)[:, None] * self.g[None, :]
