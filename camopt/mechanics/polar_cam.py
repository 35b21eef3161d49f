"""Profile-based analysis of a negative-radius roller cam (Yan et al. 2023, Eqs 4-24).

The cam profile is r(theta) in polar coordinates about the cam pivot O; the follower
is a bearing ring of inner radius rg whose centre A moves along a line offset e from
O. All functions take arrays and broadcast over (particles, profile samples); lengths
in one consistent unit (SI in camopt).
"""

from __future__ import annotations

import numpy as np

from camopt.mechanics import Floats, FloatsLike


def normal_arm(r: FloatsLike, dr: FloatsLike) -> Floats:
    """Distance l from O to the profile normal at the contact point (Eqs 5-8).

    With B = r(cos, sin) and tangent (dr cos - r sin, dr sin + r cos), |OD| = |B . T| / |T|
    = r |dr| / sqrt(r^2 + dr^2): Eq 8 without the slopes' singularities.
    """
    r, dr = np.asarray(r), np.asarray(dr)
    return r * np.abs(dr) / np.sqrt(r * r + dr * dr)


def center_distance(r: FloatsLike, l: FloatsLike, rg: FloatsLike) -> Floats:
    """|OA| between the cam pivot and the ring centre (Eq 9)."""
    r, l = np.asarray(r), np.asarray(l)
    return np.sqrt(r * r + rg * rg - 2 * rg * np.sqrt(np.clip(r * r - l * l, 0, None)))


def follower_height(oa: FloatsLike, e: FloatsLike) -> Floats:
    """h = |AC| along the follower's line (Eq 10); lift s = h(theta0) - h(theta) (Eq 11)."""
    oa = np.asarray(oa)
    return np.sqrt(oa * oa - np.square(e))


def pressure_angle(oa: FloatsLike, e: FloatsLike, l: FloatsLike, r: FloatsLike,
                   rg: FloatsLike) -> Floats:
    """Pressure angle on the two branches of Eq 13 (rad; negative: right of the normal)."""
    oa, l, r = np.asarray(oa), np.asarray(l), np.asarray(r)
    a_e = np.arcsin(np.clip(np.asarray(e) / oa, -1, 1))
    a_l = np.arcsin(np.clip(l / oa, -1, 1))
    near = rg >= np.sqrt(np.clip(r * r - l * l, 0, None))
    return np.where(near, a_e - a_l, a_e + a_l - np.pi)


def rotation_angle(theta: FloatsLike, l: FloatsLike, r: FloatsLike, alpha: FloatsLike) -> Floats:
    """Cam rotation angle phi at profile angle theta (Eq 17)."""
    return np.asarray(theta) - np.arcsin(np.clip(np.asarray(l) / r, -1, 1)) + alpha


def curvature_radius(r: FloatsLike, dr: FloatsLike, ddr: FloatsLike) -> Floats:
    """Radius of curvature of r(theta) (Eq 16)."""
    r, dr, ddr = np.asarray(r), np.asarray(dr), np.asarray(ddr)
    q = r * r + dr * dr
    return q * np.sqrt(q) / np.abs(r * r + 2 * dr * dr - r * ddr)


def contact_stress(force: FloatsLike, rho_cam: FloatsLike, rg: float, length: float,
                   z_e: float) -> Floats:
    """Hertz stress of a cam inside a ring, sigma_H = Z_E sqrt(F / (L rho_e)) with
    rho_e = rho1 rho2 / (rho1 - rho2), rho1 = rg (Eq 15); NaN where rho_cam >= rg
    (no internal contact: the profile is distorted)."""
    rho_cam = np.asarray(rho_cam)
    with np.errstate(divide="ignore", invalid="ignore"):
        rho_e = np.where(rho_cam < rg, rg * rho_cam / (rg - rho_cam), np.nan)
        return z_e * np.sqrt(np.asarray(force) / (length * rho_e))


def start_distance(r_st: FloatsLike, rg: float, kappa: FloatsLike) -> Floats:
    """|AO| at the initial position from the initial tangent angle (Eq 22)."""
    return np.sqrt(rg * rg + np.square(r_st) - 2 * rg * r_st * np.cos(kappa))


def angle_to_center(oa: FloatsLike, r: FloatsLike, rg: float) -> Floats:
    """Angle AOB for a profile point at radius r on the ring (law of cosines, Eqs 23, 31)."""
    oa, r = np.asarray(oa), np.asarray(r)
    return np.arccos(np.clip((oa * oa + r * r - rg * rg) / (2 * oa * r), -1, 1))


def total_profile_angle(oa: FloatsLike, r_st: float, r_end: FloatsLike, rg: float) -> Floats:
    """theta_a between the first and last contact points, both on the ring at the start
    (Eq 23)."""
    return angle_to_center(oa, r_st, rg) + angle_to_center(oa, r_end, rg)


def initial_profile_angle(oa: FloatsLike, r_st: float, e: FloatsLike, rg: float) -> Floats:
    """theta0 of the first contact point from the horizontal axis (Eq 24)."""
    return (np.pi / 2 - angle_to_center(oa, r_st, rg)
            + np.arccos(np.clip(np.asarray(e) / oa, -1, 1)))


def max_radius_on_ring(oa: FloatsLike, angle: FloatsLike, rg: float) -> Floats:
    """|OB| of the point at angle ``angle`` from OA on a circle of radius rg about A
    (Eq 32): the far intersection of the ray from O with the ring."""
    oa, c = np.asarray(oa), np.cos(angle)
    return oa * c + np.sqrt(np.clip(rg * rg + oa * oa * (c * c - 1), 0, None))
