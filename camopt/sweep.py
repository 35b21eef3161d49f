"""Sweeps: the Cartesian product of grid values x seeds, each cell one solver run.

A cell is a plain, picklable spec (validated config data, seed entropy, seed index),
so the same function runs it inline, in a local process pool or on a Dask cluster,
and its result does not depend on where it ran. Seed k of every grid point is child k
of ``SeedSequence(run.seed)``. The sweep archive is rewritten atomically after each
finished cell: it is a valid archive at every moment, an interruption loses no
finished cell, and ``--resume`` runs only the missing ones.
"""

from __future__ import annotations

import copy
import itertools
import json
import re
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from camopt import archive
from camopt.config import LoadedConfig, validate_data
from camopt.config.loader import apply_override, parse_value
from camopt.driver import prepare, run_repeat
from camopt.errors import ArchiveError, ConfigError
from camopt.perf import tune_allocator
from camopt.solvers import solvers

SCHEMA_VERSION = 1


# ---- specification ------------------------------------------------------------------
def parse_seeds(text: str) -> tuple[int, int]:
    """'0:25' -> (0, 25); '7' -> (0, 7)."""
    m = re.fullmatch(r"\s*(\d+)\s*(?::\s*(\d+)\s*)?", text)
    if not m:
        raise ConfigError("--seeds", text, "expected START:STOP (e.g. 0:25) or a count")
    start, stop = (0, int(m.group(1))) if m.group(2) is None else (int(m.group(1)),
                                                                    int(m.group(2)))
    if stop <= start:
        raise ConfigError("--seeds", text, "STOP must be above START")
    return start, stop


def _split_top(text: str) -> list[str]:
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += ch in "[{"
        depth -= ch in "]}"
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    return [*parts, cur]


def parse_grid(items: Iterable[str]) -> list[tuple[str, list[Any]]]:
    """'solver.population=50,100,200' -> [('solver.population', [50, 100, 200])]."""
    grid = []
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not re.fullmatch(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)+", key):
            raise ConfigError("--grid", item, "expected section.key=v1,v2,...")
        values = []
        for part in _split_top(raw):
            try:
                values.append(parse_value(part))
            except ValueError:
                raise ConfigError("--grid", key, f"cannot parse value {part!r}") from None
        grid.append((key, values))
    return grid


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs: the base config, the grid, the seed range."""

    data: dict[str, Any]
    source: str
    text: str
    grid: list[tuple[str, list[Any]]]
    seeds: tuple[int, int]

    @property
    def entropy(self) -> int:
        return int(self.data["run"]["seed"])

    def points(self) -> list[dict[str, Any]]:
        keys = [k for k, _ in self.grid]
        return [dict(zip(keys, combo))
                for combo in itertools.product(*(v for _, v in self.grid))] or [{}]

    def point_data(self, point: dict[str, Any]) -> dict[str, Any]:
        data = copy.deepcopy(self.data)
        for key, value in point.items():
            apply_override(data, key, value)
        return data

    def validate(self) -> list[LoadedConfig]:
        """Validate every grid point's config now, so a bad grid fails before any work."""
        opts = {n: c.Options for n, c in solvers().items()}
        out = []
        for point in self.points():
            cfg = validate_data(self.point_data(point), opts, self.source, self.text)
            prepare(cfg)
            out.append(cfg)
        return out

    def cells(self) -> list[CellSpec]:
        return [CellSpec(self.point_data(p), self.source, self.entropy, s, i)
                for i, p in enumerate(self.points()) for s in range(*self.seeds)]

    def to_json(self) -> str:
        return json.dumps({"data": self.data, "source": self.source, "grid": self.grid,
                           "seeds": list(self.seeds)})

    @classmethod
    def from_json(cls, text: str, toml_text: str) -> SweepSpec:
        d = json.loads(text)
        return cls(d["data"], d["source"], toml_text, [tuple(g) for g in d["grid"]],
                   tuple(d["seeds"]))


@dataclass(frozen=True)
class CellSpec:
    """One cell: a grid point's config data and one seed index."""

    data: dict[str, Any]
    source: str
    entropy: int
    seed: int
    point: int

    @property
    def key(self) -> tuple[int, int]:
        return (self.point, self.seed)


@dataclass
class CellResult:
    """What a cell returns (plain data, so it pickles to any worker and back)."""

    point: int
    seed: int
    objective: float
    feasible: bool
    success: bool
    nfev: int
    nit: int
    wall_s: float
    converged_nit: int
    nfev_to_target: int
    x: list[float]
    history: dict[str, list[float]] = field(default_factory=dict)

    @property
    def key(self) -> tuple[int, int]:
        return (self.point, self.seed)


def run_cell(cell: CellSpec) -> CellResult:
    """Run one cell (a top-level function: process pools and Dask pickle it by name)."""
    tune_allocator()
    cfg = validate_data(cell.data, {n: c.Options for n, c in solvers().items()}, cell.source)
    problem, solver_cls = prepare(cfg)
    child = np.random.SeedSequence(cell.entropy, spawn_key=(cell.seed,))
    rec = run_repeat(problem, solver_cls, cfg, child, cell.seed, 1)
    target = cfg.run.target
    h = rec.history
    ok = h["best_violation"] == 0
    if target is not None:
        ok &= h["best_objective"] <= target
    success = bool(rec.feasible and (target is None or rec.fun <= target))
    return CellResult(
        point=cell.point, seed=cell.seed, objective=rec.fun, feasible=rec.feasible,
        success=success, nfev=rec.nfev, nit=rec.nit, wall_s=rec.wall_s,
        converged_nit=rec.converged_nit,
        nfev_to_target=int(h["nfev"][np.argmax(ok)]) if ok.any() else -1,
        x=rec.x.tolist(),
        history={k: np.asarray(v).tolist() for k, v in h.items()},
    )


# ---- summary ------------------------------------------------------------------------
def summary(spec: SweepSpec, results: Iterable[CellResult]) -> list[dict[str, Any]]:
    """One row per grid point: success rate, objective statistics, evaluations to target."""
    by_point: dict[int, list[CellResult]] = {}
    for r in results:
        by_point.setdefault(r.point, []).append(r)
    rows = []
    for i, point in enumerate(spec.points()):
        cells = sorted(by_point.get(i, []), key=lambda r: r.seed)
        f = np.array([c.objective if c.feasible else np.inf for c in cells], dtype=float)
        reach = [c.nfev_to_target for c in cells if c.nfev_to_target >= 0]
        row: dict[str, Any] = {"point": i, **{k: json.dumps(v) for k, v in point.items()},
                               "runs": len(cells), "successes": sum(c.success for c in cells)}
        row.update({
            "success_rate": row["successes"] / len(cells) if cells else float("nan"),
            "best": float(np.min(f)) if cells else float("nan"),
            "median": float(np.median(f)) if cells else float("nan"),
            "worst": float(np.max(f)) if cells else float("nan"),
            "median_nfev_to_target": float(np.median(reach)) if reach else float("nan"),
            "wall_s_median": float(np.median([c.wall_s for c in cells])) if cells else 0.0,
        })
        rows.append(row)
    return rows


# ---- archive --------------------------------------------------------------------------
def write_sweep(path: Path, spec: SweepSpec, results: dict[tuple[int, int], CellResult],
                total: int) -> None:
    """Rewrite the sweep archive atomically with every finished cell."""

    def write(f: h5py.File) -> None:
        f.attrs.update({
            **archive.versions(), "schema_version": SCHEMA_VERSION, "archive_kind": "sweep",
            "config_toml": spec.text, "config_path": spec.source, "spec": spec.to_json(),
            "seed_entropy": str(spec.entropy), "cells_total": total,
            "cells_done": len(results), "complete": len(results) == total,
            "created": datetime.now(timezone.utc).isoformat(),
        })
        cells = f.create_group("cells")
        for key in sorted(results):
            r = results[key]
            g = cells.create_group(f"p{r.point:03d}_s{r.seed:05d}")
            meta = {k: v for k, v in asdict(r).items() if k not in ("x", "history")}
            g.attrs.update(meta)
            g.create_dataset("x", data=np.asarray(r.x))
            hist = g.create_group("history")
            for k, v in r.history.items():
                hist.create_dataset(k, data=np.asarray(v), maxshape=(None,), chunks=True)
        archive.write_table(f.create_group("summary"), summary(spec, results.values()))

    archive.atomic_write(path, write)


def load_sweep(path: str | Path) -> tuple[SweepSpec, dict[tuple[int, int], CellResult]]:
    """A sweep archive's spec and finished cells."""
    with archive.open_run(path) as f:
        if f.attrs.get("archive_kind") != "sweep":
            raise ArchiveError(f"{path}: file: a run archive, not a sweep archive")
        spec = SweepSpec.from_json(str(f.attrs["spec"]), str(f.attrs["config_toml"]))
        results = {}
        for g in f["cells"].values():
            a = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in g.attrs.items()}
            r = CellResult(**a, x=g["x"][()].tolist(),
                           history={k: v[()].tolist() for k, v in g["history"].items()})
            results[r.key] = r
    return spec, results


# ---- execution ------------------------------------------------------------------------
class SweepInterrupted(Exception):
    """Raised when a sweep stops early; the archive holds every finished cell."""


def _local(cells: list[CellSpec], jobs: int, done: Callable[[CellResult], None]) -> None:
    if jobs <= 1:
        for cell in cells:
            done(run_cell(cell))
        return
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("fork"))
    try:
        pending = {pool.submit(run_cell, c) for c in cells}
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(fut.result())
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _dask(cells: list[CellSpec], scheduler: str, done: Callable[[CellResult], None]) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError("--executor", "dask",
                          "needs the 'distributed' package: pip install 'camopt[dask]'") from None
    with Client(scheduler, timeout="20s") as client:
        futures = client.map(run_cell, cells, pure=False)
        for fut in as_completed(futures):
            done(fut.result())


def run_sweep(spec: SweepSpec, path: Path, results: dict[tuple[int, int], CellResult],
              jobs: int = 1, executor: str = "local", scheduler: str | None = None,
              progress: Callable[[int, int], None] | None = None) -> dict:
    """Run every cell not yet in ``results``, rewriting the archive after each one."""
    cells = [c for c in spec.cells() if c.key not in results]
    total = len(results) + len(cells)
    write_sweep(path, spec, results, total)
    if progress:
        progress(len(results), total)

    def done(r: CellResult) -> None:
        results[r.key] = r
        write_sweep(path, spec, results, total)
        if progress:
            progress(len(results), total)

    try:
        if executor == "dask":
            if not scheduler:
                raise ConfigError("--scheduler", "", "give the Dask scheduler's address")
            _dask(cells, scheduler, done)
        else:
            _local(cells, jobs, done)
    except KeyboardInterrupt:
        raise SweepInterrupted(f"{len(results)} of {total} cells done") from None
    return results
