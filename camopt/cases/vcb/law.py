"""The follower law phi(theta_c) = sum a_k theta_c^k (Eq 6) as numbers: its value, the zeros
of its rate phi' (Eq 12) in the stroke, the first dwell and the exact largest swing."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def rate_zeros(A: NDArray, end: float) -> NDArray:
    """Zeros in [0, end] of the follower's rate phi' = a1 + 2 a2 t + 3 a3 t^2 (+ 4 a4 t^3
    + ...; Eq 12), (n, d - 1) in ascending order for coefficient rows ``A`` (n, d + 1),
    NaN where there is none. The cubic's (d = 3) are exact, from the quadratic formula;
    a higher degree's are the real eigenvalues of phi''s companion matrices (one stacked
    ``numpy.linalg.eigvals`` call; a root counts as real within 1e-9 of its size).
    Consecutive rows with the same a1, a2, ... (a robust search's draws of one design
    differ in a0 alone: the cam profile's error) are solved once: the zeros read no a0."""
    n = len(A)
    if n > 1:
        same = np.all(A[1:, 1:] == A[:-1, 1:], axis=1)
        if same.any():
            first = np.flatnonzero(np.r_[True, ~same])
            return np.repeat(_rate_zeros(A[first], end), np.diff(np.r_[first, n]), axis=0)
    return _rate_zeros(A, end)


def _rate_zeros(A: NDArray, end: float) -> NDArray:
    """:func:`rate_zeros` of every row."""
    if A.shape[1] > 4:
        return _polynomial_rate_zeros(A, end)
    c0, c1, c2 = A[:, 1], 2 * A[:, 2], 3 * A[:, 3]
    roots = np.empty((len(A), 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = np.sqrt(c1 * c1 - 4 * c2 * c0)
        inv = 0.5 / c2
        np.multiply(-c1 - disc, inv, out=roots[:, 0])
        np.multiply(-c1 + disc, inv, out=roots[:, 1])
        flat = np.abs(c2) <= 1e-12 * (np.abs(c1) + np.abs(c0))  # phi' linear
        if flat.any():
            roots[flat] = (-c0[flat] / c1[flat])[:, None]
    roots[~((roots >= 0) & (roots <= end))] = np.nan
    roots.sort(axis=1)  # NaN last
    return roots


def _polynomial_rate_zeros(A: NDArray, end: float) -> NDArray:
    """:func:`rate_zeros` for degree d >= 4: phi' has degree d - 1. Its coefficients are
    scaled to theta / end (roots in [0, 1]) so the companion matrix is well conditioned;
    a row whose leading coefficient vanishes (relative 1e-12) is solved at the degree
    below it by the same route, down to the linear case."""
    n, d = len(A), A.shape[1] - 1
    k = np.arange(1, d + 1)
    c = A[:, 1:] * k * end ** (k - 1)  # phi' in u = theta / end: sum c_j u^j, j = 0..d-1
    roots = np.full((n, d - 1), np.nan)
    scale = np.abs(c).max(axis=1)
    left = n  # rows not yet solved (a phi' of degree 0 never is: no zero)
    with np.errstate(divide="ignore", invalid="ignore"):
        for deg in range(d - 1, 0, -1):  # degree of phi' actually present
            if not left:
                break
            lead = np.abs(c[:, deg]) > 1e-12 * scale
            if deg == d - 1:  # nothing above the top degree
                rows = lead
            else:
                rows = lead & np.all(np.abs(c[:, deg + 1:]) <= 1e-12 * scale[:, None], axis=1)
            count = int(rows.sum())
            if not count:
                continue
            left -= count
            comp = np.zeros((count, deg, deg))
            comp[:, 0, :] = -c[rows, deg - 1::-1] / c[rows, deg:deg + 1]
            comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
            z = np.linalg.eigvals(comp) if deg > 1 else comp[:, :, 0]
            real = np.abs(z.imag) <= 1e-9 * np.maximum(1.0, np.abs(z))
            u = np.where(real & (z.real >= 0) & (z.real <= 1), z.real, np.nan)
            roots[rows, :deg] = u * end
    roots.sort(axis=1)  # NaN last
    return roots


def follower_dwell(A: NDArray, end: float, zeros: NDArray | None = None) -> NDArray:
    """First cam angle in [0, end] where phi' vanishes (rad), NaN where it does not."""
    return (rate_zeros(A, end) if zeros is None else zeros)[:, 0]


def phi_max(A: NDArray, end: float, zeros: NDArray | None = None) -> NDArray:
    """Largest follower swing over 0 <= theta_c <= end (rad), exactly: the law's value at
    the ends and at the zeros of phi' (from :func:`rate_zeros`, computed if not given)."""
    zeros = rate_zeros(A, end) if zeros is None else zeros
    t = np.empty((len(A), 2 + zeros.shape[1]))
    t[:, 0], t[:, 1], t[:, 2:] = 0.0, end, zeros
    return np.nanmax(polynomial_value(A, t), axis=1)


def polynomial_value(A: NDArray, t: NDArray) -> NDArray:
    """The follower law's value phi(t) (rad) for coefficient rows ``A`` (n, d + 1) at
    cam angles ``t`` (n, j) or (j,) rad, by Horner's rule."""
    values = np.broadcast_to(A[:, -1:], np.broadcast_shapes((len(A), 1), np.shape(t)))
    for k in range(A.shape[1] - 2, -1, -1):
        values = A[:, k:k + 1] + t * values
    return values
