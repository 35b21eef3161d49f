"""VCB closing dynamics per evaluation (issue #20): the search's evaluation of
``configs/vcb_velocity.toml`` with the velocity band (the identified parameters and every
set of ``dynamics_band``) against the same evaluation with the identified set alone (the
cost of the one-set model the band replaced), as a ratio measured in one run; and the
same band evaluation with the compiled closing events (camopt/cases/vcb/kernel.py) against
the numpy path (``CAMOPT_NUMBA=0``), interleaved in the same run (issue #36)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from camopt.cases.vcb import VcbProblem
from camopt.engine.driver import load

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb_velocity.toml"


def _per_call(problem: VcbProblem, X: np.ndarray, rounds: int = 7, calls: int = 5) -> float:
    """Median over rounds of the mean time of ``calls`` population evaluations (s)."""
    problem.evaluate(X)  # warm-up
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(calls):
            problem.evaluate(X)
        times.append((time.perf_counter() - t0) / calls)
    return float(np.median(times))


def main() -> None:
    band = VcbProblem(load(CONFIG, []).case)
    single = VcbProblem(load(CONFIG, ["case.dynamics_band=[]"]).case)
    rng = np.random.default_rng(0)
    X = band.lower + rng.random((100, band.n_var)) * (band.upper - band.lower)
    sets = 1 + len(band.config.dynamics_band)
    t_band, t_single = _per_call(band, X), _per_call(single, X)
    print(f"vcb_velocity evaluate, population 100: band of {sets} parameter sets "
          f"{t_band * 1e3:.1f} ms, identified set alone {t_single * 1e3:.1f} ms, "
          f"ratio {t_band / t_single:.2f} ({t_band / 100 * 1e6:.0f} us per design)")
    compiled, reference = [], []
    for _ in range(3):  # interleaved: a load change on a shared host hits both alike
        os.environ["CAMOPT_NUMBA"] = "0"
        reference.append(_per_call(band, X, rounds=3))
        os.environ["CAMOPT_NUMBA"] = "1"
        compiled.append(_per_call(band, X, rounds=3))
    os.environ.pop("CAMOPT_NUMBA")
    t_np, t_nb = float(np.median(reference)), float(np.median(compiled))
    print(f"vcb_velocity evaluate, population 100, band of {sets} sets: numpy path "
          f"{t_np * 1e3:.1f} ms, compiled band events {t_nb * 1e3:.1f} ms, speed-up "
          f"{t_np / t_nb:.2f}x ({t_nb / 100 * 1e6:.0f} us per design)")


if __name__ == "__main__":
    main()
