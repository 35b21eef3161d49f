"""Plain-data views of archives for ``show`` and ``compare`` (no printing here)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

SHOW_KEYS = ("case", "solver", "best", "repeats", "table")


def jsonable(value: Any) -> Any:
    """Replace non-finite floats by None and numpy scalars by Python ones, recursively."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def show(run: dict[str, Any]) -> dict[str, Any]:
    """The ``show --format json`` document: exactly case, solver, best, repeats, table."""
    keys = ("seed", "objective", "feasible", "nfev", "wall_s", "converged_nit", "spawn_key",
            "notes")
    repeats = [{k: r[k] for k in keys}
               for r in run["repeats"]]
    doc = {"case": run["case"], "solver": run["solver"], "best": run["best"],
           "repeats": repeats, "table": run["table"]}
    return jsonable(doc)


def _flatten(prefix: str, value: Any, out: dict[str, Any]) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(f"{prefix}.{k}" if prefix else k, v, out)
    else:
        out[prefix] = value


def repeat_statistics(run: dict[str, Any]) -> dict[str, Any]:
    """Best, median and worst final objective over repeats and the feasible fraction."""
    f = np.array([r["objective"] for r in run["repeats"]], dtype=float)
    feasible = np.array([r["feasible"] for r in run["repeats"]], dtype=bool)
    return {"repeats": int(f.size), "best": float(np.min(f)), "median": float(np.median(f)),
            "worst": float(np.max(f)), "feasible_fraction": float(feasible.mean())}


def compare(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """Config differences, best objectives, variables, metrics and repeat statistics."""
    flat = []
    for run in runs:
        cfg: dict[str, Any] = {}
        _flatten("", {"case": run["case"], "solver": run["solver"], "run": run["extra"]["run"]},
                 cfg)
        flat.append(cfg)
    keys = sorted(set().union(*flat))
    differences = {k: [c.get(k) for c in flat] for k in keys
                   if any(c.get(k) != flat[0].get(k) for c in flat)}

    def side_by_side(section: str) -> dict[str, list[Any]]:
        names: list[str] = []
        for run in runs:
            names += [n for n in run["best"][section] if n not in names]
        return {n: [run["best"][section].get(n) for run in runs] for n in names}

    return jsonable({
        "runs": [run["extra"]["path"] for run in runs],
        "config_differences": differences,
        "objective": [run["best"]["objective"] for run in runs],
        "feasible": [run["best"]["feasible"] for run in runs],
        "x": side_by_side("x"),
        "metrics": side_by_side("metrics"),
        "statistics": [repeat_statistics(run) for run in runs],
    })
