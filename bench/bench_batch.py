"""Issue #24's hot paths, each as a ratio measured in this run (CPU time of this process,
interleaved rounds, median): the batched path's chunks against one call over many VCB
rows (the VCB closing dynamics hold ~0.85 MiB of temporaries a row: one call over 10^4
rows would need ~8 GiB, so the comparison is made at 1,024); the EMB lift correction's
two end samples against the whole profile; the fast switch's search evaluation against
its descriptive one; and the time of an infeasible fast-switch design's metrics (the
exact dynamics skipped)."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from camopt.cases import build_problem
from camopt.core import batch
from camopt.core.perf import tune_allocator
from camopt.engine.driver import load

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


def _cpu(fn: Callable[[], object], number: int = 1) -> float:
    t0 = time.process_time()
    for _ in range(number):
        fn()
    return (time.process_time() - t0) / number


def _median_ratio(slow: Callable[[], object], fast: Callable[[], object], rounds: int,
                  number: int = 1) -> tuple[float, float, float]:
    """Median CPU seconds of ``slow`` and ``fast`` per call over interleaved rounds, and
    the median of the per-round ratios slow/fast."""
    a, b = [], []
    for _ in range(rounds):
        a.append(_cpu(slow, number))
        b.append(_cpu(fast, number))
    return float(np.median(a)), float(np.median(b)), float(np.median(np.array(a) / b))


def chunks_vs_one_call(n: int = 1024, rounds: int = 2) -> None:
    """VCB describe with the closing dynamics and a per-row l1 (the tolerance pass) over
    ``n`` rows: chunks of 100, 256 (default) and 1,000 rows against one call."""
    problem = build_problem(load(CONFIGS / "vcb_velocity.toml").case)
    rng = np.random.default_rng(np.random.SeedSequence(0))
    X = np.tile(problem.vendor_x(), (n, 1))
    X[:, 3] *= 1 + rng.uniform(-0.05, 0.05, n)
    fields = {"l1_mm": problem.config.l1_mm + rng.uniform(-0.1, 0.1, n)}
    batch.describe(problem, X[:300], {k: v[:300] for k, v in fields.items()})  # warm-up
    for size in (64, batch.CHUNK_ROWS):
        one, chunked, ratio = _median_ratio(
            lambda: problem.describe_with(X, fields),
            lambda size=size: batch.describe(problem, X, fields, size=size), rounds)
        print(f"VCB describe of {n} rows: one call {one / n * 1e6:.0f} us/row, chunks of "
              f"{size} {chunked / n * 1e6:.0f} us/row: {ratio:.2f}x faster per design")


def emb_lift(rounds: int = 5, number: int = 200) -> None:
    """The lift correction's lift (Eq 37) of 60 particles: whole profile vs end samples."""
    p = build_problem(load(CONFIGS / "emb.toml").case)
    rng = np.random.default_rng(1)
    n = 60
    R = p.r_st + np.sort(rng.uniform(0, 1, (n, p.n - 1)), axis=1) * p.rg / 2
    X = np.column_stack([R, rng.uniform(0, p.kappa_max / 2, n), rng.uniform(0.01, 0.5, n) * p.rg])
    whole, ends, ratio = _median_ratio(lambda: p.profile(X).s[:, -1], lambda: p.lift(X),
                                       rounds, number)
    print(f"EMB lift of {n} particles: whole profile ({p.u.size} samples) {whole * 1e6:.0f} us, "
          f"two end samples {ends * 1e6:.0f} us: {ratio:.1f}x cheaper (bit-identical)")


def fast_switch_search_path(rounds: int = 5, number: int = 200) -> None:
    """Population 100: ``evaluate`` (what a search reads) against ``describe`` (the same
    plus x1..x13 and the full model's equality residuals, as evaluate computed before)."""
    p = build_problem(load(CONFIGS / "fast_switch_de.toml").case)
    X = p.sample(np.random.default_rng(0), 100)
    X[:, 0] = np.rint(X[:, 0])
    full, lean, ratio = _median_ratio(lambda: p.describe(X), lambda: p.evaluate(X), rounds,
                                      number)
    print(f"fast switch, population 100: describe {full * 1e6:.0f} us, evaluate "
          f"{lean * 1e6:.0f} us: the search's path {ratio:.2f}x cheaper")


def fast_switch_metrics_bounded() -> None:
    """Metrics of an infeasible design whose exact motion oscillates short of 90 deg
    (130 s of ODE before #24) and of the feasible paper optimum (ODE computed)."""
    p = build_problem(load(CONFIGS / "fast_switch_de.toml").case)
    X = p.sample(np.random.default_rng(5), 40)
    X[:, 0] = np.rint(X[:, 0])
    bad = _cpu(lambda: p.metrics(X[35]))
    good = _cpu(lambda: p.metrics(p.family()[4]))
    print(f"fast switch metrics: infeasible design {bad * 1e3:.1f} ms "
          f"({p.metrics(X[35])['exact_dynamics']}), feasible optimum {good * 1e3:.0f} ms "
          "(computed)")


def main() -> None:
    tune_allocator()
    chunks_vs_one_call()
    emb_lift()
    fast_switch_search_path()
    fast_switch_metrics_bounded()


if __name__ == "__main__":
    main()
