"""Disc cam with an oscillating roller follower (Kang 2023 Eqs 6-15).

Cam pivot O, follower pivot B at distance l6, follower arm l2, roller radius rf,
base circle rb. phi is the follower swing measured from the base-circle position
(xi, Eq 10). Everything broadcasts over (population, cam angle); the cosine and
sine of xi + phi are computed once in :class:`Follower` (by :func:`sincos`) and shared.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camopt.mechanics import Floats, FloatsLike
from camopt.mechanics.trig import sincos


def base_angle(l2: FloatsLike, l6: FloatsLike, distance: FloatsLike) -> Floats:
    """Angle at B between BO and BD when the roller centre is ``distance`` from O
    (Eq 10 with distance = rb + rf; Eqs 2 and 8 with other distances)."""
    return np.arccos((l2**2 + l6**2 - np.square(distance)) / (2 * l2 * l6))



@dataclass(frozen=True)
class Follower:
    """Follower motion on a cam-angle grid: the angle xi + phi with its cos and sin."""

    theta_c: Floats
    xi: float
    angle: Floats  # xi + phi
    dphi: Floats
    ddphi: Floats
    cos_a: Floats
    sin_a: Floats

    @property
    def phi(self) -> Floats:
        """Follower swing from the base-circle position (Eq 6), rad."""
        return self.angle - self.xi

    @classmethod
    def polynomial(cls, a: Floats, theta_c: Floats, xi: float) -> Follower:
        """Polynomial motion phi = sum_k a_k theta_c^k, with phi' and phi'' (Eqs 6, 12,
        15: the paper's cubic when ``a`` is (n, 4); (n, d + 1) for degree d) on a 1-D grid
        ``theta_c`` (:func:`polynomial_law`), with the cos and sin of xi + phi."""
        t, angle, dphi, ddphi = polynomial_law(a, theta_c, xi)
        # |xi + phi| <= |xi| + sum |a_k| max |t|^k: spares sincos its range check
        powers = t[None, :] ** np.arange(a.shape[1], dtype=float)[:, None]
        bound = float(np.max(np.abs(a) @ np.abs(powers).max(axis=1))) + abs(xi)
        cos_a, sin_a = sincos(angle, bound if np.isfinite(bound) else None)
        return cls(t[None, :], xi, angle, dphi, ddphi, cos_a, sin_a)


def polynomial_law(a: Floats, theta_c: Floats, xi: float
                   ) -> tuple[Floats, Floats, Floats, Floats]:
    """The grid ``theta_c`` flattened (m,) and xi + phi, phi' and phi'' (n, m) of the
    polynomial phi = sum_k a_k theta_c^k (Eqs 6, 12, 15), ``a`` (n, d + 1), as one matrix
    product per derivative."""
    t = np.ravel(theta_c)
    k = np.arange(a.shape[1], dtype=float)[:, None]
    powers = t[None, :] ** k  # (d + 1, m); t^0 = 1 also at t = 0
    angle = a @ powers
    angle += xi  # after the product: a row's value must not depend on the batch
    shifted = np.vstack([np.zeros_like(t), powers[:-1]])  # t^(k - 1)
    dphi = a @ (k * shifted)
    ddphi = a @ (k * (k - 1) * np.vstack([np.zeros_like(t), shifted[:-1]]))
    return t, angle, dphi, ddphi


def pitch_curve(l2: float, l6: float, f: Follower) -> tuple[Floats, Floats, Floats, Floats]:
    """Pitch curve (xp, yp) and its derivatives with respect to theta_c (Eqs 9, 12)."""
    ct, st = np.cos(f.theta_c), np.sin(f.theta_c)
    cu = ct * f.cos_a + st * f.sin_a  # u = theta_c - xi - phi
    su = st * f.cos_a - ct * f.sin_a
    w = l2 * (1 - f.dphi)
    return l6 * ct - l2 * cu, l6 * st - l2 * su, -l6 * st + w * su, l6 * ct - w * cu


def profile(xp: FloatsLike, yp: FloatsLike, dxp: FloatsLike, dyp: FloatsLike,
            rf: FloatsLike) -> tuple[Floats, Floats]:
    """Cam profile, the pitch curve offset by the roller radius (Eq 11)."""
    norm = np.hypot(dxp, dyp)
    return xp - rf * dyp / norm, yp + rf * dxp / norm


def pressure_angle(l2: float, l6: float, f: Follower) -> Floats:
    """Pressure angle psi (rad, signed), the shape of ``f.angle``: the angle between the
    common normal at the roller centre D (the pitch curve's normal, from Eq 12's
    derivative) and the direction D moves in as the follower swings (perpendicular to BD).
    In the cam's frame the two give

        tan psi = (l6 cos(xi + phi) - l2 (1 - phi')) / (l6 sin(xi + phi)).

    For phi' < 1 this is the paper's psi = pi/2 - eta - xi - phi (Eqs 13-14, through the
    instant centre I at OI = l6 phi' / (1 - phi')) to rounding. From phi' = 1 on, I
    passes to the other side of O and Eq 14's arcsin takes the wrong branch (at
    phi' = 1.3 in tests/mechanics/test_cam.py, 26.3 deg where the geometry gives 45.6
    deg): a steep law could pass the 45 deg limit (docs/assumptions.md, "VCB: the
    pressure angle of a steep law")."""
    with np.errstate(divide="ignore"):
        return np.arctan((l6 * f.cos_a - l2 * (1 - f.dphi)) / (l6 * f.sin_a))


def curvature_radius(l2: float, l6: float, f: Follower, rf: float) -> Floats:
    """Radius of curvature of the cam profile (Eq 15): pitch radius minus rf."""
    w = 1 - f.dphi
    w2 = w * w
    cw = f.cos_a * w
    base = l6**2 - (2 * l2 * l6) * cw + l2**2 * w2
    den = (l6**2 - (l2 * l6) * (2 - f.dphi) * cw - (l2 * l6) * f.ddphi * f.sin_a
           + l2**2 * w2 * w)
    return base * np.sqrt(base) / den - rf
