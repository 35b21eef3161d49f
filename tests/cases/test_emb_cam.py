"""EMB cam against Yan, Chen, Yan & Hang (2023), Sec 3.1 and 4.4."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from camopt.driver import execute
from tests.conftest import CONFIGS
from tests.helpers import load


@pytest.fixture(scope="module")
def emb():
    return execute(load(CONFIGS / "emb.toml"))


def test_ideal_screw_of_the_paper(reported):
    """Eqs 45-46 with the paper's numbers: lead 2.40 mm gives 19.10 N m and 2.62 rad (the
    paper prints 19.06 N m: its lead is 2.396 mm before rounding)."""
    e = reported["emb_cam"]
    lead = e["screw_lead_mm"] * 1e-3
    assert 50e3 * lead / (2 * np.pi) == pytest.approx(e["screw_peak_torque_nm"], rel=5e-3)
    assert 2 * np.pi * 1e-3 / lead == pytest.approx(e["screw_clearance_angle_rad"], abs=5e-3)


@pytest.mark.slow
def test_paper_headline_reached_or_beaten(emb, reported):
    """Sec 4.4 with the same inputs: lift 2.000 +- 0.002 mm, rotation no more than the
    2.40 mm-lead screw's, no distortion (rho <= r_g), stress within the allowable, peak
    torque <= 7.72 N m and clearance angle <= 1.72 rad."""
    m, e = emb.metrics, reported["emb_cam"]
    assert emb.best.feasible
    assert m["lift_mm"] == pytest.approx(2.0, abs=0.002 + 1e-12)
    assert m["max_rotation_rad"] <= 2 * np.pi * 2.0 / 2.40 + 1e-9
    assert m["curvature_max_mm"] <= 20.0
    assert m["contact_stress_max_mpa"] <= emb.problem.config.allowable_stress_mpa
    assert m["peak_torque_nm"] <= e["peak_torque_nm"]
    assert m["clearance_angle_rad"] <= e["clearance_angle_rad"]


@pytest.mark.slow
def test_paper_objective_reaches_4p7(emb):
    """Issue #13: on the paper's own objective (Eq 29 with the assumed weights) the search
    reaches fitness <= 4.7 with the lift held at 2.000 +- 0.002 mm (an independent scipy
    DE over the same particle found 4.57; the swarm alone stopped at 5.8-6.9)."""
    assert emb.best.feasible
    assert emb.best.fun <= 4.7
    assert abs(emb.metrics["lift_mm"] - 2.0) <= 0.002 + 1e-12


@pytest.mark.slow
def test_self_consistency_eq44(emb):
    """Eq 44: T/F and ds/dphi agree within 1 % over the clamping section."""
    assert emb.metrics["consistency_error_pct"] < 1.0


@pytest.mark.slow
def test_physical_floor(emb):
    """The caliper absorbs K x2^4 / 4 = 12.5 J over the clamping rotation: no peak torque
    can be below the flat floor, and the ramp floor is twice it."""
    m = emb.metrics
    left = m["max_rotation_rad"] - m["clearance_angle_rad"]
    assert m["torque_floor_flat_nm"] == pytest.approx(12.5 / left, rel=1e-9)
    assert m["torque_floor_ramp_nm"] == pytest.approx(2 * m["torque_floor_flat_nm"])
    assert m["peak_torque_nm"] >= m["torque_floor_flat_nm"]


@pytest.mark.slow
def test_corrections_help(reported):
    """Improved PSO against plain PSO (same budget, 3 seeds here; 10 in bench/): the
    corrections give more feasible runs and a better median fitness."""
    def runs(repair: bool):
        cfg = load(CONFIGS / "emb.toml", f"solver.repair={str(repair).lower()}",
                   "solver.iterations=150", "solver.particles=60", "run.repeats=3")
        swarm = cfg.solver.model_copy(update={"polish": None})  # the swarms alone
        return execute(replace(cfg, solver=swarm)).repeats

    improved, plain = runs(True), runs(False)
    feas = [sum(r.feasible for r in rs) for rs in (improved, plain)]
    assert feas[0] > feas[1]
    assert np.median([r.fun for r in improved]) < np.median([r.fun for r in plain])


@pytest.mark.slow
def test_straight_ramp_at_or_below_5p2_nm():
    """Beyond the paper (issue #13): configs/emb_linear.toml as run (6 repeats): same
    inputs and constraints, torque a straight ramp over the clamping section (RMS <= 3 %
    of the peak), clearance <= 1.72 rad, lift 2.000 +- 0.002 mm, and peak <= 5.2 N m (an
    independent scipy DE found 5.12 N m; the earlier SLSQP polish stopped at 5.40 N m at
    the loose 1.990 mm lift)."""
    rec = execute(load(CONFIGS / "emb_linear.toml"))
    m = rec.metrics
    assert rec.best.feasible
    assert m["peak_torque_nm"] <= 5.2
    assert m["torque_ramp_rms_pct"] <= 3.0 + 1e-9
    assert m["clearance_angle_rad"] <= 1.72
    assert abs(m["lift_mm"] - 2.0) <= 0.002 + 1e-12
    assert m["max_rotation_rad"] <= 2 * np.pi * 2.0 / 2.40 + 1e-9
    assert m["curvature_max_mm"] <= 20.0 + 1e-9


def test_swarm_evaluation_is_row_independent():
    cfg = load(CONFIGS / "emb.toml")
    from camopt.cases.emb_cam import EmbCamProblem

    p = EmbCamProblem(cfg.case)
    rng = np.random.default_rng(1)
    X = p.lower + rng.random((30, p.n_var)) * (p.upper - p.lower)
    X = p.repair(X, rng, {k: 1.0 for k in p.repair_schedule()})
    whole = p.evaluate(X)
    for i in (0, 11, 29):
        one = p.evaluate(X[i : i + 1])
        assert one.f[0] == pytest.approx(whole.f[i], rel=1e-12)
