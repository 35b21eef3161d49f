"""Event location on the closing's node grids: the graded cam-angle grid, the trapezoid
time t = integral dtheta / omega, the first crossing of a level with linear interpolation,
and the first zero of the kinetic energy between nodes (a cubic Hermite interpolant of
the energy and its exact slope, the net torque)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.motion import compiled


def graded_grid(end: float, steps: int) -> tuple[NDArray, NDArray]:
    """theta = end (3 u^2 - 2 u^3) on u = 0..1 in ``steps`` intervals, and dtheta/du,
    (steps + 1,): fine at both ends, where the motion starts and may come almost to rest
    at the latch (dt = dtheta / omega stays integrable: omega ~ sqrt(distance) there)."""
    u = np.linspace(0.0, 1.0, steps + 1)
    return end * u * u * (3 - 2 * u), 6 * end * u * (1 - u)


def _cumulative_time(dtheta_du: NDArray, omega: NDArray, du: float) -> NDArray:
    """Cumulative integral of dtheta / omega over u by the trapezoid rule, (n, m). Where
    dtheta/du = 0 at an end the integrand is 0 if omega > 0 there, and its limit (taken as
    the neighbouring node's value) if the motion is at rest there."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = dtheta_du / omega
    g = np.array(np.broadcast_to(g, omega.shape))
    for end, inner in ((0, 1), (-1, -2)):
        if np.all(np.broadcast_to(dtheta_du, g.shape)[:, end] == 0):
            g[:, end] = np.where(omega[:, end] > 0, 0.0, g[:, inner])
    out = np.zeros_like(g)
    np.cumsum(0.5 * (g[:, 1:] + g[:, :-1]) * du, axis=1, out=out[:, 1:])
    return out


def _crossing(values: NDArray, level: float | NDArray) -> tuple[NDArray, NDArray]:
    """First interval (index k, values[k-1] < level <= values[k]) where each row reaches
    ``level``, and the fraction w in it; k = 0 where it never does."""
    above = values >= level
    k = np.where(above.any(axis=1), np.argmax(above, axis=1), 0)
    rows = np.arange(len(values))
    lo, hi = values[rows, np.maximum(k - 1, 0)], values[rows, k]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(k > 0, (level - lo) / (hi - lo), 0.0)
    return k, np.clip(np.nan_to_num(w), 0.0, 1.0)


def _at(a: NDArray, k: NDArray, w: NDArray) -> NDArray:
    """Linear interpolation of rows of ``a`` at fraction w of interval k."""
    rows = np.arange(len(a))
    a = np.broadcast_to(a, (len(k), a.shape[-1]))
    with np.errstate(invalid="ignore"):  # inf x 0 where a row never gets there
        return (1 - w) * a[rows, np.maximum(k - 1, 0)] + w * a[rows, k]


HERMITE_POINTS = 16
"""Points per interval at which :func:`first_zero` looks for the energy's first sign
change on its cubic Hermite interpolant between two nodes."""
BISECTIONS = 30
"""Bisections of that sub-interval: the root to 2^-30 of it."""


def _hermite(t: NDArray, h: NDArray, e0: NDArray, d0: NDArray, e1: NDArray, d1: NDArray
             ) -> NDArray:
    """The cubic Hermite interpolant at fraction t of an interval of length h with values
    e0, e1 and slopes d0, d1 at its ends (arrays broadcast)."""
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * e0 + (t3 - 2 * t2 + t) * h * d0
            + (-2 * t3 + 3 * t2) * e1 + (t3 - t2) * h * d1)


def first_zero(x: NDArray, energy: NDArray, slope: NDArray) -> NDArray:
    """The first coordinate where the kinetic energy reaches zero, per row (n,), nan where
    it stays positive: ``energy`` (n, m) and its exact derivative ``slope`` (n, m, the net
    torque) at the nodes ``x`` ((m,) or (n, m), increasing). Between two nodes the energy is
    its cubic Hermite interpolant (values and slopes at both ends: error O(h^4)), scanned
    at :data:`HERMITE_POINTS` points, so a zero between nodes is found even where both
    nodes are positive (the cam comes to rest and would be pushed on again: it stays);
    the root is then bisected on the cubic. A start at rest with a positive slope (the
    release) is not a zero. Compiled (``kernel.first_zero_rows``, the same scan and
    bisection row by row) where :func:`compiled` gives the kernel."""
    kernel = compiled()
    if kernel is not None and len(energy):
        root = np.empty(len(energy))
        kernel.first_zero_rows(np.ascontiguousarray(np.atleast_2d(x), dtype=float),
                               np.ascontiguousarray(energy, dtype=float),
                               np.ascontiguousarray(slope, dtype=float), root)
        return root
    x = np.broadcast_to(x, energy.shape)
    h = x[:, 1:] - x[:, :-1]
    e0, d0, e1, d1 = energy[:, :-1], slope[:, :-1], energy[:, 1:], slope[:, 1:]
    # the interpolant is at least min(e0, e1) - 4/27 h (|d0| + |d1|) (the bounds of its
    # basis functions): only intervals where that is not positive can hold a zero, and
    # none after the first node at or below zero (its interval holds one)
    low = energy[:, 1:] <= 0
    last = np.where(low.any(axis=1), np.argmax(low, axis=1), e0.shape[1])
    rows, cells = np.nonzero(
        (np.minimum(e0, e1) - 4 / 27 * h * (np.abs(d0) + np.abs(d1)) <= 0)
        & (np.arange(e0.shape[1])[None, :] <= last[:, None]))
    ends = (h[rows, cells], e0[rows, cells], d0[rows, cells], e1[rows, cells],
            d1[rows, cells])
    t = np.arange(1, HERMITE_POINTS + 1)[None, :] / HERMITE_POINTS
    e = _hermite(t, *(a[:, None] for a in ends))
    e[:, -1] = ends[3]  # the right node itself exactly
    below = e <= 0
    zero = below.any(axis=1)
    root = np.full(len(energy), np.nan)
    if not zero.any():  # no row comes to rest (the usual case): nothing to bisect
        return root
    # each row's first candidate interval that holds a zero (candidates are row-major)
    first_rows, first = np.unique(rows[zero], return_index=True)
    pick = np.flatnonzero(zero)[first]
    point = np.argmax(below[pick], axis=1)
    args = tuple(a[pick] for a in ends)
    lo, hi = point / HERMITE_POINTS, (point + 1) / HERMITE_POINTS  # e(lo) > 0 >= e(hi)
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        positive = _hermite(mid, *args) > 0
        lo, hi = np.where(positive, mid, lo), np.where(positive, hi, mid)
    root[first_rows] = x[first_rows, cells[pick]] + hi * args[0]
    return root
