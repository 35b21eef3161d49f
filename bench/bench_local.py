"""Local solvers' single-design path (issues #12, #36): CPU time per evaluation of
configs/opening_spring_lse6.toml's simplex repeat (20 Nelder-Mead starts, camopt's driver,
solver and case) against scipy's own Nelder-Mead on a 5-variable numpy Rosenbrock
(``scipy.optimize.rosen``), in the same process, rounds interleaved, medians of
``ROUNDS`` (``time.process_time``: the other sessions on a shared host do not count;
target <= 3x); and --jobs 2 against --jobs 1 for its starts."""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize, rosen

from camopt.engine.driver import execute, load, prepare, run_repeat

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "opening_spring_lse6.toml"
ROUNDS = 5


def _camopt_round(cfg, problem, solver_cls) -> float:
    """CPU seconds per evaluation of one simplex repeat (20 starts)."""
    child = np.random.SeedSequence(cfg.run.seed).spawn(1)[0]
    t0 = time.process_time()
    rec = run_repeat(problem, solver_cls, cfg, child, 0, 1)
    return (time.process_time() - t0) / rec.nfev


def _scipy_round() -> float:
    """CPU seconds per evaluation of scipy's Nelder-Mead on Rosenbrock-5 (three starts)."""
    t0, nfev = time.process_time(), 0
    for start in (1.3, 0.7, -0.5):
        res = minimize(rosen, np.full(5, start), method="Nelder-Mead",
                       options={"maxiter": 20000, "maxfev": 20000, "xatol": 1e-12,
                                "fatol": 1e-14})
        nfev += res.nfev
    return (time.process_time() - t0) / nfev


def per_evaluation() -> float:
    """The ratio camopt simplex / scipy Nelder-Mead per evaluation (and print it)."""
    cfg = load(CONFIG)
    problem, solver_cls = prepare(cfg)
    _camopt_round(cfg, problem, solver_cls)  # warm-up (imports, caches)
    _scipy_round()
    ours, theirs = [], []
    for _ in range(ROUNDS):
        ours.append(_camopt_round(cfg, problem, solver_cls))
        theirs.append(_scipy_round())
    o, t = statistics.median(ours), statistics.median(theirs)
    ratios = sorted(a / b for a, b in zip(ours, theirs))
    print(f"opening_spring_lse6 simplex: {o * 1e6:.1f} us CPU per evaluation; scipy "
          f"Nelder-Mead on Rosenbrock-5 {t * 1e6:.1f} us: ratio {o / t:.2f} (rounds "
          f"{ratios[0]:.2f}-{ratios[-1]:.2f}; target <= 3)")
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
