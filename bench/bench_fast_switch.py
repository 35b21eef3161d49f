"""Fast-switch evaluation: vectorised population call against a loop over individuals."""

from __future__ import annotations

import time

import numpy as np

from camopt.cases.fast_switch import FastSwitchConfig, FastSwitchProblem


def main(n_pop: int = 2000) -> None:
    p = FastSwitchProblem(FastSwitchConfig(branch="both"))
    rng = np.random.default_rng(0)
    X = p.lower + rng.random((n_pop, p.n_var)) * (p.upper - p.lower)
    X[:, 0] = np.rint(X[:, 0])
    t0 = time.perf_counter()
    for _ in range(5):
        p.evaluate(X)
    vec = (time.perf_counter() - t0) / 5 / n_pop
    t0 = time.perf_counter()
    for x in X[:200]:
        p.evaluate(x[None, :])
    loop = (time.perf_counter() - t0) / 200
    print(f"per individual: vectorised {vec * 1e6:.2f} us, loop {loop * 1e6:.1f} us, "
          f"speed-up {loop / vec:.0f}x")


if __name__ == "__main__":
    main()
