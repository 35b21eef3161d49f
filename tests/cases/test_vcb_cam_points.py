"""A current cam as points (camopt/cases/vcb/cam_points.py) and designs from --set."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.calibration_report import design_of
from camopt.cases.vcb.cam_points import read_cam_points
from camopt.cases.vcb.problem import VcbProblem
from camopt.errors import ConfigError
from camopt.units import DEG, N_PER_MM
from tests.conftest import CONFIGS
from tests.helpers import load


@pytest.fixture(scope="module")
def problem():
    return VcbProblem(load(CONFIGS / "vcb.toml").case)


def _write(path, theta_deg, phi_deg, header="cam_angle_deg,follower_angle_deg"):
    path.write_text(header + "\n" + "".join(f"{a:.10f},{b:.10f}\n"
                                            for a, b in zip(theta_deg, phi_deg)))
    return path


def test_the_vendor_cam_exported_as_analysis_curves_reads_back(problem, tmp_path):
    """The analysis curves cam_angle_deg / follower_angle_deg of the vendor design (what
    export writes) give back the vendor's cubic a0..a3 to 1e-9 rad (Eq 9)."""
    curves = problem.curves(problem.vendor_x())
    path = _write(tmp_path / "cam.csv", curves["cam_angle_deg"], curves["follower_angle_deg"])
    a = read_cam_points(path, problem.model.theta_c[-1])
    np.testing.assert_allclose(a, problem.model.vendor_a, atol=1e-9)


def test_a_quintic_law_is_fitted_as_a_quintic(problem, tmp_path):
    a_true = np.r_[problem.model.vendor_a, 0.002, -0.0008]
    theta = np.linspace(0, 140, 71) * DEG
    phi = np.polynomial.polynomial.polyval(theta, a_true)
    path = _write(tmp_path / "q.csv", theta, phi, "cam_angle_rad,follower_angle_rad")
    np.testing.assert_allclose(read_cam_points(path, 140 * DEG), a_true, atol=1e-8)


def test_points_no_polynomial_follows_or_that_miss_the_stroke_are_refused(tmp_path):
    theta = np.linspace(0, 140, 71)
    wavy = 10 + 0.5 * np.sin(theta * DEG * 12)
    with pytest.raises(ConfigError, match="no polynomial law of degree 3 to 5"):
        read_cam_points(_write(tmp_path / "w.csv", theta, wavy), 140 * DEG)
    with pytest.raises(ConfigError, match="cover 0 to 70 deg; the stroke is 0 to 140"):
        read_cam_points(_write(tmp_path / "s.csv", theta[:36], wavy[:36]), 140 * DEG)
    with pytest.raises(ConfigError, match="cam angles must increase"):
        read_cam_points(_write(tmp_path / "d.csv", theta[::-1], wavy), 140 * DEG)


def test_a_design_from_points_is_the_design_from_coefficients(problem, tmp_path):
    curves = problem.curves(problem.vendor_x())
    path = _write(tmp_path / "cam.csv", curves["cam_angle_deg"], curves["follower_angle_deg"])
    c, m = problem.config, problem.model
    from_points = design_of(c, m, {"cam_points": str(path), "kc1_n_per_mm": "9.6"}, "x")
    reference = design_of(c, m, {}, "case")
    np.testing.assert_allclose(from_points.a, reference.a, atol=1e-9)
    assert from_points.kc[0] == pytest.approx(9.6 * N_PER_MM)
    assert reference.label == "reference" and "cam.csv" in from_points.label
    with pytest.raises(ConfigError, match="not both"):
        design_of(c, m, {"cam_points": str(path), "a1": "0.2"}, "x")
