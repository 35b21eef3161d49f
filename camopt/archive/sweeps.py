"""Sweep archives: the spec, every finished cell and a summary per grid point."""

from __future__ import annotations

from dataclasses import asdict
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

from camopt.archive.files import atomic_write, open_archive, versions
from camopt.archive.runs import check_schema, damaged
from camopt.archive.tables import write_table
from camopt.errors import ArchiveError
from camopt.sweep.spec import CellResult, SweepSpec, summary

SCHEMA_VERSION = 1


def write_sweep(path: Path, spec: SweepSpec, results: dict[tuple[int, int], CellResult],
                total: int, replace: bool = True) -> None:
    """Rewrite the sweep archive atomically with every finished cell (``replace=False``:
    never replace an existing file, for a new sweep's first write)."""

    def write(f: h5py.File) -> None:
        f.attrs.update({
            **versions(), "schema_version": SCHEMA_VERSION, "archive_kind": "sweep",
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
        write_table(f.create_group("summary"), summary(spec, results.values()))

    atomic_write(path, write, replace=replace)


def load_sweep(path: str | Path) -> tuple[SweepSpec, dict[tuple[int, int], CellResult]]:
    """A sweep archive's spec and finished cells."""
    with open_archive(path) as f:
        if f.attrs.get("archive_kind") != "sweep":
            raise ArchiveError(f"{path}: file: a run archive, not a sweep archive")
        with damaged(path):
            check_schema(f, SCHEMA_VERSION, SWEEP_SCHEMA)
            spec = SweepSpec.from_json(str(f.attrs["spec"]), str(f.attrs["config_toml"]))
            _check_spec(spec)
            n_points, (start, stop) = len(spec.points()), spec.seeds
            results = {}
            fields = [k for k in CellResult.__dataclass_fields__ if k not in ("x", "history")]
            for name, g in f["cells"].items():
                a = {k: (v.item() if isinstance(v, np.generic) else v)
                     for k, v in g.attrs.items()}
                if sorted(a) != sorted(fields) or "x" not in g or "history" not in g:
                    raise ArchiveError(f"/cells/{name}: attributes {sorted(a)}, expected "
                                       f"{sorted(fields)} with x and history")
                r = CellResult(**a, x=g["x"][()].tolist(),
                               history={k: v[()].tolist() for k, v in g["history"].items()})
                if not (isinstance(r.point, int) and isinstance(r.seed, int)
                        and 0 <= r.point < n_points and start <= r.seed < stop):
                    raise ArchiveError(f"/cells/{name}: grid point or seed outside the sweep")
                results[r.key] = r
    return spec, results


SWEEP_SCHEMA = (("/", ("spec", "config_toml", "cells_total", "cells_done")), ("/cells", ()))


def _check_spec(spec: SweepSpec) -> None:
    """The stored spec has the shape ``SweepSpec`` needs."""
    seeds, grid = spec.seeds, spec.grid
    ok = (isinstance(spec.data, dict) and isinstance(spec.data.get("run"), dict)
          and isinstance(spec.data["run"].get("seed"), int)
          and len(seeds) == 2 and all(isinstance(s, int) for s in seeds) and seeds[0] < seeds[1]
          and isinstance(grid, list)
          and all(len(g) == 2 and isinstance(g[0], str) and isinstance(g[1], list) and g[1]
                  for g in grid))
    if not ok:
        raise ArchiveError("spec: not a sweep specification (data, grid, seeds)")
