"""Robust design's cost: the CPU time of each shipped robust config (configs/*_robust.toml)
as a ratio to (a) the same config without ``[robust]`` (same solver, same budget: the
price of the draws) and (b) one repeat of the case's shipped nominal config run for the
robust config's generations (issue #33's measure: "the CPU of a nominal run with the same
generations"; goal <= 10x), or, where the nominal solver stops on evaluations (cmaes), at
the robust search's candidate evaluations (population x generations). CPU time
(``time.process_time``), not wall time: the host is shared, and CPU is what the goal is
about. One run each, in one process, one after the other, after one evaluation of each
problem (the process's imports and the compiled kernel's load are no repeat's cost);
racing's saving is shown by the draws evaluated with and without it, the yield
centring's cost (``centre_generations``) by the same run without it.

``python -m bench.bench_robust [CONFIG ...] [--generations N]``: only those robust
configs (e.g. ``vcb_velocity_robust``), and every run at N generations (a reduced budget
while developing; the ratio is then for N generations); ``--ratio-only``: the robust
repeat and the nominal one alone; ``--times N``: the robust and the nominal repeat N
times each, one after the other in turn, and their medians (a nominal repeat of ~3 s
moved by 30 % between runs on the shared host; the ratio of medians is steadier).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

from camopt.core.perf import tune_allocator
from camopt.engine.driver import execute, load, prepare

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
PAIRS = (("fast_switch_robust", "fast_switch_de"), ("vcb_velocity_robust", "vcb_velocity"),
         ("emb_robust", "emb"))


def _cpu(config) -> tuple[float, int]:  # type: ignore[no-untyped-def]
    """CPU seconds of one repeat and the candidate draws its robust problem evaluated."""
    t0 = time.process_time()
    result = execute(config, repeats=1)
    return time.process_time() - t0, int(getattr(result.problem, "draws_evaluated", 0))


def _warm(config) -> None:  # type: ignore[no-untyped-def]
    """One evaluation of the config's problem before any timing: the imports and the
    compiled kernel's load (numba, once per process) are no repeat's cost."""
    problem, _ = prepare(config)
    problem.evaluate(0.5 * (problem.lower + problem.upper)[None, :])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("configs", nargs="*", help="robust configs to measure (default all)")
    parser.add_argument("--generations", type=int, default=None)
    parser.add_argument("--ratio-only", action="store_true",
                        help="only the robust repeat and the nominal one (no runs without "
                        "[robust], centring or racing)")
    parser.add_argument("--times", type=int, default=1,
                        help="the robust and the nominal repeat this many times each, in "
                        "turn: their medians")
    args = parser.parse_args(argv)
    tune_allocator()
    for robust_name, nominal_name in PAIRS:
        if args.configs and robust_name not in args.configs:
            continue
        over = [] if args.generations is None else [f"solver.generations={args.generations}"]
        cfg = load(CONFIGS / f"{robust_name}.toml", over)
        assert cfg.robust is not None
        gens = getattr(cfg.solver, "generations", None)
        pop = getattr(cfg.solver, "population", None)
        nominal = load(CONFIGS / f"{nominal_name}.toml")
        # the nominal run's budget: the robust search's generations, or, for a solver that
        # stops on its evaluations (cmaes: generations are only a ceiling), the robust
        # search's candidate evaluations (population x generations)
        if hasattr(nominal.solver, "evaluations") and gens is not None and pop is not None:
            same_gens, budget = [f"solver.evaluations={pop * gens}"], f"{pop * gens} evaluations"
        else:
            same_gens = [f"solver.generations={gens}"] if gens is not None else []
            budget = f"{gens} generations"
        _warm(cfg)
        _warm(nominal)
        robust_times, shipped_times = [], []
        for _ in range(max(args.times, 1)):  # in turn: a change of load falls on both
            robust_s, draws = _cpu(cfg)
            robust_times.append(robust_s)
            shipped_times.append(_cpu(load(CONFIGS / f"{nominal_name}.toml", same_gens))[0])
        robust_s = statistics.median(robust_times)
        shipped_s = statistics.median(shipped_times)
        unraced = dataclasses.replace(cfg, robust=cfg.robust.model_copy(update={"race": 0}))
        if len(robust_times) > 1:
            print(f"{robust_name}: {len(robust_times)} times each, robust "
                  f"{', '.join(f'{t:.1f}' for t in robust_times)} s, {nominal_name}.toml "
                  f"{', '.join(f'{t:.1f}' for t in shipped_times)} s: medians", flush=True)
        if args.ratio_only:
            print(f"{robust_name}: robust {robust_s:.1f} s CPU; {nominal_name}.toml at "
                  f"{budget} {shipped_s:.1f} s: {robust_s / shipped_s:.1f}x (goal <= 10x)",
                  flush=True)
            continue
        same_s, _ = _cpu(dataclasses.replace(cfg, robust=None))
        line = (f"{robust_name}: robust {robust_s:.1f} s CPU ({cfg.robust.samples} draws, "
                f"race {cfg.robust.race}, {draws} candidate draws evaluated; "
                f"{cfg.robust.finalists} finalists x {cfg.robust.check_samples}); "
                f"same budget without [robust] {same_s:.1f} s: {robust_s / same_s:.1f}x; "
                f"{nominal_name}.toml at {budget} {shipped_s:.1f} s: "
                f"{robust_s / shipped_s:.1f}x (goal <= 10x)")
        print(line, flush=True)
        if cfg.robust.centre_generations:
            # the yield centring is a stage after the search: its share apart
            search_s, _ = _cpu(dataclasses.replace(cfg, robust=cfg.robust.model_copy(
                update={"centre_generations": 0})))
            print(f"  without its {cfg.robust.centre_generations} generations of yield "
                  f"centring: {search_s:.1f} s CPU ({search_s / shipped_s:.1f}x); the "
                  f"centring {robust_s - search_s:.1f} s", flush=True)
        if cfg.robust.race:
            unraced_s, unraced_draws = _cpu(unraced)
            print(f"  without racing: {unraced_s:.1f} s CPU, {unraced_draws} candidate draws "
                  f"({unraced_s / shipped_s:.1f}x)", flush=True)


if __name__ == "__main__":
    main()
