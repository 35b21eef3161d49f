"""Robust design's cost: the wall time of each shipped robust config (configs/*_robust.toml)
as a ratio to (a) the same config without ``[robust]`` (same solver, same budget: the
price of the draws) and (b) one repeat of the case's shipped nominal config (what a user
runs for the nominal optimum). Goal of issue #21: <= 10x. One run each, no repetition
(minutes on a loaded 2-core host); ratios are within one process, one after the other."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

from camopt.core.perf import tune_allocator
from camopt.engine.driver import execute, load

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
PAIRS = (("fast_switch_robust", "fast_switch_de"), ("vcb_velocity_robust", "vcb_velocity"),
         ("emb_robust", "emb"))


def _wall(config) -> float:  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    execute(config, repeats=1)
    return time.perf_counter() - t0


def main() -> None:
    tune_allocator()
    for robust_name, nominal_name in PAIRS:
        cfg = load(CONFIGS / f"{robust_name}.toml")
        assert cfg.robust is not None
        robust_s = _wall(cfg)
        same_s = _wall(dataclasses.replace(cfg, robust=None))
        shipped_s = _wall(load(CONFIGS / f"{nominal_name}.toml"))
        print(f"{robust_name}: robust {robust_s:.1f} s ({cfg.robust.samples} draws, "
              f"{cfg.robust.finalists} finalists x {cfg.robust.check_samples}); "
              f"same budget without [robust] {same_s:.1f} s: {robust_s / same_s:.1f}x; "
              f"one repeat of {nominal_name}.toml {shipped_s:.1f} s: "
              f"{robust_s / shipped_s:.1f}x (goal <= 10x)")


if __name__ == "__main__":
    main()
