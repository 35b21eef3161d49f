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
