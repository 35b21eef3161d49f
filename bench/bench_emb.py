"""EMB cam: swarm evaluation with the batched spline vs a per-particle loop with scipy
splines; improved PSO (corrections) vs plain PSO over 10 seeds each (swarms alone); the
straight-ramp design (configs/emb_linear.toml) with and without its polish; wall time
of each EMB config against the settings before issue #13 (ratio, interleaved rounds)."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from camopt.cases.emb_cam import EmbCamProblem
from camopt.core.perf import tune_allocator
from camopt.engine.driver import execute, load

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def _load(*overrides: str, name: str = "emb.toml"):
    return load(CONFIGS / name, list(overrides))


class ScipySplines:
    """Same interface as ClampedNaturalSpline, one scipy CubicSpline per particle."""

    def __init__(self, n: int, u: np.ndarray) -> None:
        self.n, self.u = n, u

    def __call__(self, r, slope0):
        out = [np.empty((len(r), self.u.size)) for _ in range(3)]
        for i in range(len(r)):
            cs = CubicSpline(np.arange(self.n), r[i], bc_type=((1, slope0[i]), (2, 0.0)))
            for k in range(3):
                out[k][i] = cs(self.u, k)
        return tuple(out)


def evaluation_cost(n_pop: int = 100) -> None:
    problem = EmbCamProblem(_load().case)
    rng = np.random.default_rng(0)
    X = problem.lower + rng.random((n_pop, problem.n_var)) * (problem.upper - problem.lower)
    X = problem.repair(X, rng, {k: 1.0 for k in problem.repair_schedule()})
    t0 = time.perf_counter()
    for _ in range(20):
        batched = problem.evaluate(X)
    vec = (time.perf_counter() - t0) / 20 / n_pop
    problem.spline = ScipySplines(problem.n, problem.u)
    t0 = time.perf_counter()
    for x in X:
        problem.evaluate(x[None, :])
    loop = (time.perf_counter() - t0) / n_pop
    same = np.allclose(problem.evaluate(X).f, batched.f, rtol=1e-9)
    print(f"swarm evaluation per particle: batched {vec * 1e6:.1f} us, per-particle scipy "
          f"loop {loop * 1e6:.0f} us, speed-up {loop / vec:.0f}x (same results: {same})")


def improved_vs_plain(seeds: int = 10) -> None:
    for repair in (True, False):
        cfg = _load(f"solver.repair={str(repair).lower()}", f"run.repeats={seeds}",
                    "solver.iterations=500")  # the paper's budget, swarm alone
        rec = execute(replace(cfg, solver=cfg.solver.model_copy(update={"polish": None})))
        f = np.array([r.fun for r in rec.repeats])
        feas = np.array([r.feasible for r in rec.repeats])
        first = [int(np.argmax(r.history["best_violation"] == 0)) + 1
                 if (r.history["best_violation"] == 0).any() else None for r in rec.repeats]
        found = [x for x in first if x is not None]
        label = "improved PSO" if repair else "plain PSO   "
        print(f"{label}: feasible {feas.mean():.0%}, fitness median {np.median(f):.4g}, best "
              f"{f.min():.4g}; first feasible particle at iteration median "
              f"{np.median(found) if found else 'never'} ({len(found)}/{seeds} runs found one)")


def ramp_with_and_without_polish() -> None:
    """The config's 6 repeats; success = feasible with a peak torque <= 5.2 N m."""
    polished = _load(name="emb_linear.toml")
    alone = replace(polished, solver=polished.solver.model_copy(update={"polish": None}))
    for label, cfg in (("swarm alone          ", alone), ("swarm + CMA-ES polish", polished)):
        t0 = time.perf_counter()
        rec = execute(cfg)
        wall = time.perf_counter() - t0
        peaks = np.array([rec.problem.evaluate(r.x[None, :]).extras["peak_torque_nm"][0]
                          for r in rec.repeats])
        feas = np.array([r.feasible for r in rec.repeats])
        ok = feas & (peaks <= 5.2)
        best = f"{peaks[feas].min():.2f} N m" if feas.any() else "none"
        print(f"ramp design, {label}: feasible {feas.sum()}/{feas.size}, peak <= 5.2 N m "
              f"in {ok.sum()}/{ok.size}, best feasible peak {best}, {wall:.0f} s")


def _before_issue_13(name: str):
    """The config as it ran before issue #13: lift +- 0.01 mm, 500 swarm iterations, and
    for the ramp the SLSQP epsilon-constraint polish (peak <= 5.4 N m)."""
    cfg = _load("case.lift_tolerance_mm=0.01", "solver.iterations=500", name=name)
    polish = None
    if name == "emb_linear.toml":
        polish = {"minimise": "torque_ramp_rms_pct", "limits": {"peak_torque_nm": 5.4}}
    options = type(cfg.solver).model_validate({**cfg.solver.model_dump(), "polish": polish})
    return replace(cfg, solver=options)


def wall_time_against_before(rounds: int = 3) -> None:
    """Each EMB config as it runs now against its pre-#13 settings: medians of
    interleaved rounds (load from elsewhere on the host hits both sides), ratio now/before,
    with each side's best fitness."""
    for name in ("emb.toml", "emb_linear.toml"):
        now, before = _load(name=name), _before_issue_13(name)
        times: dict[str, list[float]] = {"now": [], "before": []}
        best: dict[str, float] = {}
        for _ in range(rounds):
            for label, cfg in (("now", now), ("before", before)):
                t0 = time.perf_counter()
                rec = execute(cfg)
                times[label].append(time.perf_counter() - t0)
                best[label] = rec.best.fun if rec.best.feasible else float("inf")
        med = {k: float(np.median(v)) for k, v in times.items()}
        print(f"{name}: wall now {med['now']:.1f} s, before {med['before']:.1f} s, ratio "
              f"{med['now'] / med['before']:.2f} (best fitness now {best['now']:.4g}, before "
              f"{best['before']:.4g})")


def main() -> None:
    tune_allocator()
    evaluation_cost()
    improved_vs_plain()
    ramp_with_and_without_polish()
    wall_time_against_before()


if __name__ == "__main__":
    main()
