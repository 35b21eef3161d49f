"""Run archives: one HDF5 file per run, written atomically, read back as a RunView.

Layout (schema 1): root attributes (versions, exact TOML, config as run, seed);
``/repeats/rNNN`` per repeat with growable ``history/*`` datasets; ``/best`` with
``metrics``; ``/analysis/<curve>``; ``/table/<column>``; ``/summary/<column>``.
"""

from __future__ import annotations

import json
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from camopt.archive.files import atomic_write, check_writable, open_archive, versions
from camopt.archive.tables import read_table, write_table
from camopt.driver import RunRecord
from camopt.errors import ArchiveError
from camopt.problem import ACTIVE_TOL, FEASIBILITY_TOL
from camopt.runview import BestView, RepeatView, RunView

SCHEMA_VERSION = 1


def _write(f: h5py.File, rec: RunRecord) -> None:
    cfg, problem = rec.config, rec.problem
    attrs = {
        **versions(), "schema_version": SCHEMA_VERSION, "config_toml": cfg.text,
        "config_path": cfg.path, "overrides": json.dumps(list(cfg.overrides)),
        "config_effective": json.dumps(cfg.effective()), "case_kind": cfg.case.kind,
        "solver": cfg.solver.name, "run_name": cfg.run.name, "seed_entropy": str(rec.seed),
        "created": datetime.now(timezone.utc).isoformat(),
        "variables": json.dumps(list(problem.names)),
        "variable_scale": problem.scale, "constraints": json.dumps(list(problem.constraint_names)),
        "objective_name": problem.objective_name,
    }
    f.attrs.update(attrs)
    reps = f.create_group("repeats")
    for r in rec.repeats:
        grp = reps.create_group(f"r{r.index:03d}")
        grp.attrs.update({"spawn_key": json.dumps(list(r.spawn_key)), "seed": r.seed,
                          "objective": r.fun, "feasible": r.feasible, "violation": r.violation,
                          "nfev": r.nfev, "nit": r.nit, "wall_s": r.wall_s, "message": r.message,
                          "converged_nit": r.converged_nit, "notes": json.dumps(r.notes)})
        grp.create_dataset("x", data=r.x)
        grp.create_dataset("g", data=r.g)
        hist = grp.create_group("history")
        for key, values in r.history.items():
            hist.create_dataset(key, data=values, maxshape=(None,), chunks=True)
    best = f.create_group("best")
    best.attrs.update({"objective": rec.best.fun, "feasible": rec.best.feasible,
                       "repeat": rec.best.index})
    best.create_dataset("x", data=rec.best.x)
    best.create_dataset("g", data=rec.best.g)
    metrics = best.create_group("metrics", track_order=True)
    for key, value in rec.metrics.items():
        metrics.attrs[key] = value
    analysis = f.create_group("analysis")
    for key, value in rec.analysis.items():
        analysis.create_dataset(key, data=np.asarray(value))
    write_table(f.create_group("table"), rec.best.table)
    summary = [{"repeat": r.index, "seed": r.seed, "objective": r.fun, "feasible": r.feasible,
                "nfev": r.nfev, "converged_nit": r.converged_nit, "wall_s": r.wall_s}
               for r in rec.repeats]
    write_table(f.create_group("summary"), summary)


def write_run(rec: RunRecord, path: str | Path, force: bool = False) -> Path:
    """Write ``rec`` to a temporary file beside ``path`` and rename it when complete."""
    path = Path(path)
    check_writable(path, force)
    return atomic_write(path, lambda f: _write(f, rec))


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def load_run(path: str | Path) -> RunView:
    """A run archive as a :class:`RunView`; a sweep or a foreign file is an ArchiveError."""
    with open_archive(path) as f:
        if f.attrs.get("archive_kind", "run") != "run":
            raise ArchiveError(f"{path}: file: a {f.attrs['archive_kind']} archive, not a "
                               "run archive")
        names = tuple(json.loads(f.attrs["variables"]))
        constraints = tuple(json.loads(f.attrs["constraints"]))
        scale = np.asarray(f.attrs["variable_scale"])
        repeats = []
        for key in sorted(f["repeats"]):
            grp = f["repeats"][key]
            a = grp.attrs
            repeats.append(RepeatView(
                index=int(key[1:]), spawn_key=tuple(json.loads(a["spawn_key"])),
                seed=int(a["seed"]), objective=float(a["objective"]),
                feasible=bool(a["feasible"]), violation=float(a["violation"]),
                nfev=int(a["nfev"]), nit=int(a["nit"]), wall_s=float(a["wall_s"]),
                converged_nit=int(a["converged_nit"]), message=str(a["message"]),
                notes=tuple(json.loads(a["notes"])),
                x=dict(zip(names, (grp["x"][()] * scale).tolist())),
                history={k: v[()] for k, v in grp["history"].items()}))
        best = f["best"]
        g = best["g"][()]
        config = json.loads(f.attrs["config_effective"])
        return RunView(
            path=str(path), kind=str(f.attrs["case_kind"]),
            case={"kind": str(f.attrs["case_kind"]), **config["case"]},
            solver=config["solver"], run=config["run"],
            objective_name=str(f.attrs["objective_name"]), variables=names,
            constraints=constraints,
            best=BestView(
                objective=float(best.attrs["objective"]),
                feasible=bool(best.attrs["feasible"]),
                x=dict(zip(names, (best["x"][()] * scale).tolist())),
                metrics={k: _plain(v) for k, v in best["metrics"].attrs.items()},
                active=[c for c, gi in zip(constraints, g) if abs(gi) <= ACTIVE_TOL],
                violated=[c for c, gi in zip(constraints, g) if not gi <= FEASIBILITY_TOL],
                repeat=int(best.attrs["repeat"])),
            repeats=repeats, table=read_table(f["table"]),
            analysis={k: v[()] for k, v in f["analysis"].items()},
            config_toml=str(f.attrs["config_toml"]), created=str(f.attrs["created"]),
            camopt_version=str(f.attrs["camopt_version"]),
            seed_entropy=str(f.attrs["seed_entropy"]),
            interrupted=bool(f.attrs.get("interrupted", False)),
        )
