"""Hand-made mutants of the equations and seeds, each applied alone in a scratch copy of
the repository, against the fast tests (``-m "not slow"``) of the mechanics, case, sweep,
driver, record, solver and statistics modules. A mutant is killed when those tests fail.

    .venv/bin/python scripts/mutants.py [NAME ...]      # all, or the named ones

Prints one line per mutant (what killed it: the mirror tests of its module, else the fast
tests) and a closing 'mutants: N killed, N survived'; exits 1 if any survived.
The list and the last results are in docs/design.md (Mutation check).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ["tests/mechanics", "tests/cases", "tests/engine/test_sweep.py", "tests/solvers",
         "tests/core/test_stats.py", "tests/engine/test_driver.py", "tests/core/test_record.py",
         "tests/engine/test_robust.py", "tests/reporting/test_tolerance_figures.py",
         "tests/engine/test_allocation.py", "tests/reporting/test_report.py",
         "tests/reporting/test_views.py", "tests/core/test_requirements.py",
         "tests/core/test_fitting.py"]

# name: (file, original text, mutated text); each original must occur exactly once
MUTANTS: dict[str, tuple[str, str, str]] = {
    # Kang 2023, disc cam (Eqs 6-15)
    # the follower law's derivatives (a polynomial since the quintic: k a_k t^(k-1) and
    # k (k-1) a_k t^(k-2)); the cubic's phi'' = 2 a2 + 6 a3 t becomes 1, 4 or a2 t + a3 t^2
    "cam_ddphi_6t": ("camopt/mechanics/cam.py", "k * (k - 1) * np.vstack",
                     "(k - 1) * (k - 1) * np.vstack"),
    "cam_ddphi_2": ("camopt/mechanics/cam.py", "np.vstack([np.zeros_like(t), shifted[:-1]])",
                    "shifted"),
    "cam_dphi_3t2": ("camopt/mechanics/cam.py", "dphi = a @ (k * shifted)",
                     "dphi = a @ (k * powers)"),
    # the quintic's rate zeros (companion matrix) and the band members' closing time
    "vcb_companion_sign": ("camopt/cases/vcb/law.py", "comp[:, 0, :] = -c[rows",
                           "comp[:, 0, :] = c[rows"),
    "vcb_event_closing_time": ("camopt/cases/vcb/closing.py",
                               "s.t_k + np.cumsum(s.cells, axis=1)[:, -1]", "s.t_k"),
    # issue #37: a stalled identification prediction is no perfect fit; the sign of the
    # lift-off constraint; issue #31: a zero of the kinetic energy between nodes
    "vcb_identify_stall_fits": ("camopt/cases/vcb/identify.py",
                                "return np.where(np.isfinite(r), r, 10.0)",
                                "return np.where(np.isfinite(r), r, 0.0)"),
    "vcb_lift_off_sign": ("camopt/cases/vcb/constraints.py",
                          "q.config.lift_off_fraction_min - q.lift_off_ratio",
                          "q.lift_off_ratio - q.config.lift_off_fraction_min"),
    "vcb_first_zero_nodes_only": ("camopt/cases/vcb/locate.py",
                                  "- 4 / 27 * h * (np.abs(d0) + np.abs(d1)) <= 0)",
                                  "<= 0)"),
    # the design's closing latch moves every band set (set-major order, issue #21)
    "vcb_band_latch_order": ("camopt/cases/vcb/parts.py", "+ np.tile(moved, k))",
                             "+ np.repeat(moved, k))"),
    "vcb_band_latch_sign": ("camopt/cases/vcb/problem.py",
                            "self.release_offset(X) - self.config.release_offset_deg * DEG",
                            "self.config.release_offset_deg * DEG - self.release_offset(X)"),
    "cam_pitch_w": ("camopt/mechanics/cam.py", "w = l2 * (1 - f.dphi)", "w = l2 * (1 + f.dphi)"),
    "cam_base_angle": ("camopt/mechanics/cam.py", "/ (2 * l2 * l6))", "/ (l2 * l6))"),
    "cam_psi_eta_sign": ("camopt/mechanics/cam.py", "np.pi / 2 - eta - f.angle",
                         "np.pi / 2 + eta - f.angle"),
    "cam_psi_oi": ("camopt/mechanics/cam.py", "f.dphi / (1 - f.dphi)", "f.dphi / (1 + f.dphi)"),
    "cam_rho_ddphi_sign": ("camopt/mechanics/cam.py", "- (l2 * l6) * f.ddphi * f.sin_a",
                           "+ (l2 * l6) * f.ddphi * f.sin_a"),
    "cam_rho_ddphi_dropped": ("camopt/mechanics/cam.py", "- (l2 * l6) * f.ddphi * f.sin_a",
                              ""),
    "cam_rho_rf": ("camopt/mechanics/cam.py", "/ den - rf", "/ den + rf"),
    # Hertz line contact (Kang Eqs 27-31)
    "hertz_2pi": ("camopt/mechanics/hertz.py", "(2 * np.pi * length)", "(np.pi * length)"),
    "hertz_radius": ("camopt/mechanics/hertz.py", "1.0 / np.asarray(rho1) + 1.0",
                     "1.0 / np.asarray(rho1) - 1.0"),
    "hertz_0304": ("camopt/mechanics/hertz.py", "0.304 * np.asarray", "0.35 * np.asarray"),
    # Yan 2023, EMB polar cam (Eqs 8-18, 27)
    "emb_pressure_angle": ("camopt/mechanics/polar_cam.py", "np.where(near, a_e - a_l,",
                           "np.where(near, a_e + a_l,"),
    "emb_hertz_radius": ("camopt/mechanics/polar_cam.py", "rg * rho_cam / (rg - rho_cam)",
                         "rg * rho_cam / (rg + rho_cam)"),
    "emb_curvature_2dr2": ("camopt/mechanics/polar_cam.py", "r * r + 2 * dr * dr - r * ddr",
                           "r * r + dr * dr - r * ddr"),
    "emb_rotation_alpha": ("camopt/mechanics/polar_cam.py", "np.clip(np.asarray(l) / r, -1, 1)) + "
                           "alpha", "np.clip(np.asarray(l) / r, -1, 1)) - alpha"),
    "emb_center_distance": ("camopt/mechanics/polar_cam.py", "rg * rg - 2 * rg * np.sqrt",
                            "rg * rg - rg * np.sqrt"),
    "emb_force_cube": ("camopt/cases/emb_cam/problem.py", "self.x1, 0, None) ** 3  # Eq 18",
                       "self.x1, 0, None) ** 2  # Eq 18"),
    "emb_force_clearance": ("camopt/cases/emb_cam/problem.py",
                            "np.clip(s - self.x1, 0, None) ** 3  # Eq 18",
                            "np.clip(s, 0, None) ** 3  # Eq 18"),
    "emb_torque_normal_force": ("camopt/cases/emb_cam/problem.py", "torque = f_b * l",
                                "torque = force * l"),
    "emb_objective_curvature_unit": ("camopt/cases/emb_cam/problem.py",
                                     "w[3] * m.curvature_steps / MM", "w[3] * m.curvature_steps"),
    "emb_objective_curvature_dropped": ("camopt/cases/emb_cam/problem.py",
                                        "+ w[3] * m.curvature_steps / MM", ""),
    "emb_start_slope": ("camopt/cases/emb_cam/problem.py", "self.r_st * np.tan(kappa)",
                        "self.r_st * np.sin(kappa)"),
    # Clauss 1982, fast switch
    "switch_r20_factor": ("camopt/cases/fast_switch/problem.py", '"R20": 1.2 * (x4 - x5) / damped',
                          '"R20": 1.0 * (x4 - x5) / damped'),
    "switch_arcsine_sign": ("camopt/cases/fast_switch/problem.py", "(np.pi - np.arcsin(v) - phase)",
                            "(np.pi + np.arcsin(v) - phase)"),
    "switch_phase": ("camopt/cases/fast_switch/problem.py", "phase = np.arctan(root / xi)",
                     "phase = np.arctan(xi / root)"),
    "switch_mass_eq32": ("camopt/cases/fast_switch/problem.py", "+ 0.021 * self.M3  # Eq 32",
                         "+ 0.21 * self.M3  # Eq 32"),
    # seeds
    "sweep_cell_spawn_key": ("camopt/engine/sweep.py", "spawn_key=(cell.seed,)",
                             "spawn_key=(cell.seed + 1,)"),
    "sweep_cell_entropy": ("camopt/engine/sweep.py", "SeedSequence(cell.entropy,",
                           "SeedSequence(cell.entropy + 1,"),
    "driver_seed": ("camopt/engine/driver.py", "np.random.SeedSequence(seed).spawn(repeats)",
                    "np.random.SeedSequence(seed + 1).spawn(repeats)"),
    # the repeat record's success and evaluations to target (issue #25)
    "driver_success_target": ("camopt/engine/driver.py", "succeeded([fun], [feasible], target)",
                              "succeeded([fun], [feasible], None)"),
    "record_nfev_to_target": ("camopt/core/record.py",
                              'ok &= np.asarray(history["best_objective"]) <= target',
                              'ok &= np.asarray(history["best_objective"]) >= target'),
    # DE-gr operators
    "de_crossover_direction": ("camopt/solvers/de_gr.py", "rng.random((n, d)) < rate",
                               "rng.random((n, d)) > rate"),
    "de_forced_gene": ("camopt/solvers/de_gr.py", "    cross[np.arange(n), rng.integers(0, d, n)]"
                       " = True\n", "    rng.integers(0, d, n)\n"),
    "de_best1_base": ("camopt/solvers/de_gr.py", "return best + factor *",
                      "return pop + factor *"),
    "de_parents_stale": ("camopt/solvers/de_gr.py",
                         "self.ev = Evaluation.concat([self.ev, ev.take(slice(n, None))])"
                         ".take(index)", "index = index"),
    "de_best1_self": ("camopt/solvers/de_gr.py", "idx = np.where(idx == np.arange(n)[:, None], "
                      "idx[:, -1:], idx)[:, :2]", "idx = idx[:, :2]"),
    # PSO inertia (Eq 40)
    "pso_inertia_reversed": ("camopt/solvers/pso.py", "return w_max - iteration / iterations",
                             "return w_min + iteration / iterations"),
    "pso_inertia_constant": ("camopt/solvers/pso.py", "return w_max - iteration / iterations "
                             "* (w_max - w_min)", "return w_max"),
    # robust design: a candidate not sampled (nominally infeasible) ranks behind every
    # sampled one (issue #37: survived every test)
    "robust_screened_offset": ("camopt/engine/robust.py",
                               "np.column_stack([nom_g, SCREENED + np.maximum(nom_worst, 0.0)])",
                               "np.column_stack([nom_g, np.maximum(nom_worst, 0.0)])"),
    # the tolerance tornado's +X bar at the input's +X value (issue #37: survived every test)
    "tornado_plus_at_minus": ("camopt/reporting/tolerance_figures.py",
                              '(("low", "tab:blue", "-"), ("high", "tab:orange", "+"))',
                              '(("low", "tab:blue", "-"), ("low", "tab:orange", "+"))'),
    "tornado_ends_swapped": ("camopt/reporting/tolerance_figures.py",
                             '("low", "tab:blue", "-"), ("high", "tab:orange", "+")',
                             '("low", "tab:blue", "+"), ("high", "tab:orange", "-")'),
    # the polish under the run's budget (issue #37)
    "polish_unmetered": ("camopt/solvers/polish.py",
                         "reason = self.budget.spent(self.used + self.count + len(X))",
                         "reason = None"),
    "polish_no_reserve": ("camopt/solvers/polish.py", "else budget.max_nfev - 1, budget.deadline)",
                          "else budget.max_nfev, budget.deadline)"),
    # the multi-start local solves under the run's budget (issue #37)
    "multistart_unmetered": ("camopt/solvers/multistart.py",
                             "reason = self.budget.spent(self.used + self.count + 1)",
                             "reason = None"),
    "multistart_no_reserve": ("camopt/solvers/multistart.py",
                              "else budget.max_nfev - 1,\n", "else budget.max_nfev,\n"),
    # statistics
    "stats_mw_direction": ("camopt/core/stats.py", "p_a_better = 1.0 - float(res.statistic)",
                           "p_a_better = float(res.statistic)"),
    "stats_mw_one_sided": ("camopt/core/stats.py", 'alternative="two-sided"', 'alternative="less"'),
    "stats_verdict": ("camopt/core/stats.py", "if test.p_a_better > 0.5",
                      "if test.p_a_better < 0.5"),
    # decision rules: a class "reaching" or a run "meeting" its yield target by the
    # interval's lower end, not the point estimate; "latched" under every band set and
    # every form, not some; the next-step rule's branches; compare's Fisher counts
    "alloc_reach_point": ("camopt/engine/allocation.py", 'rate["ci_low"] >= target)',
                          "passed / samples >= target)"),
    "robust_meets_point": ("camopt/reporting/report.py", "else low >= target)",
                           'else checked.get("yield") >= target)'),
    "verdict_low_point": ("camopt/reporting/views.py", "else self.expected_yield.low",
                          "else self.expected_yield.value"),
    "grade_boundary": ("camopt/core/requirements.py", "or expected < target:",
                       "or expected <= target:"),
    "band_latched_some": ("camopt/cases/vcb/band.py", "latched=np.asarray(latched.all(axis=0))",
                          "latched=np.asarray(latched.any(axis=0))"),
    "verdict_latched_some": ("camopt/cases/vcb/verdict.py", '"latched": Reduction.LEAST,',
                             '"latched": Reduction.GREATEST,'),
    "next_robust_met": ("camopt/reporting/report.py", "if robust_yield_doc.meets_target is False:",
                        "if robust_yield_doc.meets_target is True:"),
    "next_repeats": ("camopt/reporting/report.py", "if len(run.repeats) > 1:",
                     "if len(run.repeats) >= 1:"),
    "next_nominal_fail": ("camopt/reporting/report.py", 'if judged.verdict != "pass":',
                          'if judged.verdict == "pass":'),
    "next_amber": ("camopt/reporting/report.py", 'if judged.grade != "pass":',
                   'if judged.grade == "pass":'),
    "next_config_own": ("camopt/reporting/report.py", "target.resolve() == own.resolve()",
                        "target.resolve() != own.resolve()"),
    "fisher_counts": ("camopt/core/stats.py", "[[k_a, n_a - k_a], [k_b, n_b - k_b]]",
                      "[[k_a, n_a], [k_b, n_b]]"),
    "fisher_runs_own": ("camopt/reporting/report.py",
                        "stats.compare_success(k_a, len(a), k_b, len(b))",
                        "stats.compare_success(k_b, len(a), k_a, len(b))"),
    # fitting: the profile-likelihood threshold and each rule that judges a fit
    "fit_profile_threshold": ("camopt/core/fitting.py", "rise = 0.5 * CHI2_95_1DOF * opt.s2",
                              "rise = 2.0 * CHI2_95_1DOF * opt.s2"),
    "fit_identified": ("camopt/core/fitting.py", "reach <= accuracy * abs(value) if log",
                       "reach > accuracy * abs(value) if log"),
    "fit_identified_open": ("camopt/core/fitting.py", "return bool(closed and (",
                            "return bool((not closed) and ("),
    "fit_determined": ("camopt/core/fitting.py", "determined = s >= DETERMINED * s[0]",
                       "determined = s < DETERMINED * s[0]"),
    "fit_rms_ratio": ("camopt/core/fitting.py", "return self.rms_ratio <= RMS_RATIO_LIMIT and",
                      "return self.rms_ratio > RMS_RATIO_LIMIT and"),
    "fit_durbin_watson": ("camopt/core/fitting.py", "and self.structure_z <= STRUCTURE_Z_LIMIT",
                          "and self.structure_z > STRUCTURE_Z_LIMIT"),
    "fit_at_bound": ("camopt/core/fitting.py",
                     "return bool(q - lower <= room or upper - q <= room)",
                     "return bool(q - lower > room and upper - q > room)"),
    "fit_keep": ("camopt/core/fitting.py", "return [r <= limit for r in rms]",
                 "return [r > limit for r in rms]"),
    "fit_nested_keep": ("camopt/cases/vcb/calibrate.py", "if ratio >= CHI2_99_1DOF else",
                        "if ratio < CHI2_99_1DOF else"),
    "vcb_verdict_forms": ("camopt/cases/vcb/calibration_verdict.py",
                          "good = [f for f in fits if f.explains]",
                          "good = [f for f in fits if not f.explains]"),
}

# the tests that mirror each mutated module (a subset of the fast tests above): a mutant
# they kill is killed by the fast tests; a survivor is tried on all of them
MIRROR = {
    "camopt/mechanics/cam.py": ["tests/mechanics/test_cam.py"],
    "camopt/mechanics/hertz.py": ["tests/mechanics/test_hertz.py"],
    "camopt/mechanics/polar_cam.py": ["tests/mechanics/test_polar_cam.py",
                                      "tests/cases/test_emb_cam.py"],
    "camopt/cases/emb_cam/problem.py": ["tests/cases/test_emb_cam.py"],
    "camopt/cases/fast_switch/problem.py": ["tests/cases/test_fast_switch.py"],
    "camopt/cases/vcb/problem.py": ["tests/cases/test_vcb_release.py"],
    "camopt/cases/vcb/parts.py": ["tests/cases/test_vcb_release.py"],
    "camopt/cases/vcb/band.py": ["tests/cases/test_vcb_band.py"],
    "camopt/cases/vcb/verdict.py": ["tests/cases/test_vcb_verdict.py"],
    "camopt/engine/allocation.py": ["tests/engine/test_allocation.py"],
    "camopt/reporting/report.py": ["tests/reporting/test_report.py"],
    "camopt/reporting/views.py": ["tests/reporting/test_views.py"],
    "camopt/core/requirements.py": ["tests/core/test_requirements.py"],
    "camopt/cases/vcb/identify.py": ["tests/cases/test_vcb_identify.py"],
    "camopt/cases/vcb/constraints.py": ["tests/cases/test_vcb_constraints.py"],
    "camopt/cases/vcb/dynamics.py": ["tests/cases/test_vcb_dynamics.py"],
    "camopt/cases/vcb/closing.py": ["tests/cases/test_vcb_dynamics.py",
                                    "tests/cases/test_vcb_kernel.py"],
    "camopt/cases/vcb/locate.py": ["tests/cases/test_vcb_dynamics.py"],
    "camopt/cases/vcb/law.py": ["tests/cases/test_vcb_law.py"],
    "camopt/engine/sweep.py": ["tests/engine/test_sweep.py"],
    "camopt/engine/driver.py": ["tests/engine/test_driver.py"],
    "camopt/core/record.py": ["tests/core/test_record.py"],
    "camopt/solvers/de_gr.py": ["tests/solvers/test_de_gr.py"],
    "camopt/solvers/pso.py": ["tests/solvers/test_pso.py"],
    "camopt/core/stats.py": ["tests/core/test_stats.py"],
    "camopt/engine/robust.py": ["tests/engine/test_robust.py"],
    "camopt/reporting/tolerance_figures.py": ["tests/reporting/test_tolerance_figures.py"],
    "camopt/solvers/polish.py": ["tests/solvers/test_polish.py"],
    "camopt/solvers/multistart.py": ["tests/solvers/test_multistart.py"],
    "camopt/core/fitting.py": ["tests/core/test_fitting.py"],
    "camopt/cases/vcb/calibrate.py": ["tests/cases/test_vcb_calibrate.py"],
    "camopt/cases/vcb/calibration_verdict.py": ["tests/cases/test_vcb_calibration_verdict.py"],
}


def fails(scratch: Path, tests: list[str]) -> bool:
    """Whether the fast tests among ``tests`` fail in ``scratch`` (stops at the first)."""
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:randomly",
                           "-p", "no:cacheprovider", "-m", "not slow", *tests],
                          cwd=scratch, env={**os.environ, "PYTHONPATH": str(scratch)},
                          capture_output=True, text=True)
    return proc.returncode != 0


def run(name: str, scratch: Path) -> str | None:
    """Apply mutant ``name`` alone to a fresh copy; what killed it (its module's mirror
    tests, else the fast tests), None when it survived."""
    path, old, new = MUTANTS[name]
    if scratch.exists():
        shutil.rmtree(scratch)
    shutil.copytree(ROOT, scratch, ignore=shutil.ignore_patterns(".venv", ".git", "runs",
                                                                  "*.egg-info", "__pycache__"))
    target = scratch / path
    text = target.read_text()
    if text.count(old) != 1:
        raise SystemExit(f"error: {path}: {name}: the original text occurs {text.count(old)} "
                         "times (the source changed; update the mutant)")
    target.write_text(text.replace(old, new))
    mirror = MIRROR.get(path, TESTS)
    if fails(scratch, mirror):
        return " ".join(mirror)
    return "the fast tests" if fails(scratch, TESTS) else None


def main(names: list[str]) -> int:
    names = names or list(MUTANTS)
    scratch = Path(tempfile.mkdtemp(prefix="camopt-mutant-")) / "repo"
    # no mutant: the tests must pass, or every mutant would count as killed
    shutil.copytree(ROOT, scratch, ignore=shutil.ignore_patterns(".venv", ".git", "runs",
                                                                  "*.egg-info", "__pycache__"))
    mirrors = sorted({t for name in names for t in MIRROR.get(MUTANTS[name][0], TESTS)})
    if fails(scratch, mirrors):
        raise SystemExit(f"error: {' '.join(mirrors)}: fail without a mutant; fix them first")
    killed = 0
    for name in names:
        by = run(name, scratch)
        killed += by is not None
        print(f"{name}: {f'killed by {by}' if by else 'SURVIVED'}", flush=True)
    shutil.rmtree(scratch.parent)
    print(f"mutants: {killed} killed, {len(names) - killed} survived")
    return 0 if killed == len(names) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
