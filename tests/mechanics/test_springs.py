"""Helical spring formulas (Clauss 1982 Eqs 21-22)."""

from __future__ import annotations

import pytest

from camopt.mechanics import springs


def test_rate_matches_eq86_constant():
    """Eq 86: k = 103.5 / x5 with x5 = N d, i.e. k N d = 103.5 N (G = 207 GPa as printed)."""
    k = springs.helical_rate(0.002, 0.02, 207e9, 7)
    assert k * 7 * 0.002 == pytest.approx(103.5, rel=1e-12)


def test_max_deflection_is_where_strength_ratio_is_one():
    k = 5000.0
    delta = springs.max_deflection(k, 0.002, 0.02, 1880e6, 0.186)
    assert springs.strength_ratio(k, delta, 0.002, 0.02, 1880e6, 0.186) == pytest.approx(1.0)
    # Eq 86 prints x4 = 4.739 x5, i.e. delta = 3.739 x5; with k = 103.5 / x5 this is 3.737
    assert delta * k / 103.5 == pytest.approx(3.739, rel=1e-3)
