"""A current cam as points (camopt/cases/vcb/cam_points.py) and designs from --set."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.calibration_run import design_of
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


def _case_with_points(tmp_path, problem, a=None, extra=""):
    """A case file extending configs/vcb.toml whose reference cam is a points file beside
    it (the vendor's law unless ``a``), named relative to the case file."""
    a = problem.model.vendor_a if a is None else np.asarray(a)
    theta = np.linspace(0, 140, 71)
    _write(tmp_path / "current_cam.csv", theta,
           np.polynomial.polynomial.polyval(theta * DEG, a) / DEG)
    case = tmp_path / "mine.toml"
    case.write_text(f'extends = "{CONFIGS / "vcb.toml"}"\n[case]\n'
                    'reference_label = "my breaker, drawing 4711 rev B"\n'
                    f'reference_cam_points = "current_cam.csv"\n{extra}')
    return case


def test_the_reference_cam_is_imported_from_a_points_file(problem, tmp_path, monkeypatch):
    """reference_cam_points (relative to the case file) becomes the case's reference law:
    the vendor's points give the vendor's reference design and metrics back; a cam with
    a quartic term is the reference once the search's law reaches its degree."""
    from camopt.cli.app import load_case

    monkeypatch.chdir(tmp_path.parent)  # not the case file's folder
    config = load_case(_case_with_points(tmp_path, problem)).case
    np.testing.assert_allclose(config.reference_law, problem.model.vendor_a, atol=1e-9)
    mine = VcbProblem(config)
    np.testing.assert_allclose(mine.vendor_x(), problem.vendor_x(), rtol=1e-9, atol=1e-12)
    quartic = np.r_[problem.model.vendor_a, 0.002]
    path = _case_with_points(tmp_path, problem, quartic, "a4_bounds = [-0.01, 0.01]\n")
    mine = VcbProblem(load_case(path).case)
    np.testing.assert_allclose(mine.model.vendor_a, quartic, atol=1e-9)
    assert mine.vendor_x()[5] == pytest.approx(0.002, abs=1e-9)  # a4 after kc1, kc2


@pytest.mark.parametrize("a_change, extra, message", [
    (np.r_[0.0, 0.0, 0.0, 0.0, 0.002], "", "has degree 4: set a4_bounds"),
    (np.r_[1.0 * DEG, 0.0, 0.0, 0.0], "", "a cam of another geometry?"),
])
def test_a_reference_cam_the_case_cannot_use_is_one_line(problem, tmp_path, a_change, extra,
                                                         message):
    from typer.testing import CliRunner

    from camopt.cli import app

    a = np.r_[problem.model.vendor_a, 0.0][:len(a_change)] + a_change
    path = _case_with_points(tmp_path, problem, a, extra)
    result = CliRunner().invoke(app, ["validate", str(path)])
    assert result.exit_code == 2, result.output
    assert message in result.stderr and result.stderr.count("\n") == 1
    missing = tmp_path / "missing.toml"
    missing.write_text(f'extends = "{CONFIGS / "vcb.toml"}"\n[case]\n'
                       'reference_cam_points = "nowhere.csv"\n')
    result = CliRunner().invoke(app, ["validate", str(missing)])
    assert result.exit_code == 2
    assert "case.reference_cam_points: nowhere.csv: no such file" in result.stderr
