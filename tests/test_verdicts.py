"""One verdict everywhere: small runs of every shipped config, judged by run, show,
runs, compare, report, dashboard and export (table and JSON)."""

from __future__ import annotations

from pathlib import Path

from tests.conftest import CONFIGS

SHIPPED = sorted(CONFIGS.glob("*.toml")) + sorted((CONFIGS / "reference").glob("*.toml"))

BUDGETS = {  # per solver: the smallest budget that still runs every stage
    "de_gr": ["solver.population=10", "solver.generations=4"],
    "nsga2": ["solver.population=12", "solver.generations=3"],
    "pso": ["solver.particles=10", "solver.iterations=4"],
    "cmaes": ["solver.evaluations=200"],
}


def small_overrides(config: Path, folder: Path) -> list[str]:
    """``--set`` values that make ``config`` run in seconds (one repeat, a few
    generations, few robust draws); a step-2 VCB config gets a step-1 archive."""
    from camopt.engine.setup import load

    cfg = load(config, [])
    sets = list(BUDGETS.get(cfg.solver.name, []))
    if cfg.run.repeats > 1:
        sets.append("run.repeats=1")
    if getattr(cfg, "robust", None) is not None:
        sets += ["robust.samples=4", "robust.check_samples=40"]
    polish = getattr(cfg.solver, "polish", None)
    if polish is not None:
        sets.append("solver.polish.evaluations=100")
    if cfg.case.kind == "vcb" and getattr(cfg.case, "step", "") == "fourbar":
        step1 = folder / "vcb.h5"  # the cam of a small step-1 run
        sets.append(f'case.cam_archive="{step1}"')
    return sets
