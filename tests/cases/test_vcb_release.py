"""The closing latch's release offset as a VCB design variable
(``release_offset_bounds_deg``): at the identified offset nothing changes; a later latch
turns springs the identified one holds; the band's sets move with the design's latch;
step 2 takes the step-1 design's latch; and the default tolerances include it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from camopt.cases.registry import get_case
from camopt.cases.vcb.config import CamDesign
from camopt.cases.vcb.dynamics import free_rotation, free_steps
from camopt.cases.vcb.problem import VcbProblem
from camopt.core.variation import applicable_defaults
from camopt.engine.driver import load
from camopt.errors import ConfigError
from camopt.units import DEG

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
VELOCITY_PAPER = CONFIGS / "reference" / "vcb_velocity_paper.toml"
LATCH = "case.release_offset_bounds_deg=[14.0,19.0]"


def latch_problem(*overrides: str) -> VcbProblem:
    return VcbProblem(load(VELOCITY_PAPER, [LATCH, *overrides]).case)


def test_the_identified_offset_evaluates_as_the_case_without_the_variable():
    fixed = VcbProblem(load(VELOCITY_PAPER).case)
    free = latch_problem()
    assert free.names[-1] == "release_offset_deg"
    x = fixed.vendor_x()
    np.testing.assert_array_equal(free.vendor_x(), np.r_[x, 14.07 * DEG])
    a, b = fixed.describe(x[None, :]), free.describe(free.vendor_x()[None, :])
    # the offset as a design column vs the config's scalar: two computations, to rounding
    np.testing.assert_allclose(b.f, a.f, rtol=1e-12)
    np.testing.assert_allclose(b.g, a.g, rtol=1e-12, atol=1e-12)
    for name in ("cam_contact_time_ms", "cam_contact_time_high_ms", "closing_velocity_high_m_s"):
        np.testing.assert_allclose(b.extras[name], a.extras[name], rtol=1e-12, atol=1e-12)


def test_a_later_latch_turns_springs_the_identified_one_holds():
    """Vendor springs 8 % soft: eps x their torque at 14.07 deg is below the identified
    friction (11.85 N m x 0.92 < 11.53 N m), so the cam never leaves the latch; at 17 deg
    (14.18 N m x 0.92) it does, under the identified set and every set of the band."""
    p = latch_problem()
    X = np.tile(p.vendor_x(), (2, 1))
    X[:, 3:5] *= 0.92
    X[:, -1] = np.array([14.07, 17.0]) * DEG
    ev = p.describe(X)
    assert np.isinf(ev.extras["cam_contact_time_ms"][0])
    assert np.isinf(ev.extras["cam_contact_time_high_ms"][0])
    assert np.isfinite(ev.extras["cam_contact_time_high_ms"][1])
    assert ev.extras["cam_contact_time_ms"][1] < 13.1  # less free rotation, more torque


def test_the_band_moves_with_the_design_latch():
    """Each set's release offset is its identified one plus the design's move: the
    band's slowest cam contact equals the slowest of the sets, each moved by hand."""
    p = latch_problem()
    x = p.vendor_x()
    x[-1] = 16.5 * DEG
    assert p.band is not None
    ev = p.describe(x[None, :])
    _, kc, _ = p.designs(x)
    moved = replace(p.band, release_offset_rad=np.ravel(p.band.release_offset_rad)
                    + (16.5 - 14.07) * DEG)
    k = len(np.ravel(p.band.cam_kg_m2))
    steps = free_steps(p.config.dynamics_steps)
    _, times = free_rotation(p.model, np.tile(kc, (k, 1)), moved, steps)
    _, nominal = free_rotation(p.model, kc, replace(p.dynamics, release_offset_rad=16.5 * DEG),
                               steps)
    assert ev.extras["cam_contact_time_high_ms"][0] == pytest.approx(
        max(times.max(), nominal[0]) * 1e3, rel=1e-12)
    assert ev.extras["cam_contact_time_low_ms"][0] == pytest.approx(
        min(times.min(), nominal[0]) * 1e3, rel=1e-12)


def test_designs_with_different_latches_evaluate_together_as_alone():
    """The band's sets are repeated set-major and each design's move tiled over them: a
    batch of designs with different latches and springs gives each design's band exactly
    as evaluated alone, to rounding (a design-major slip would give one design another's
    latch)."""
    p = latch_problem()
    X = np.tile(p.vendor_x(), (3, 1))
    X[:, -1] = np.array([15.0, 17.5, 18.9]) * DEG
    X[:, 3:5] *= np.array([[1.0, 1.0], [1.04, 0.97], [0.96, 1.05]])
    together = p.describe(X)
    for i in range(3):
        alone = p.describe(X[i:i + 1])
        np.testing.assert_allclose(together.g[i], alone.g[0], rtol=1e-9, atol=1e-12)
        for name in ("cam_contact_time_low_ms", "cam_contact_time_high_ms",
                     "closing_velocity_low_m_s", "closing_velocity_high_m_s",
                     "latch_kinetic_energy_low_j"):
            assert together.extras[name][i] == pytest.approx(alone.extras[name][0],
                                                             rel=1e-9), name


def test_step_two_takes_the_step_one_design_latch():
    c = load(VELOCITY_PAPER).case
    design = CamDesign(a1=0.24, a2=0.01, a3=-0.017, kc1_n_per_mm=7.72, kc2_n_per_mm=9.33,
                       release_offset_deg=16.0)
    step2 = VcbProblem(c.model_copy(update={"step": "fourbar", "cam_design": design}))
    assert step2.release_offset(step2.vendor_x()[None, :]) == pytest.approx(16.0 * DEG)
    unset = VcbProblem(c.model_copy(update={
        "step": "fourbar", "cam_design": design.model_copy(update={"release_offset_deg": None})}))
    assert unset.release_offset(unset.vendor_x()[None, :]) == pytest.approx(14.07 * DEG)


def test_the_default_tolerances_hold_the_latch_where_it_is_a_variable():
    tolerances = get_case("vcb").tolerances
    with_latch = {v.name for v in applicable_defaults(latch_problem(), tolerances, "t")}
    without = {v.name for v in applicable_defaults(
        VcbProblem(load(VELOCITY_PAPER).case), tolerances, "t")}
    assert with_latch - without == {"release_offset_deg"}


@pytest.mark.parametrize("bounds", ["[0.0,10.0]", "[10.0,90.0]", "[-5.0,10.0]"])
def test_a_latch_not_past_its_dead_centre_is_refused(bounds):
    with pytest.raises(ConfigError, match="release_offset_bounds_deg"):
        load(VELOCITY_PAPER, [f"case.release_offset_bounds_deg={bounds}"])


@pytest.mark.parametrize("field, value", [("release_offset_bounds_deg", "[14.0,19.0]"),
                                          ("a4_bounds", "[-0.01,0.01]")])
def test_step_one_variables_in_a_step_two_case_are_refused(field, value):
    """Step 2 takes the cam design (law and latch) from step 1; its own bounds for them
    would be silently ignored, so they are refused."""
    with pytest.raises(ConfigError, match=f"{field}: a step-1"):
        load(CONFIGS / "vcb_fourbar.toml", [f"case.{field}={value}"])
