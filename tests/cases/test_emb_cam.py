"""EMB cam against Yan, Chen, Yan & Hang (2023), Sec 3.1 and 4.4."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from camopt.engine.driver import execute
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


@pytest.mark.parametrize("density", [None, (0.5, 2.0, 0.2)])
def test_lift_from_the_end_samples_is_the_profiles_last_lift(density):
    """The lift correction (Eq 37) reads the lift from the profile's two end samples:
    the last sample of the whole profile's Eq 11 to rounding (rtol 1e-12: two evaluation
    paths, whose SIMD kernels differ by ~1e-13 relative on some CPUs), for rising key radii
    (about half of them give a finite profile), with uniform and with warped key points."""
    from camopt.cases.emb_cam import EmbCamProblem

    case = load(CONFIGS / "emb.toml").case
    p = EmbCamProblem(case.model_copy(update={"knot_density": density}))
    rng = np.random.default_rng(2)
    n = 400
    R = p.r_st + np.sort(rng.uniform(0, 1, (n, p.n - 1)), axis=1) * p.rg / 2
    X = np.column_stack([R, rng.uniform(0, p.kappa_max / 2, n), rng.uniform(0.01, 0.5, n) * p.rg])
    whole = p.profile(X).s[:, -1]
    assert np.isfinite(whole).sum() > n / 4
    np.testing.assert_allclose(p.lift(X), whole, rtol=1e-12, atol=1e-15)  # m; NaN at NaN


# ---- one fixed particle, every equation against an independent calculation -------------
# Key radii rising from r_st = 15 mm to 16.6 mm, kappa 0.05 rad, offset 2 mm: every sample
# finite, the clearance taken up part-way (lift 1.88 mm > x1), pressure angles to 29 deg.
R_KEYS = (15 + 1.6 * np.linspace(1 / 9, 1, 9) ** 1.3) * 1e-3
PARTICLE = np.r_[R_KEYS, 0.05, 2e-3]
K_PAPER = 50e3 / 1e-9  # N/m^3: 50 kN at 1 mm of caliper deformation (Sec 3.1)
Z_E = 189.8e3  # sqrt(Pa), steel on steel (Eq 15)


def fixed_problem(**changes):
    from camopt.cases.emb_cam import EmbCamConfig, EmbCamProblem

    return EmbCamProblem(EmbCamConfig(**changes))


def independent_profile(problem):
    """The working profile by scipy's CubicSpline in the profile angle (clamped to the
    non-working arc's slope r_st tan kappa at the start, Eq 20; natural at the end), with
    theta0 and theta_a from Eqs 22-24 written out by the law of cosines, and the geometry
    of Eqs 8-11 and 16 by vectors: B = r (cos, sin), the ring centre A = B - rg n (n the
    outward normal), the follower height from |OA| and the offset."""
    from scipy.interpolate import CubicSpline

    rg, r_st, e, kappa = 20e-3, 15e-3, PARTICLE[-1], PARTICLE[-2]
    r_keys = np.r_[r_st, R_KEYS]
    oa0 = np.sqrt(rg**2 + r_st**2 - 2 * rg * r_st * np.cos(kappa))  # Eq 22

    def ring_angle(r):  # angle AOB for B on the ring about A at the start
        return np.arccos((oa0**2 + r**2 - rg**2) / (2 * oa0 * r))

    theta_a = ring_angle(r_st) + ring_angle(r_keys[-1])  # Eq 23
    theta0 = np.pi / 2 - ring_angle(r_st) + np.arccos(e / oa0)  # Eq 24
    knots = theta0 + theta_a * np.arange(10) / 9  # Eq 25, uniform key points
    spline = CubicSpline(knots, r_keys, bc_type=((1, r_st * np.tan(kappa)), (2, 0.0)))
    theta = theta0 + theta_a * np.linspace(0, 1, problem.u.size)
    r, dr, ddr = spline(theta), spline(theta, 1), spline(theta, 2)
    c, s = np.cos(theta), np.sin(theta)
    b = np.array([r * c, r * s])
    t = np.array([dr * c - r * s, dr * s + r * c])  # dB/dtheta
    tt = np.array([ddr * c - 2 * dr * s - r * c, ddr * s + 2 * dr * c - r * s])
    speed = np.hypot(*t)
    arm = np.abs(np.sum(b * t, axis=0)) / speed  # Eq 8: distance from O to the normal
    normal_out = np.array([t[1], -t[0]]) / speed
    oa = np.hypot(*(b - rg * normal_out))  # Eq 9
    h = np.sqrt(oa**2 - e**2)  # Eq 10
    rho = speed**3 / np.abs(t[0] * tt[1] - t[1] * tt[0])  # Eq 16
    return {"theta": theta, "r": r, "dr": dr, "l": arm, "oa": oa, "s": h[0] - h, "rho": rho,
            "knots": knots}


@pytest.fixture(scope="module")
def fixed():
    problem = fixed_problem()
    return problem, problem.profile(PARTICLE[None]).row(0), independent_profile(problem)


def test_fixed_particle_geometry_eqs8_to_11_16_and_20_to_25(fixed):
    _, p, ref = fixed
    for key, tol in (("theta", 1e-12), ("r", 1e-12), ("dr", 1e-9), ("l", 1e-9),
                     ("oa", 1e-12), ("s", 1e-8), ("rho", 1e-7)):
        np.testing.assert_allclose(getattr(p, key), ref[key], rtol=tol,
                                   atol=tol * 1e-3, err_msg=key)


def test_fixed_particle_force_eq18_and_torque_eq14(fixed):
    """Eq 18: F = K (s - x1)^3 once the 1 mm clearance is taken up (zero before); Eq 14 with
    Eq 12: T = F l / cos(alpha)."""
    _, p, ref = fixed
    expected = K_PAPER * np.clip(ref["s"] - 1e-3, 0, None) ** 3
    assert (expected > 0).sum() > 20 and (expected == 0).sum() > 20
    np.testing.assert_allclose(p.force, expected, rtol=1e-7, atol=1e-6)
    np.testing.assert_allclose(p.torque, expected * ref["l"] / np.cos(p.alpha), rtol=1e-7,
                               atol=1e-9)


def test_fixed_particle_pressure_angle_eq13_by_virtual_work(fixed):
    """Eqs 13 and 17 against the work balance T dphi = F ds (Eq 44): l / cos(alpha) equals
    ds/dphi over the clamping section (where the caliper force does work), by differences
    of the independent lift over the rotation."""
    _, p, ref = fixed
    ratio = np.gradient(ref["s"], p.rotation)
    clamping = ref["s"] > 1e-3
    clamping[-3:] = False  # one-sided differences at the end
    assert clamping.sum() > 20
    np.testing.assert_allclose((ref["l"] / np.cos(p.alpha))[clamping], ratio[clamping],
                               rtol=2e-3)


def test_fixed_particle_hertz_stress_eq15(fixed):
    """Eq 15: sigma_H = Z_E sqrt(F / (L rho_e)), 1/rho_e = 1/rho - 1/rg (the cam inside
    the ring), F the normal force F / cos(alpha), L = 20 mm."""
    _, p, ref = fixed
    rho_e = 1 / (1 / ref["rho"] - 1 / 20e-3)
    expected = Z_E * np.sqrt(p.force / np.cos(p.alpha) / (20e-3 * rho_e))
    assert np.nanmax(expected) > 100e6
    np.testing.assert_allclose(p.sigma, expected, rtol=1e-6, atol=1e-3)


def test_fixed_particle_objective_eq27_terms():
    """Eq 27 term by term (one weight at a time, no penalty): the curvature steps between
    key points in mm (w4), the peak torque (w3) and the largest tan(alpha) while clamping
    (w6), against the independent profile."""
    flat = {"penalty_p1": 0.0, "penalty_p2": 0.0}
    base = fixed_problem()
    ref = independent_profile(base)
    p = base.profile(PARTICLE[None]).row(0)
    keys = base.knots
    steps = np.abs(np.diff(ref["rho"][keys])).sum() / 1e-3
    torque = K_PAPER * np.clip(ref["s"] - 1e-3, 0, None) ** 3 * ref["l"] / np.cos(p.alpha)
    clamping = ref["s"] > 1e-3
    for w, expected in ((3, steps), (2, torque.max()),
                        (5, np.tan(np.abs(p.alpha[clamping])).max())):
        weights = [0.0] * 6
        weights[w] = 1.0
        f = fixed_problem(weights=weights, **flat).evaluate(PARTICLE[None]).f[0]
        assert f == pytest.approx(expected, rel=1e-6), w
