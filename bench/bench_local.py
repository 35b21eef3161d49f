"""Local solvers' single-design path (issue #12): wall time per evaluation of
configs/opening_spring_lse6.toml (20 Nelder-Mead starts, from the repeats' wall_s and
nfev as the archive records them) against scipy's own Nelder-Mead on a 5-variable numpy
Rosenbrock, measured in the same run (target <= 3x); and --jobs 2 against --jobs 1 for
its starts."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize, rosen

from camopt.engine.driver import execute, load

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "opening_spring_lse6.toml"


def per_evaluation() -> None:
    rec = execute(load(CONFIG))
    ours = sum(r.wall_s for r in rec.repeats) / sum(r.nfev for r in rec.repeats)
    rounds = []
    for start in (1.3, 0.7, -0.5):
        t0 = time.perf_counter()
        res = minimize(rosen, np.full(5, start), method="Nelder-Mead",
                       options={"maxiter": 20000, "maxfev": 20000, "xatol": 1e-12,
                                "fatol": 1e-14})
        rounds.append((time.perf_counter() - t0) / res.nfev)
    scipy_nm = float(np.median(rounds))
    print(f"opening_spring_lse6: {ours * 1e6:.1f} us per evaluation; scipy Nelder-Mead on "
          f"Rosenbrock-5 {scipy_nm * 1e6:.1f} us: ratio {ours / scipy_nm:.2f} (target <= 3)")


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
