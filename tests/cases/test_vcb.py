"""VCB closing mechanism against Kang, Huang & Yang (2023)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt import archive
from camopt.cases.vcb import VcbConfig, VcbProblem
from camopt.cases.vcb.model import follower_dwell
from camopt.engine.driver import execute
from camopt.mechanics import cam
from camopt.units import MM
from tests.conftest import CONFIGS
from tests.helpers import load


@pytest.fixture(scope="module")
def problem():
    return VcbProblem(load(CONFIGS / "vcb.toml").case)


def test_l6_from_pivots(problem):
    """Sec 2.3: l6 = 90.6035 mm from B(-72, -55) and O(0, 0)."""
    assert problem.model.l6 / MM == pytest.approx(90.6035, abs=5e-5)


def test_s2bar_and_theta4bar():
    """Eq 1: s2bar = (l4/l5) s1bar / alpha + beta + gamma = 29.20 mm; Eq 4: theta4bar."""
    c = VcbConfig()
    s2bar = (c.l4_mm / c.l5_mm) * c.s1_bar_mm / c.alpha + c.beta_mm + c.gamma_mm
    assert s2bar == pytest.approx(29.20, abs=5e-3)
    assert np.degrees(2 * np.arcsin(s2bar / (2 * c.l4_mm))) == pytest.approx(11.97, abs=0.01)


def test_initial_cubic_coefficients(problem, reported):
    """Sec 2.3: a0..a3 = 0.015185, 0.240347, 0.011694, -0.017243, each within 1e-5,
    computed from the vendor data (Eqs 1-8, Step 9) in the documented reading."""
    expected = reported["vcb"]["initial_cubic"]
    got = problem.model.vendor_a
    for i, key in enumerate(("a0", "a1", "a2", "a3")):
        assert got[i] == pytest.approx(expected[key], abs=1e-5), key


def test_literal_clearance_does_not_reproduce_a0(problem):
    """Eq 8 with beta = 2 mm as printed gives a0 = 0.030, not 0.015185."""
    m = problem.model
    literal = cam.base_angle(m.l2, m.l6, m.rb + m.rf + 2 * MM) - m.xi
    assert abs(literal - 0.015185) > 0.01


def test_initial_design_findings(problem):
    """Sec 2.3: pressure angle below 45 deg, curvature above rf = 15 mm (no undercut);
    Sec 2.4 / Fig 20: tau_max above the 1194 MPa shear yield (vendor design infeasible)."""
    m = problem.metrics(problem.vendor_x())
    assert m["pressure_angle_max_deg"] < 45
    assert m["curvature_min_mm"] > 15
    assert m["tau_max_mpa"] > 1194
    assert m["feasible"] == 0.0


def test_table7_output_ranges(reported):
    """Sec 4.3 / Fig 15: output link range about [-8, 4] deg initially and [-6, 6] deg for
    Table 7's linkage; our kinematics within 1 deg of the values read off the figure."""
    cfg = load(CONFIGS / "reference" / "vcb_table7.toml")
    rec = execute(cfg)
    rows = rec.best.table
    expected = reported["vcb"]["output_range_deg"]
    for row, key in zip(rows, ("initial", "optimum")):
        lo, hi = sorted([row["output_start_deg"], row["output_end_deg"]])
        assert lo == pytest.approx(expected[key][0], abs=1.0)
        assert hi == pytest.approx(expected[key][1], abs=1.0)


def test_virtual_work_sum_converges_to_the_exact_driving_work(problem):
    """Eq 25's sum of Fo ds = T dtheta on a fine grid converges to the closing springs'
    energy released (the exact driving work the model reports): the torque is the
    energy's derivative, so the two readings of Eq 23 agree."""
    c = problem.config
    fine = VcbProblem(c.model_copy(update={"positions": 20000}))
    m = fine.model
    x = fine.vendor_x()
    _, kc, _ = fine.designs(x)
    torque = m.closing_torque(kc)[0]
    midpoint = 0.5 * (torque[1:] + torque[:-1]) * m.dtheta
    exact = fine.evaluate(x[None, :]).extras["driving_work_j"][0]
    assert midpoint.sum() == pytest.approx(exact, rel=1e-6)


def test_resistant_work_is_the_integral_of_fr(problem):
    """The exact resistant work (potential of Fr, Eq 24) equals the integral of the sampled
    Fr over the rod travel on a fine grid, whose only error is the touch interval."""
    m = problem.model
    loads = problem.load
    s = np.linspace(0.0, 18.0 * MM, 200001)
    fr = loads.resistant_force(s)
    numeric = np.sum(0.5 * (fr[1:] + fr[:-1]) * np.diff(s))
    assert loads.resistant_energy(np.array([18.0 * MM]))[0] == pytest.approx(numeric, abs=2e-3)
    assert m.c.contact_gap_mm == 11.0


def test_works_and_stress_do_not_depend_on_the_sample_count():
    """Issue #10: surplus, rod travel, phi_max and tau_max of fixed designs at 140 and 5,600
    positions agree (surplus within 0.02 J); Eq 39's sum grows with Ns (a sum, not a
    force) and the vendor's stress is reported unbounded (follower dwell), not a grid value."""
    designs = np.array([[0.2043, 1.79e-06, -0.00672857, 4329.4, 4252.71],
                        [0.238432, 0.000226, -0.011492, 9315.336, 7788.183]])
    out = {}
    for ns in (140, 5600):
        p = VcbProblem(load(CONFIGS / "vcb.toml", f"case.positions={ns}").case)
        out[ns] = p.describe(np.vstack([designs, p.vendor_x()])).extras
    a, b = out[140], out[5600]
    np.testing.assert_allclose(a["surplus_work_j"], b["surplus_work_j"], atol=0.02)
    np.testing.assert_allclose(a["rod_travel_mm"], b["rod_travel_mm"], atol=1e-9)
    np.testing.assert_allclose(a["phi_max_deg"], b["phi_max_deg"], atol=1e-9)
    np.testing.assert_allclose(a["tau_max_mpa"][:2], b["tau_max_mpa"][:2], rtol=2e-4)
    assert np.isinf(a["tau_max_mpa"][2]) and np.isinf(b["tau_max_mpa"][2])
    assert a["follower_dwell_deg"][2] == pytest.approx(137.1, abs=0.1)
    assert b["eq39_sum_n"][0] > 30 * a["eq39_sum_n"][0]


def test_evaluation_is_vectorised_and_row_independent(problem):
    rng = np.random.default_rng(0)
    X = problem.lower + rng.random((50, problem.n_var)) * (problem.upper - problem.lower)
    whole = problem.evaluate(X)
    for i in (0, 17, 49):
        one = problem.evaluate(X[i : i + 1])
        # a row alone vs in a batch of 50: numpy's SIMD kernels may round a row differently
        # by its place in the batch, so to rounding (inf where inf)
        np.testing.assert_allclose(one.f[0], whole.f[i], rtol=1e-12)
        np.testing.assert_allclose(one.g[0], whole.g[i], rtol=1e-12, atol=1e-12)


@pytest.mark.slow
def test_step1_reaches_zero_surplus_feasibly(tmp_path):
    """Step 1 with Table 5's DE-gr (reduced: 5 repeats x 150 generations): every repeat
    meets 23-26 deg, monotonic motion, tau_max < 1194 MPa, and |surplus| <= 1e-6 of the
    initial design's driving work; the archive holds every convergence history."""
    cfg = load(CONFIGS / "vcb.toml", "run.repeats=5", "solver.generations=150")
    rec = execute(cfg)
    path = archive.write_run(rec, tmp_path / "vcb.h5")
    run = archive.load_run(path)
    limit = 1e-6 * rec.metrics["initial_driving_work_j"]
    for r in rec.repeats:
        assert r.feasible and r.fun <= limit
        assert 0 < r.converged_nit <= 150
    m = run.best.metrics
    assert 23 <= m["phi_max_deg"] <= 26 and m["tau_max_mpa"] < 1194
    assert abs(m["surplus_work_j"]) <= limit
    assert len(run.histories()) == 5
    assert all(len(h) == 150 for h in run.histories("best_objective"))
    for key in ("a0", "a1", "a2", "a3", "phi_max_deg", "pressure_angle_max_deg",
                "curvature_min_mm", "sigma_max_mpa", "tau_max_mpa", "driving_work_j",
                "resistant_work_j", "surplus_work_j", "output_range_deg"):
        assert key in m, key
    assert len(m["output_range_deg"]) == 2
    for curve in ("profile_x_mm", "pitch_y_mm", "pressure_angle_deg", "curvature_mm",
                  "normal_force_n", "tau_max_mpa", "fo_n", "fr_n", "initial_fo_n"):
        assert curve in run.analysis, curve


@pytest.mark.slow
def test_step2_grashof_and_output_range(tmp_path):
    """Step 2 (reduced budget) from a step-1 archive: Grashof holds, range reported."""
    step1 = archive.write_run(execute(load(CONFIGS / "vcb.toml", "run.repeats=1",
                                           "solver.generations=60")), tmp_path / "s1.h5")
    cfg = archive.resolve_references(load(CONFIGS / "vcb_fourbar.toml", "run.repeats=2",
                                          "solver.generations=60",
                                          f'case.cam_archive="{step1}"'))
    assert cfg.case.cam_design.a1 == pytest.approx(
        archive.load_run(step1).best.x["a1"])
    rec = execute(cfg)
    assert rec.best.feasible
    names = rec.problem.constraint_names
    assert rec.best.g[names.index("grashof")] <= 0
    lo, hi = rec.metrics["output_range_deg"]
    assert lo < hi and hi - lo > 5  # the output link swings; compared with [-6, 6] in docs


def _misfit_minima_along_the_rod_offset(problem) -> list[tuple[float, float]]:
    """(offset in deg, misfit) of every local minimum of the identification's misfit
    along the rod arm offset, the arm ratio and free-contact force at the bounds where
    every fit ends (1.85, 0 N): a 0.05 deg grid over the bounds, each minimum refined by
    a bounded scalar search. Independent of DE."""
    from scipy.optimize import minimize_scalar

    (lo, hi), arm = (problem.lower[0], problem.upper[0]), problem.upper[1]

    def f(offset):
        X = np.column_stack([np.atleast_1d(offset), np.full(np.size(offset), arm),
                             np.zeros(np.size(offset))])
        return problem.evaluate(X).f

    grid = np.linspace(lo, hi, int(round(np.degrees(hi - lo) / 0.05)) + 1)
    y = f(grid)
    inner = np.flatnonzero((y[1:-1] < y[:-2]) & (y[1:-1] < y[2:])) + 1
    out = []
    for i in inner:
        res = minimize_scalar(lambda t: f(t)[0], bounds=(grid[i - 1], grid[i + 1]),
                              method="bounded", options={"xatol": 1e-9})
        out.append((float(np.degrees(res.x)), float(res.fun)))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_identification_reproduces_rod_travel(seed):
    """configs/vcb_identify.toml fits the rod arm so the vendor rod travel is 18 mm (Sec
    3.2); the physically bounded fit cannot make Table 6's surpluses vanish (documented).
    The misfit has two minima along the rod offset, 11.65 deg apart (two rod arm angles
    give 18 mm of travel; misfits 0.4343 and 0.4350): whatever the seed, one repeat
    ends on one of them, and configs/vcb.toml holds the lower."""
    rec = execute(load(CONFIGS / "vcb_identify.toml", "run.repeats=1",
                       "solver.generations=80", f"run.seed={seed}"))
    m = rec.metrics
    assert m["rod_travel_mm"] == pytest.approx(18.0, abs=0.05)
    assert m["vendor_surplus_j"] > 20  # the gap written down in docs/assumptions.md
    cfg = load(CONFIGS / "vcb.toml").case
    x = rec.problem.to_display(rec.best.x)
    assert x["opening_arm_ratio"] == pytest.approx(cfg.opening_arm_ratio, abs=0.01)
    assert x["free_contact_force_n"] == pytest.approx(cfg.free_contact_force_n, abs=1.0)
    minima = _misfit_minima_along_the_rod_offset(rec.problem)
    assert len(minima) == 2
    landed = min(minima, key=lambda mf: abs(mf[0] - x["rod_arm_offset_deg"]))
    assert x["rod_arm_offset_deg"] == pytest.approx(landed[0], abs=0.05)
    assert rec.best.fun == pytest.approx(landed[1], rel=1e-6)
    assert cfg.rod_arm_offset_deg == pytest.approx(min(minima, key=lambda mf: mf[1])[0],
                                                   abs=0.05)


def test_peak_stress_fast_path_equals_the_full_contact_analysis(problem):
    """The search's closed-form, refined peak Hertz stress (``VcbModel.peak_stress``, 140
    positions) equals the maximum over the stroke of the full analysis path (``contact``,
    Eqs 15, 19, 27-30) sampled 100 times finer, for designs whose follower never dwells;
    a dwell inside the stroke (the vendor's, phi' = 0) is infinite, not a grid value."""
    m = problem.model
    rng = np.random.default_rng(3)
    X = np.vstack([problem.vendor_x(), problem.sample(rng, 300)])
    A, kc, link = problem.designs(X)
    kin = m.kinematics(A, link, problem.rod_offset)
    fast = m.peak_stress(A, kin.follower, m.closing_torque(kc))
    fine = VcbProblem(problem.config.model_copy(update={"positions": 14000}))
    fm = fine.model
    kin_f = fm.kinematics(A, link, problem.rod_offset)
    full = np.max(fm.contact(kin_f.follower, fm.closing_torque(kc)).sigma, axis=1)
    dwell = np.isfinite(follower_dwell(A, m.theta_c[-1]))
    dwell |= np.any(np.sin(kin_f.follower.angle) <= 0, axis=1)  # arm through O: no phi'
    ok = np.isfinite(full) & ~dwell
    assert ok.sum() > 10 and dwell[0]
    np.testing.assert_allclose(fast[ok], full[ok], rtol=1e-4)
    assert np.all(np.isinf(fast[dwell]))
    assert np.all(np.isinf(fast[~np.isfinite(full)]))  # no Hertz contact: infinite, not NaN
    ev = problem.describe(X[:1])
    assert ev.extras["tau_max_mpa"][0] == pytest.approx(0.304 * ev.extras["sigma_max_mpa"][0])


def test_a_concave_flank_is_no_undercut():
    """The no-undercut requirement reads the convex part of the profile only: a quintic
    law whose profile turns concave (radius about -4.2 m there: the roller rides inside a
    near-flat hollow) reports its least convex radius, not the concave one; the profile
    radius rho_p - rf of a concave pitch curve is below -rf, never an undercut."""
    from camopt.engine.driver import prepare

    config = load(CONFIGS / "vcb_velocity.toml", "case.a4_bounds=[-0.03, 0.03]",
                  "case.a5_bounds=[-0.006, 0.006]", "case.release_offset_bounds_deg=[14, 19]")
    p, _ = prepare(config)
    x = np.array([0.388283, -0.085336, -0.047605, 8094.84, 5926.71, 0.00394, 0.005922,
                  np.radians(19.0)])
    A, kc, link = p.designs(x[None, :])
    kin = p.model.kinematics(A, link, p.rod_offset)
    radius = p.model.contact(kin.follower, p.model.closing_torque(kc)).curvature[0] * 1e3
    rf = p.config.rf_mm
    assert radius.min() < -rf  # a concave stretch
    convex = radius[radius > -rf]
    reported = p.describe(x[None, :]).extras["curvature_min_mm"][0]
    assert reported == pytest.approx(convex.min(), rel=1e-12) and reported > rf


def test_run_in_class_is_standard_springs_with_controlled_friction():
    """Class ``run_in`` (docs/tolerance.md, "Tolerance classes"): every spring as the
    standard class, the friction and the loss 1 - eps as ``controlled``'s run-in; ranked
    after ``graded`` (same cost, declared first) and before ``controlled``."""
    from camopt.cases.vcb import TOLERANCE_CLASSES, TOLERANCES, VCB

    run_in = TOLERANCE_CLASSES["run_in"].tolerances
    controlled = TOLERANCE_CLASSES["controlled"].tolerances
    changed = {k for k in TOLERANCES if run_in[k] != TOLERANCES[k]}
    assert changed == {"case.cam_friction_nm", "case.efficiency"}
    assert all(run_in[k] == controlled[k] for k in changed)
    assert VCB.class_names() == ("standard", "graded", "run_in", "controlled", "matched")
