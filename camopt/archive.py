"""HDF5 run archives (h5py only): write atomically, read back as plain data.

Layout (schema 1): root attributes (versions, exact TOML, parsed config, seed);
``/repeats/rNNN`` per repeat with growable ``history/*`` datasets; ``/best`` with
``metrics``; ``/analysis/<curve>``; ``/table/<column>``; ``/summary/<column>``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import platform
import tempfile
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5py
import numpy as np

import camopt
from camopt.config import LoadedConfig
from camopt.driver import RunRecord
from camopt.errors import ArchiveError, ConfigError
from camopt.problem import ACTIVE_TOL

SCHEMA_VERSION = 1
_STR = h5py.string_dtype()


def default_path(name: str, out_dir: str | Path = "runs") -> Path:
    """``runs/<name>-<UTC timestamp>.h5``."""
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S%fZ")
    return Path(out_dir) / f"{name}-{stamp}.h5"


def check_writable(path: Path, force: bool) -> None:
    """Fail before any work if ``path`` exists (without force) or its folder is not writable."""
    if path.exists() and not force:
        raise ArchiveError(f"{path}: --out: exists; pass --force to overwrite")
    if path.is_dir():
        raise ArchiveError(f"{path}: --out: is a directory")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ArchiveError(f"{path}: --out: folder {folder} does not exist")
    try:  # a real probe: os.access says yes to root even where writing fails
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".camopt-probe-")
    except OSError as exc:
        raise ArchiveError(f"{path}: --out: folder {folder} is not writable "
                           f"({exc.strerror})") from None
    os.close(fd)
    os.unlink(probe)


def versions() -> dict[str, str]:
    import scipy

    return {"camopt_version": camopt.__version__, "python_version": platform.python_version(),
            "numpy_version": np.__version__, "scipy_version": scipy.__version__,
            "h5py_version": h5py.__version__}


def write_table(group: h5py.Group, rows: list[dict[str, Any]]) -> None:
    """A list of row dicts as one dataset per column (lists and strings as JSON text)."""
    columns: list[str] = []
    for row in rows:
        columns += [k for k in row if k not in columns]
    group.attrs["columns"] = json.dumps(columns)
    for col in columns:
        values = [row.get(col) for row in rows]
        if all(isinstance(v, (bool, np.bool_)) for v in values):
            group.create_dataset(col, data=np.array(values, dtype=bool))
        elif all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool)
                 for v in values):
            group.create_dataset(col, data=np.array(values, dtype=float))
        else:  # lists and strings: JSON text per row
            group.create_dataset(col, data=[json.dumps(v) for v in values], dtype=_STR)
            group[col].attrs["json"] = True


def read_table(group: h5py.Group) -> list[dict[str, Any]]:
    """Rows written by :func:`write_table`."""
    columns = json.loads(group.attrs["columns"])
    data = {}
    for col in columns:
        ds = group[col]
        if ds.attrs.get("json", False):
            data[col] = [json.loads(v) for v in ds.asstr()[()]]
        else:
            data[col] = ds[()].tolist()
    n = len(data[columns[0]]) if columns else 0
    return [{c: data[c][i] for c in columns} for i in range(n)]


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


def atomic_write(path: Path, write: Any) -> Path:
    """Call ``write(h5py.File)`` on a temporary file beside ``path``, then rename it into
    place: readers see the old complete file or the new one, never a partial one."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_run(rec: RunRecord, path: str | Path, force: bool = False) -> Path:
    """Write ``rec`` to a temporary file beside ``path`` and rename it when complete."""
    path = Path(path)
    check_writable(path, force)
    return atomic_write(path, lambda f: _write(f, rec))


def open_run(path: str | Path) -> h5py.File:
    """Open an archive read-only; anything else is an ArchiveError naming the file."""
    path = Path(path)
    if not path.is_file():
        raise ArchiveError(f"{path}: file: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise ArchiveError(f"{path}: file: not a camopt archive (not HDF5)") from None
    if "schema_version" not in f.attrs or "camopt_version" not in f.attrs:
        f.close()
        raise ArchiveError(f"{path}: file: not a camopt archive (no camopt attributes)")
    return f


def archive_kind(path: str | Path) -> str:
    """'run' or 'sweep'."""
    with open_run(path) as f:
        return str(f.attrs.get("archive_kind", "run"))


def load_run(path: str | Path) -> dict[str, Any]:
    """An archive as plain data: the ``show --format json`` structure plus ``extra``."""
    with open_run(path) as f:
        if f.attrs.get("archive_kind", "run") != "run":
            raise ArchiveError(f"{path}: file: a sweep archive, not a run archive")
        names = json.loads(f.attrs["variables"])
        scale = np.asarray(f.attrs["variable_scale"])
        best = f["best"]
        repeats = []
        histories = []
        for key in sorted(f["repeats"]):
            grp = f["repeats"][key]
            a = grp.attrs
            repeats.append({"seed": int(a["seed"]), "objective": float(a["objective"]),
                            "feasible": bool(a["feasible"]), "nfev": int(a["nfev"]),
                            "wall_s": float(a["wall_s"]),
                            "converged_nit": int(a["converged_nit"]),
                            "notes": json.loads(a["notes"]),
                            "spawn_key": json.loads(a["spawn_key"]),
                            "x": dict(zip(names, (grp["x"][()] * scale).tolist()))})
            histories.append({k: v[()] for k, v in grp["history"].items()})
        config = json.loads(f.attrs["config_effective"])
        return {
            "case": {"kind": str(f.attrs["case_kind"]), **config["case"]},
            "solver": config["solver"],
            "best": {
                "objective": float(best.attrs["objective"]),
                "feasible": bool(best.attrs["feasible"]),
                "x": dict(zip(names, (best["x"][()] * scale).tolist())),
                "metrics": {k: _plain(v) for k, v in best["metrics"].attrs.items()},
                "active": [c for c, gi in zip(json.loads(f.attrs["constraints"]), best["g"][()])
                           if abs(gi) <= ACTIVE_TOL],
            },
            "repeats": repeats,
            "table": read_table(f["table"]),
            "extra": {
                "path": str(path), "run": config["run"],
                "objective_name": str(f.attrs["objective_name"]),
                "config_toml": str(f.attrs["config_toml"]),
                "created": str(f.attrs["created"]),
                "camopt_version": str(f.attrs["camopt_version"]),
                "histories": histories,
                "analysis": {k: v[()] for k, v in f["analysis"].items()},
                "seed_entropy": str(f.attrs["seed_entropy"]),
            },
        }


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def resolve_references(config: LoadedConfig) -> LoadedConfig:
    """Fill values a case file takes from another run's archive (VCB step 2's
    ``cam_archive`` -> ``cam_design``); the archive path is relative to the working
    folder, else to the case file's folder."""
    case = config.case
    ref = getattr(case, "cam_archive", None)
    if not ref:
        return config
    path = Path(ref)
    if not path.is_file() and (Path(config.path).parent / ref).is_file():
        path = Path(config.path).parent / ref
    try:
        run = load_run(path)
    except ArchiveError as exc:
        raise ConfigError(config.path, "case.cam_archive", str(exc)) from None
    x = run["best"]["x"]
    if run["case"]["kind"] != "vcb" or run["case"].get("step") != "cam" or "a1" not in x:
        raise ConfigError(config.path, "case.cam_archive",
                          f"{path} is not a VCB step-1 (cam) run archive")
    design = {"a0": run["best"]["metrics"]["a0"], "a1": x["a1"], "a2": x["a2"], "a3": x["a3"],
              "kc1_n_per_mm": x["kc1_n_per_mm"], "kc2_n_per_mm": x["kc2_n_per_mm"]}
    new_case = type(case).model_validate({**case.model_dump(), "cam_design": design})
    return dataclasses.replace(config, case=new_case)
