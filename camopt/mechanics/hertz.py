"""Hertz line contact between two cylinders (Kang 2023 Eqs 27-31; Shigley 10th ed.)."""

from __future__ import annotations

import numpy as np

from camopt.mechanics import Floats, FloatsLike


def equivalent_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E_e from 1/E_e = ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) / 2 (Eq 29)."""
    return 2.0 / ((1 - nu1**2) / e1 + (1 - nu2**2) / e2)


def max_shear_stress(sigma_max: FloatsLike) -> Floats:
    """Largest shear stress beneath the surface of a line contact, tau_max = 0.304
    sigma_max (Eq 31; the stress field gives 0.300 at 0.786 b for nu = 0.3)."""
    return 0.304 * np.asarray(sigma_max)


def line_contact(force: FloatsLike, rho1: FloatsLike, rho2: FloatsLike, length: float,
                 e_eq: float) -> tuple[Floats, Floats, Floats]:
    """Half-width b (Eq 27), peak pressure sigma_max (Eq 30) and tau_max = 0.304 sigma_max
    (Eq 31, nu = 0.3) for a normal ``force`` over ``length``. A concave surface has a
    negative radius; a non-positive equivalent radius gives NaN (no Hertz contact)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        rho_e = 1.0 / (1.0 / np.asarray(rho1) + 1.0 / np.asarray(rho2))  # Eq 28
        rho_e = np.where(rho_e > 0, rho_e, np.nan)
        force = np.asarray(force)
        sigma = np.sqrt(force / rho_e * (e_eq / (2 * np.pi * length)))  # Eq 30 with Eq 27
        b = 2 * force / (np.pi * length * sigma)  # Eq 30 solved for b (Eq 27)
    return b, sigma, max_shear_stress(sigma)


def line_impact_force(energy: FloatsLike, rho1: FloatsLike, rho2: FloatsLike, length: float,
                      e_eq: float, iterations: int = 12) -> Floats:
    """Peak normal force (N) of an impact that stores ``energy`` (J) elastically in the line
    contact of two cylinders (radii ``rho1``, ``rho2``, m; a concave surface negative) over
    ``length`` (m), e.g. the Carnot loss of a plastic impact, which is the kinetic energy of
    the bodies' relative motion: 1/2 J* omega^2, J* = J_1 J_2 / (J_1 + J_2).

    A line contact has no power law between force and approach: the approach of the two
    cylinders' axes is (Johnson, Contact Mechanics, 1985, Sec 5.6; both bodies of the same
    material, E* = E_e / 2 of Eq 29)

        delta(F) = F / (pi L E*) (ln(4 R1 / b) + ln(4 R2 / b) - 1),   b of Eq 27,

    and with b = beta sqrt(F), delta = F (M - ln F) / (pi L E*). The energy stored up to F
    is W(F) = F^2 (M - 1/2 - ln F) / (2 pi L E*) (integral of F ddelta), solved for F by
    fixed point (the logarithm changes slowly: each iteration gains about two digits).
    Quasi-static (the contact's time is long against the bodies' wave transit) and
    elastic: an estimate of the peak load, not a contact simulation. NaN where there is no
    Hertz contact (equivalent radius <= 0)."""
    energy = np.maximum(np.asarray(energy, dtype=float), 0.0)
    r1, r2 = np.abs(np.asarray(rho1, dtype=float)), np.abs(np.asarray(rho2, dtype=float))
    e_star = e_eq / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        rho_e = 1.0 / (1.0 / np.asarray(rho1, dtype=float) + 1.0 / np.asarray(rho2, dtype=float))
        rho_e = np.where(rho_e > 0, rho_e, np.nan)
        beta = np.sqrt(4 * rho_e / (np.pi * length * e_star))  # Eq 27: b = beta sqrt(F)
        m = 2 * np.log(4.0) + np.log(r1 * r2) - 2 * np.log(beta) - 1
        scale = 2 * np.pi * length * e_star * energy
        force = np.sqrt(scale / np.maximum(m - 0.5 - np.log(np.sqrt(scale) + 1e-300), 1.0))
        for _ in range(iterations):
            force = np.sqrt(scale / np.maximum(m - 0.5 - np.log(np.maximum(force, 1e-300)),
                                               1.0))
    return np.where(energy > 0, force, 0.0)
