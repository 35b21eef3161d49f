"""Hertz line contact (Kang 2023 Eqs 27-31) against the textbook solution.

Two parallel cylinders pressed by a force F over a length l (Shigley, Mechanical
Engineering Design, 10th ed., Sec 3-19, Eqs 3-73 and 3-74; Johnson, Contact Mechanics,
Sec 4.2): half-width b = sqrt(2 F / (pi l) * ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) /
(1/d1 + 1/d2)), peak pressure p_max = 2 F / (pi b l). Beneath the surface on the load
axis the principal stresses are (z = depth, zeta = z / b)
  sigma_x = -2 nu p_max (sqrt(1 + zeta^2) - zeta)
  sigma_y = -p_max ((1 + 2 zeta^2) / sqrt(1 + zeta^2) - 2 zeta)
  sigma_z = -p_max / sqrt(1 + zeta^2)
and the largest shear stress is 0.300 p_max at z = 0.786 b (Shigley's Fig 3-38).
"""

from __future__ import annotations

import numpy as np
import pytest

from camopt.mechanics import hertz


def shigley_line_contact(force, d1, d2, length, e1, nu1, e2, nu2):
    """b and p_max written straight from Shigley's Eqs 3-73 and 3-74 (diameters)."""
    b = np.sqrt(2 * force / (np.pi * length)
                * ((1 - nu1**2) / e1 + (1 - nu2**2) / e2) / (1 / d1 + 1 / d2))
    return b, 2 * force / (np.pi * b * length)


def subsurface_tau_max(p_max, nu):
    """Largest (sigma_1 - sigma_3)/2 along the load axis, by sampling the depth."""
    zeta = np.linspace(0, 3, 300001)
    root = np.sqrt(1 + zeta**2)
    sx = -2 * nu * p_max * (root - zeta)
    sy = -p_max * ((1 + 2 * zeta**2) / root - 2 * zeta)
    sz = -p_max / root
    s = np.sort(np.stack([sx, sy, sz]), axis=0)
    tau = (s[2] - s[0]) / 2
    i = np.argmax(tau)
    return tau[i], zeta[i]


CASES = [  # force N, radii m, length m, E Pa, nu: steel roller on steel cam, and unequal
    (5000.0, 0.015, 0.040, 0.015, 210e9, 0.3, 210e9, 0.3),
    (1200.0, 0.005, 0.120, 0.008, 207e9, 0.29, 110e9, 0.33),
]


@pytest.mark.parametrize("case", CASES)
def test_half_width_and_peak_pressure_match_shigley(case):
    force, r1, r2, length, e1, nu1, e2, nu2 = case
    e_eq = hertz.equivalent_modulus(e1, nu1, e2, nu2)
    b, sigma, _ = hertz.line_contact(force, r1, r2, length, e_eq)
    b_ref, p_ref = shigley_line_contact(force, 2 * r1, 2 * r2, length, e1, nu1, e2, nu2)
    assert b == pytest.approx(b_ref, rel=1e-12)
    assert sigma == pytest.approx(p_ref, rel=1e-12)


def test_eq31_shear_factor_matches_the_subsurface_stress_field():
    """Eq 31's tau_max = 0.304 sigma_max against the stress field's own maximum (0.300 at
    z = 0.786 b for nu = 0.3): within 1.5 %, so a wrong factor (0.35, 0.25) fails."""
    force, r1, r2, length, e, nu = 5000.0, 0.015, 0.040, 0.015, 210e9, 0.3
    _, sigma, tau = hertz.line_contact(force, r1, r2, length,
                                       hertz.equivalent_modulus(e, nu, e, nu))
    tau_ref, depth = subsurface_tau_max(sigma, nu)
    assert tau_ref / sigma == pytest.approx(0.300, abs=1e-3)
    assert depth == pytest.approx(0.786, abs=2e-3)
    assert tau == pytest.approx(tau_ref, rel=0.015)


def test_concave_surface_and_no_contact():
    """A concave radius (negative) larger than the roller still gives contact; a concave
    radius smaller than the roller cannot (NaN, no Hertz contact)."""
    e_eq = hertz.equivalent_modulus(210e9, 0.3, 210e9, 0.3)
    _, conformal, _ = hertz.line_contact(1000.0, -0.05, 0.015, 0.01, e_eq)
    _, convex, _ = hertz.line_contact(1000.0, 0.05, 0.015, 0.01, e_eq)
    assert 0 < conformal < convex
    _, none, _ = hertz.line_contact(1000.0, -0.010, 0.015, 0.01, e_eq)
    assert np.isnan(none)


@pytest.mark.parametrize("rho_cam", [0.03, -0.08, 0.2])
@pytest.mark.parametrize("energy", [0.01, 0.3, 5.0])
def test_impact_force_stores_the_energy_in_the_cylinders_approach(rho_cam, energy):
    """The peak force of an impact stores ``energy`` in the contact: the integral of F over
    the approach of two cylinders' axes (Johnson, Contact Mechanics, Sec 5.6: delta = F /
    (pi l E*) (ln(4 R1 / b) + ln(4 R2 / b) - 1)), taken here by the trapezoidal rule on a
    fine grid of forces, equals ``energy`` to 1e-6; a convex, a concave and a flat cam."""
    rf, length = 0.015, 0.015
    e_eq = hertz.equivalent_modulus(210e9, 0.3, 210e9, 0.3)
    force = float(hertz.line_impact_force(energy, rho_cam, rf, length, e_eq))
    rho_e = 1 / (1 / rho_cam + 1 / rf)
    grid = np.geomspace(force * 1e-12, force, 400_001)
    b = np.sqrt(4 * grid * rho_e / (np.pi * length * e_eq / 2))
    delta = grid / (np.pi * length * e_eq / 2) * (np.log(4 * abs(rho_cam) / b)
                                                 + np.log(4 * rf / b) - 1)
    stored = np.sum(0.5 * (grid[1:] + grid[:-1]) * np.diff(delta))
    assert stored == pytest.approx(energy, rel=1e-6)
    assert hertz.line_impact_force(0.0, rho_cam, rf, length, e_eq) == 0.0
