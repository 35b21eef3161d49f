"""Tolerance analysis: 10,000 VCB samples (spring rate +-5 %, fixed link l1 +-0.1 mm,
closing dynamics included) evaluated in one pass of cache-sized chunks (camopt.core.batch, as
``camopt tolerance`` does; one call over 10^4 rows would need ~8 GiB), against a loop of
one-row calls (timed on a subset and given per sample).

Peak memory (issue #36: 10^6 samples under 1 GiB): ``camopt tolerance`` of a short
``vcb_velocity_robust`` run (its class ``matched``: 15 inputs, 50 metrics, 14
constraints), 10^5 and 10^6 samples, each in its own process, its peak resident set size
from ``os.wait4`` (measured, not extrapolated: the allocator's thresholds make the bytes
a sample differ between the two; ~2.5 min CPU)."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from camopt.cases import build_problem
from camopt.core import batch
from camopt.core.perf import tune_allocator
from camopt.engine.driver import load

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "vcb_velocity.toml"
ROBUST = ROOT / "configs" / "vcb_velocity_robust.toml"
SHORT_RUN = ("run.repeats=1", "solver.generations=20", "robust.centre_generations=0",
             "robust.check_samples=200")
"""A ``vcb_velocity_robust`` run of ~2 s: a design of that case to vary (the memory of
the analysis does not depend on the design's quality)."""
ONE_GIB = 2**30


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


def peak_rss(args: list[str]) -> int:
    """Peak resident set size (bytes) of one child process running ``args``."""
    child = subprocess.Popen(args, stdout=subprocess.DEVNULL, cwd=ROOT)
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode:
        raise SystemExit(f"{args}: exit {child.returncode}")
    return usage.ru_maxrss * 1024  # kB on Linux


def tolerance_memory(samples: tuple[int, ...] = (100_000, 1_000_000)) -> None:
    camopt = [sys.executable, "-m", "camopt"]
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "robust.h5"
        subprocess.run([*camopt, "run", str(ROBUST), "--out", str(run), "--quiet",
                        *(a for s in SHORT_RUN for a in ("--set", s))],
                       stdout=subprocess.DEVNULL, check=True, cwd=ROOT)
        for n in samples:
            rss = peak_rss([*camopt, "tolerance", str(run), "--samples", str(n), "--seed",
                            "7", "--class", "matched", "--quiet", "--format", "json"])
            print(f"camopt tolerance, VCB class matched, {n} samples: peak RSS "
                  f"{rss / ONE_GIB:.3f} GiB ({rss / 2**20:.0f} MiB; target at 10^6: < 1 GiB)")


def main() -> None:
    tune_allocator()
    one_pass_vs_loop()
    tolerance_memory()


if __name__ == "__main__":
    main()
