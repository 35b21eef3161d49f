"""Local solvers' single-design path (issues #12, #36, #48): CPU time per evaluation of
configs/opening_spring_lse6.toml's simplex repeat (20 Nelder-Mead starts, camopt's driver,
solver and case) against scipy's own Nelder-Mead on the same objective (the case's
``evaluate`` of one row, plus the same penalty on its violation, written here with no
camopt driver, solver or meter: what the overhead of camopt's path is measured against),
in the same process, rounds interleaved, medians of ``ROUNDS`` (``time.process_time``:
the other sessions on a shared host do not count); and --jobs 2 against --jobs 1 for its
starts."""

from __future__ import annotations

import math
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from camopt.core.perf import tune_allocator
from camopt.core.problem import FEASIBILITY_TOL
from camopt.engine.driver import execute, load, prepare, run_repeat

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "opening_spring_lse6.toml"
ROUNDS = 5


def _camopt_round(cfg, problem, solver_cls) -> float:
    """CPU seconds per evaluation of one simplex repeat (20 starts)."""
    child = np.random.SeedSequence(cfg.run.seed).spawn(1)[0]
    t0 = time.process_time()
    rec = run_repeat(problem, solver_cls, cfg, child, 0, 1)
    return (time.process_time() - t0) / rec.nfev


def _scipy_round(cfg, problem) -> float:  # type: ignore[no-untyped-def]
    """CPU seconds per evaluation of scipy's Nelder-Mead on the same objective (the
    case's evaluation plus the solver's penalty on the violation) from three starts in
    the unit cube, with the simplex solver's options."""
    o = cfg.solver
    n = problem.n_var

    def objective(u: np.ndarray) -> float:
        ev = problem.evaluate(problem.from_unit(u)[None, :])
        violation = 0.0  # the sum as the solver forms it (its fastest form for a row)
        for g in ev.g[0].tolist():
            if g > FEASIBILITY_TOL:
                violation += g - FEASIBILITY_TOL
            elif g != g:
                violation = math.inf
        return float(ev.f[0]) + o.penalty * violation

    t0, nfev = time.process_time(), 0
    for u0 in np.random.default_rng(0).random((3, n)):
        step = np.where(u0 + o.initial_step <= 1.0, o.initial_step, -o.initial_step)
        res = minimize(objective, u0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * n,
                       options={"maxiter": o.maxiter, "xatol": o.xatol, "fatol": o.fatol,
                                "adaptive": o.adaptive,
                                "initial_simplex": np.vstack([u0, u0 + np.diag(step)])})
        nfev += res.nfev
    return (time.process_time() - t0) / nfev


def per_evaluation() -> float:
    """The ratio camopt simplex / scipy Nelder-Mead on the same objective per evaluation
    (and print it)."""
    tune_allocator()  # what every run makes
    cfg = load(CONFIG)
    problem, solver_cls = prepare(cfg)
    _camopt_round(cfg, problem, solver_cls)  # warm-up (imports, caches)
    _scipy_round(cfg, problem)
    ours, theirs = [], []
    for _ in range(ROUNDS):
        ours.append(_camopt_round(cfg, problem, solver_cls))
        theirs.append(_scipy_round(cfg, problem))
    o, t = statistics.median(ours), statistics.median(theirs)
    ratios = sorted(a / b for a, b in zip(ours, theirs))
    print(f"opening_spring_lse6 simplex: {o * 1e6:.1f} us CPU per evaluation; scipy "
          f"Nelder-Mead on the same objective {t * 1e6:.1f} us: camopt's overhead ratio "
          f"{o / t:.2f} (rounds {ratios[0]:.2f}-{ratios[-1]:.2f})")
    return o / t


def starts_on_two_jobs() -> None:
    cfg = load(CONFIG)
    times = {}
    for jobs in (1, 2):
        t0 = time.perf_counter()
        rec = execute(cfg, jobs=jobs)
        times[jobs] = time.perf_counter() - t0
        best = rec.best.fun
    print(f"opening_spring_lse6 20 starts: jobs=1 {times[1]:.2f} s, jobs=2 {times[2]:.2f} s, "
          f"speed-up {times[1] / times[2]:.2f}x (best objective {best:.3g} either way)")


def main() -> None:
    per_evaluation()
    starts_on_two_jobs()


if __name__ == "__main__":
    main()
