"""Tolerance analysis: 10,000 VCB samples (spring rate +-5 %, fixed link l1 +-0.1 mm,
closing dynamics included) evaluated in one pass of cache-sized chunks (camopt.core.batch, as
``camopt tolerance`` does; one call over 10^4 rows would need ~8 GiB), against a loop of
one-row calls (timed on a subset and given per sample)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from camopt.cases import build_problem
from camopt.core import batch
from camopt.core.perf import tune_allocator
from camopt.engine.driver import load

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "vcb_velocity.toml"


def one_pass_vs_loop(n: int = 10_000, n_loop: int = 300, rounds: int = 3) -> None:
    problem = build_problem(load(CONFIG).case)
    x = problem.vendor_x()
    rng = np.random.default_rng(np.random.SeedSequence(0))
    X = np.tile(x, (n, 1))
    X[:, 3] *= 1 + rng.uniform(-0.05, 0.05, n)
    l1 = problem.config.l1_mm + rng.uniform(-0.1, 0.1, n)

    def loop() -> None:
        for i in range(n_loop):
            problem.describe_with(X[i:i + 1], {"l1_mm": l1[i:i + 1]})

    batch.describe(problem, X[:100], {"l1_mm": l1[:100]})  # warm-up
    loop()
    vec, per = [], []
    for _ in range(rounds):  # interleaved: load elsewhere on the host hits both
        t0 = time.perf_counter()
        batch.describe(problem, X, {"l1_mm": l1})
        vec.append((time.perf_counter() - t0) / n)
        t0 = time.perf_counter()
        loop()
        per.append((time.perf_counter() - t0) / n_loop)
    ratio = np.median(np.array(per) / np.array(vec))
    print(f"VCB tolerance pass, {n} samples with per-sample l1 (median of {rounds} rounds): "
          f"one pass {np.median(vec) * n:.2f} s ({np.median(vec) * 1e6:.0f} us/sample), "
          f"loop {np.median(per) * 1e6:.0f} us/sample, speed-up {ratio:.0f}x")


def main() -> None:
    tune_allocator()
    one_pass_vs_loop()


if __name__ == "__main__":
    main()
