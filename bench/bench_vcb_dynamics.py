"""VCB closing dynamics per evaluation, as a run makes them (``tune_allocator()`` first,
as ``camopt run`` does; the problem from ``prepare``): the search's evaluation of
``configs/vcb_velocity.toml`` with the velocity band (the identified parameters and every
set of ``dynamics_band``) against the same evaluation with the identified set alone (the
cost of the one-set model the band replaced); the same band evaluation with the compiled
kernel (camopt/cases/vcb/kernel.py: the whole closing of the nominal set and of the band,
one call each) against the numpy path (``CAMOPT_NUMBA=0``), interleaved; and one design
per call (what a local solver or a figure pays: the fixed cost). CPU time
(``time.process_time``), ratios inside this one run."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from camopt.core.perf import tune_allocator
from camopt.engine.driver import load, prepare

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb_velocity.toml"


def _per_call(problem, X: np.ndarray, rounds: int = 7, calls: int = 5) -> float:  # type: ignore[no-untyped-def]
    """Median over rounds of the mean CPU time of ``calls`` population evaluations (s)."""
    problem.evaluate(X)  # warm-up
    times = []
    for _ in range(rounds):
        t0 = time.process_time()
        for _ in range(calls):
            problem.evaluate(X)
        times.append((time.process_time() - t0) / calls)
    return float(np.median(times))


def main() -> None:
    tune_allocator()  # what every run makes (camopt run, sweep, tolerance)
    band, _ = prepare(load(CONFIG, []))
    single, _ = prepare(load(CONFIG, ["case.dynamics_band=[]"]))
    rng = np.random.default_rng(0)
    X = band.lower + rng.random((100, band.n_var)) * (band.upper - band.lower)
    sets = 1 + len(band.config.dynamics_band)
    t_band, t_single = _per_call(band, X), _per_call(single, X)
    print(f"vcb_velocity evaluate, population 100: band of {sets} parameter sets "
          f"{t_band * 1e3:.1f} ms, identified set alone {t_single * 1e3:.1f} ms, "
          f"ratio {t_band / t_single:.2f} ({t_band / 100 * 1e6:.0f} us per design)")
    compiled, reference, one, one_np = [], [], [], []
    x1 = band.vendor_x()[None, :]
    for _ in range(3):  # interleaved: a load change on a shared host hits both alike
        os.environ["CAMOPT_NUMBA"] = "0"
        reference.append(_per_call(band, X, rounds=3))
        one_np.append(_per_call(band, x1, rounds=3, calls=50))
        os.environ["CAMOPT_NUMBA"] = "1"
        compiled.append(_per_call(band, X, rounds=3))
        one.append(_per_call(band, x1, rounds=3, calls=50))
    os.environ.pop("CAMOPT_NUMBA")
    t_np, t_nb = float(np.median(reference)), float(np.median(compiled))
    print(f"vcb_velocity evaluate, population 100, band of {sets} sets: numpy path "
          f"{t_np * 1e3:.1f} ms, compiled kernel {t_nb * 1e3:.1f} ms, speed-up "
          f"{t_np / t_nb:.2f}x ({t_nb / 100 * 1e6:.0f} us per design)")
    s_np, s_nb = float(np.median(one_np)), float(np.median(one))
    print(f"vcb_velocity evaluate of one design (band of {sets} sets): numpy path "
          f"{s_np * 1e3:.2f} ms, compiled kernel {s_nb * 1e3:.2f} ms per call (goal <= 1 ms)")


if __name__ == "__main__":
    main()
