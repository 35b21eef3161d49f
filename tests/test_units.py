"""Unit factors (camopt/units.py): each TOML unit to SI, and the display factors back, exact
reciprocals so an output converted with them equals the bare literal it replaced."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camopt import units


@pytest.mark.parametrize("to_unit, to_si, literal", [
    (units.TO_MM, units.MM, 1e3), (units.TO_MS, units.MS, 1e3),
    (units.TO_DEG, units.DEG, 180 / math.pi), (units.TO_N_PER_MM, units.N_PER_MM, 1e-3)])
def test_display_factors_are_exact_reciprocals(to_unit, to_si, literal):
    """x * TO_MM is bit for bit x * 1e3 (the archives before and after are identical), and
    a round trip through SI returns the value to within one rounding."""
    assert to_unit == literal
    x = np.random.default_rng(0).uniform(-10, 10, 1000)
    np.testing.assert_array_equal(x * to_unit, x * literal)
    np.testing.assert_allclose(x * to_si * to_unit, x, rtol=2e-16 * 2)


def test_engineering_units_to_si():
    """One spring rate, one stress, one modulus, one Hertz coefficient, worked by hand."""
    assert 2.5 * units.N_PER_MM == pytest.approx(2500.0, rel=1e-15)  # 2.5 N/mm = 2500 N/m
    assert 190.0 * units.SQRT_MPA == pytest.approx(190.0 * math.sqrt(1e6), rel=1e-15)
    assert 210.0 * units.GPA == 2.1e11 and 400.0 * units.MPA == 4e8
    assert 3.0 * units.KN == 3000.0 and 90 * units.DEG == pytest.approx(math.pi / 2)
