"""Disc cam with an oscillating roller follower (Kang 2023 Eqs 6-15), each equation at a
non-degenerate point against an independent calculation: the cubic law by hand algebra,
the pitch curve (Eq 9) by placing the roller centre with vectors, its derivatives (Eq 12)
and its curvature (Eq 15) by central differences of that construction, the pressure
angle (Eqs 13-14) as the angle between the pitch-curve normal and the roller centre's
velocity, and the contact stress it feeds by Shigley's line-contact formula."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.mechanics import cam

# a VCB-sized cam: follower pivot 100 mm from the cam pivot, arm 80 mm, base circle 40 mm,
# roller 12 mm; cubic follower law with every coefficient non-zero, so phi'' = 2 a2 + 6 a3 t
# changes sign on the grid and no term can drop out unnoticed
L2, L6, RB, RF = 0.080, 0.100, 0.040, 0.012
A = np.array([[0.01, 0.05, 0.15, -0.03]])
THETA = np.array([0.3, 0.7, 1.3, 1.9, 2.4])  # rad, none of them 0 or 1


def xi() -> float:
    """Eq 10 by the law of cosines written out: |OD|^2 = l2^2 + l6^2 - 2 l2 l6 cos xi."""
    return float(np.arccos((L2**2 + L6**2 - (RB + RF) ** 2) / (2 * L2 * L6)))


def phi_by_hand(t):
    a0, a1, a2, a3 = A[0]
    return a0 + a1 * t + a2 * t**2 + a3 * t**3


def roller_centre(theta):
    """Roller centre D in the cam's frame: B sits at angle theta at distance l6 from O,
    and D is l2 from B at angle theta - xi - phi(theta) back toward O (Eq 9 by vectors)."""
    b = L6 * np.array([np.cos(theta), np.sin(theta)])
    u = theta - xi() - phi_by_hand(theta)
    return b - L2 * np.array([np.cos(u), np.sin(u)])


def follower() -> cam.Follower:
    return cam.Follower.polynomial(A, THETA, xi())


def test_base_angle_is_the_law_of_cosines():
    """Eq 10 at the paper's construction: with phi = 0 the roller centre is rb + rf from O."""
    assert cam.base_angle(L2, L6, RB + RF) == pytest.approx(xi(), rel=1e-14)
    f = cam.Follower.polynomial(np.zeros((1, 4)), THETA, xi())
    xp, yp, _, _ = cam.pitch_curve(L2, L6, f)
    np.testing.assert_allclose(np.hypot(xp, yp), RB + RF, rtol=1e-12)


def test_cubic_law_and_its_derivatives_by_hand():
    """Eq 6 and the two derivatives Eqs 12 and 15 use: phi' = a1 + 2 a2 t + 3 a3 t^2,
    phi'' = 2 a2 + 6 a3 t (the phi'' term is what Eq 15's curvature and the peak stress
    depend on)."""
    a0, a1, a2, a3 = A[0]
    f = follower()
    t = THETA
    np.testing.assert_allclose(f.phi[0], phi_by_hand(t), rtol=1e-13)
    np.testing.assert_allclose(f.dphi[0], a1 + 2 * a2 * t + 3 * a3 * t**2, rtol=1e-13)
    np.testing.assert_allclose(f.ddphi[0], 2 * a2 + 6 * a3 * t, rtol=1e-13)
    np.testing.assert_allclose(f.cos_a[0], np.cos(xi() + phi_by_hand(t)), atol=1e-15)
    np.testing.assert_allclose(f.sin_a[0], np.sin(xi() + phi_by_hand(t)), atol=1e-15)


def test_pitch_curve_eq9_and_its_derivatives_eq12():
    """Eq 9 against the vector construction; Eq 12 against its central differences."""
    xp, yp, dxp, dyp = cam.pitch_curve(L2, L6, follower())
    d = roller_centre(THETA)
    np.testing.assert_allclose(xp[0], d[0], atol=1e-14)
    np.testing.assert_allclose(yp[0], d[1], atol=1e-14)
    h = 1e-6
    fd = (roller_centre(THETA + h) - roller_centre(THETA - h)) / (2 * h)
    np.testing.assert_allclose(dxp[0], fd[0], rtol=1e-7, atol=1e-11)
    np.testing.assert_allclose(dyp[0], fd[1], rtol=1e-7, atol=1e-11)


def pitch_curvature_by_differences(theta):
    """Signed radius of curvature of the pitch curve, (x'^2 + y'^2)^1.5 / (x'y'' - y'x''),
    from central differences of the vector construction (positive where convex)."""
    h = 1e-4
    lo, mid, hi = roller_centre(theta - h), roller_centre(theta), roller_centre(theta + h)
    d1 = (hi - lo) / (2 * h)
    d2 = (hi - 2 * mid + lo) / h**2
    return (d1[0] ** 2 + d1[1] ** 2) ** 1.5 / (d1[0] * d2[1] - d1[1] * d2[0])


def test_profile_curvature_eq15_is_the_pitch_curvature_less_the_roller():
    """Eq 15 (with the phi'' term) against the curvature of the pitch curve by differences;
    with phi'' dropped the radius moves by percent, far beyond the 1e-6 tolerance."""
    rho = cam.curvature_radius(L2, L6, follower(), RF)[0]
    np.testing.assert_allclose(rho, pitch_curvature_by_differences(THETA) - RF, rtol=1e-6)
    assert np.all(np.abs(rho) > 5 * RF)  # a non-degenerate, well-conditioned point


def test_base_circle_curvature_is_the_base_radius():
    """On the base circle (phi = 0) Eq 15 gives rb: pitch radius rb + rf less rf."""
    f = cam.Follower.polynomial(np.zeros((1, 4)), THETA, xi())
    np.testing.assert_allclose(cam.curvature_radius(L2, L6, f, RF), RB, rtol=1e-12)


def _swing_angle(a: np.ndarray) -> np.ndarray:
    """The angle between the pitch-curve normal at D and the direction D moves in as the
    follower swings (perpendicular to BD), both in the cam's frame, for the cubic ``a``
    (4,) at THETA: the tangent by central differences of D built by vectors."""
    def centre(theta):
        u = theta - xi() - np.polyval(a[::-1], theta)
        return L6 * np.array([np.cos(theta), np.sin(theta)]) - L2 * np.array([np.cos(u),
                                                                               np.sin(u)])
    h = 1e-6
    tangent = (centre(THETA + h) - centre(THETA - h)) / (2 * h)
    normal = np.array([-tangent[1], tangent[0]]) / np.hypot(*tangent)
    u = THETA - xi() - np.polyval(a[::-1], THETA)
    swing = np.array([-np.sin(u), np.cos(u)])  # unit, perpendicular to BD
    return np.arccos(np.abs(np.sum(normal * swing, axis=0)))


@pytest.mark.parametrize("a", [A[0], np.array([0.01, 1.3, 0.15, -0.03])])
def test_pressure_angle_against_the_velocity_direction(a):
    """|psi| is the angle between the pitch-curve normal at D and the direction D moves in
    (:func:`_swing_angle`): for the test's gentle law (phi' < 1) and a steep one (phi' from
    1.3 to 1.9), where the paper's Eqs 13-14 take the wrong branch of their arcsin."""
    f = cam.Follower.polynomial(a[None, :], THETA, xi())
    psi = cam.pressure_angle(L2, L6, f)[0]
    np.testing.assert_allclose(np.abs(psi), _swing_angle(a), atol=1e-7)
    assert np.abs(psi).max() > np.radians(10)


def test_pressure_angle_is_eqs13_14_below_a_unit_follower_rate():
    """For phi' < 1 the pressure angle is the paper's psi = pi/2 - eta - xi - phi through
    the instant centre (Eqs 13-14 written out here); at phi' = 1.3 Eq 14 reads 26.3 deg
    where the geometry gives 45.6 deg (the first node: a steep law passed 45 deg)."""
    def eqs13_14(f):
        oi = L6 * f.dphi / (1 - f.dphi)  # Eq 13: the instant centre
        id_ = np.sqrt(L2**2 + (oi + L6) ** 2 - 2 * L2 * (oi + L6) * f.cos_a)
        return np.pi / 2 - np.arcsin(np.clip(L2 * f.sin_a / id_, -1, 1)) - f.angle  # Eq 14
    gentle = follower()
    assert gentle.dphi.max() < 1
    np.testing.assert_allclose(cam.pressure_angle(L2, L6, gentle), eqs13_14(gentle),
                               rtol=1e-12, atol=1e-14)
    steep = cam.Follower.polynomial(np.array([[0.01, 1.3, 0.0, 0.0]]), THETA, xi())
    gap = np.abs(cam.pressure_angle(L2, L6, steep)) - np.abs(eqs13_14(steep))
    assert np.radians(5) < np.abs(gap).max()


def test_profile_eq11_offsets_the_pitch_curve_by_the_roller():
    xp, yp, dxp, dyp = cam.pitch_curve(L2, L6, follower())
    x, y = cam.profile(xp, yp, dxp, dyp, RF)
    np.testing.assert_allclose(np.hypot(x - xp, y - yp), RF, rtol=1e-12)
    # the offset is normal to the pitch curve
    np.testing.assert_allclose((x - xp) * dxp + (y - yp) * dyp, 0.0, atol=1e-15)


def test_peak_stress_follows_the_curvature_with_phi_double_prime():
    """The curvature feeds Hertz's Eq 30 (sigma = sqrt(F E_e / (2 pi L rho_e)) with
    1/rho_e = 1/rho + 1/rf): the stress from Eq 15 equals the stress from the curvature by
    differences (Shigley's line contact written out)."""
    from camopt.mechanics import hertz

    force, length, e_eq = 4000.0, 0.02, 2.3e11
    rho = cam.curvature_radius(L2, L6, follower(), RF)[0]
    _, sigma, _ = hertz.line_contact(force, rho, RF, length, e_eq)
    rho_ref = pitch_curvature_by_differences(THETA) - RF
    rho_e = 1 / (1 / rho_ref + 1 / RF)
    np.testing.assert_allclose(sigma, np.sqrt(force * e_eq / (2 * np.pi * length * rho_e)),
                               rtol=1e-6)


def test_quintic_law_and_its_derivatives_by_hand():
    """The law beyond the paper's cubic (degree 5, every term non-zero): phi, phi' and
    phi'' against the polynomial written out term by term."""
    a = np.array([[0.01, 0.05, 0.15, -0.03, 0.004, -0.0007]])
    f = cam.Follower.polynomial(a, THETA, xi())
    t = THETA
    c = a[0]
    phi = sum(c[k] * t**k for k in range(6))
    dphi = sum(k * c[k] * t ** (k - 1) for k in range(1, 6))
    ddphi = sum(k * (k - 1) * c[k] * t ** (k - 2) for k in range(2, 6))
    np.testing.assert_allclose(f.phi[0], phi, rtol=1e-13)
    np.testing.assert_allclose(f.dphi[0], dphi, rtol=1e-13)
    np.testing.assert_allclose(f.ddphi[0], ddphi, rtol=1e-13)
