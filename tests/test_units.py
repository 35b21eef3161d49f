"""Unit factors (camopt/units.py): each TOML unit to SI, and the display factors back, exact
reciprocals so an output converted with them equals the bare literal it replaced."""

from __future__ import annotations

import math
import re
from pathlib import Path

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


def test_numpy_and_math_angle_conversions_equal_the_factors():
    """``x * DEG`` and ``x * TO_DEG`` are bit for bit ``np.radians``/``np.degrees``
    and ``math.degrees``, which they replaced (issue #37)."""
    x = np.random.default_rng(1).uniform(-400, 400, 1000)
    np.testing.assert_array_equal(x * units.DEG, np.radians(x))
    np.testing.assert_array_equal(x * units.TO_DEG, np.degrees(x))
    assert all(math.degrees(v) == v * units.TO_DEG for v in x.tolist())


LITERAL_FACTOR = re.compile(r"[*/] ?(1e3|1e6|1e9|1000\.?0?)\b(?! ?\*\*)|np\.(radians|degrees|"
                            r"deg2rad|rad2deg)\(|math\.(radians|degrees)\(|pi ?/ ?180\b")


def test_no_literal_unit_factor_in_the_package():
    """Unit conversions name their unit (camopt/units.py): no bare ``* 1e3``, ``/ 1e6``,
    ``* 1e9``, ``np.radians`` or ``pi / 180`` outside units.py (issue #37)."""
    root = Path(units.__file__).parent
    found = [f"{p.relative_to(root)}:{i}: {line.strip()}"
             for p in sorted(root.rglob("*.py")) if p.name != "units.py"
             for i, line in enumerate(p.read_text().splitlines(), 1)
             if LITERAL_FACTOR.search(line.split("#")[0])]
    assert not found, "\n".join(found)
