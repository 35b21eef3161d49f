"""Sweep archives: the spec, every finished cell and a summary per grid point.

Layout (schema 2), one HDF5 file:

- root attributes: library versions, ``schema_version`` 2, ``archive_kind`` "sweep",
  ``config_toml`` (the case file's text), ``config_path``, ``spec`` (JSON: the validated
  config data, the grid, the seed range), ``seed_entropy``, ``cells_total``,
  ``cells_done``, ``complete``, ``created``;
- ``/cells``: one row per finished cell (a :class:`camopt.core.record.Repeat`), columns
  ``point``, ``seed`` (the seed index k: the record's ``index``), ``objective`` (its
  ``fun``), ``feasible``, ``success``, ``nfev``, ``nit``, ``wall_s``, ``converged_nit``,
  ``nfev_to_target`` (1-D datasets), the best designs ``x`` as ragged rows
  (``x/values`` concatenated, SI, and ``x/offsets``, n_cells + 1), and each convergence
  history ``history/<name>/values`` with ``history/<name>/offsets`` likewise;
- ``/summary``: one row per grid point (success rate, statistics, evaluations to target).

Cost per cell is O(1): a finished cell is appended to a journal beside the archive,
``.<archive name>.cells`` (one JSON line per cell, written with one ``os.write``), and
the HDF5 snapshot is rewritten (atomically, :func:`camopt.archive.files.atomic_write`)
only when the number of cells has doubled since the last snapshot (and is at least
``SNAPSHOT_MIN_CELLS``), after ``SNAPSHOT_SECONDS``, and at the end, when the journal is
removed. Readers take the
snapshot and every complete journal line (a line cut short by a kill is ignored), so
they never see a partial cell, and ``--resume`` after SIGKILL loses only running cells.
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

import h5py
import numpy as np

from camopt.archive.files import atomic_write, open_archive, read_regular, versions
from camopt.archive.runs import check_schema, damaged
from camopt.archive.tables import write_table
from camopt.config.sweep_spec import SweepSpec
from camopt.core.record import Repeat, seed_id
from camopt.core.stats import sweep_summary
from camopt.errors import ArchiveError

if TYPE_CHECKING:  # annotations only: no config models at import
    from camopt.config.raw import RawDoc

SCHEMA_VERSION = 2
SNAPSHOT_SECONDS = 30.0
# no snapshot before this many cells: a journal this short is read at once, and each
# snapshot costs ~25 ms (a whole HDF5 file written and synced), which at 1, 2, 4, ... 32
# cells was 10-25 % of a small sweep's time, spent in the parent its workers wait on
SNAPSHOT_MIN_CELLS = 64
# a cell's stored names (journal keys, /cells columns) and the Repeat fields they hold
_ATTRS = {"point": "point", "seed": "index", "objective": "fun", "feasible": "feasible",
          "success": "success", "nfev": "nfev", "nit": "nit", "wall_s": "wall_s",
          "converged_nit": "converged_nit", "nfev_to_target": "nfev_to_target"}
_SCALARS = tuple(_ATTRS)
_FIELDS = (*_SCALARS, "x", "history")
_INTS = ("point", "seed", "nfev", "nit", "converged_nit", "nfev_to_target")
_BOOLS = ("feasible", "success")
SWEEP_KEY = "sweep"  # each journal line's sweep id (SweepSpec.sweep_id)


def journal_path(path: Path) -> Path:
    """The journal of cells finished since the last snapshot, beside the archive."""
    path = Path(path)
    return path.with_name(f".{path.name}.cells")


def _ragged(group: h5py.Group, name: str, rows: list[list[Any]]) -> None:
    """Rows of different lengths as concatenated ``values`` and ``offsets`` (n + 1)."""
    g = group.create_group(name)
    lengths = [len(r) for r in rows]
    flat = [v for r in rows for v in r]
    whole = all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in flat)
    g.create_dataset("values", data=np.array(flat, dtype=np.int64 if whole and flat
                                             else float))
    g.create_dataset("offsets", data=np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64))


def _unragged(g: h5py.Group, n: int) -> list[list[Any]]:
    offsets = g["offsets"][()]
    values = g["values"][()].tolist()
    if offsets.shape != (n + 1,) or offsets[0] != 0 or np.any(np.diff(offsets) < 0) \
            or offsets[-1] != len(values):
        raise ArchiveError(f"{g.name}: offsets do not index its values")
    return [values[offsets[i]:offsets[i + 1]] for i in range(n)]


def write_sweep(path: Path, spec: SweepSpec, results: dict[tuple[int, int], Repeat],
                total: int, replace: bool = True) -> None:
    """Write the sweep snapshot atomically with every finished cell (``replace=False``:
    never replace an existing file, for a new sweep's first write)."""
    cells = [results[k] for k in sorted(results)]

    def write(f: h5py.File) -> None:
        f.attrs.update({
            **versions(), "schema_version": SCHEMA_VERSION, "archive_kind": "sweep",
            "config_toml": spec.text, "config_path": spec.source, "spec": spec.to_json(),
            "seed_entropy": str(spec.entropy), "cells_total": total,
            "cells_done": len(results), "complete": len(results) == total,
            "created": datetime.now(timezone.utc).isoformat(),
        })
        g = f.create_group("cells")
        for name in _SCALARS:
            dtype = np.int64 if name in _INTS else bool if name in _BOOLS else float
            g.create_dataset(name, data=np.array([getattr(c, _ATTRS[name]) for c in cells],
                                                 dtype=dtype))
        # plain Python numbers (tolist): _ragged's type test is per value
        _ragged(g, "x", [np.asarray(c.x).tolist() for c in cells])
        hist = g.create_group("history")
        for key in sorted({k for c in cells for k in c.history}):
            _ragged(hist, key, [np.asarray(c.history.get(key, [])).tolist() for c in cells])
        write_table(f.create_group("summary"), sweep_summary(spec, results.values()))

    atomic_write(path, write, replace=replace)


class SweepWriter:
    """Stores a running sweep's finished cells: the journal line first (O(1) per cell), a
    snapshot now and then (amortised O(1) per cell), a final snapshot on :meth:`close`."""

    def __init__(self, path: Path, spec: SweepSpec,
                 results: dict[tuple[int, int], Repeat], total: int,
                 replace: bool = True) -> None:
        self.path, self.spec, self.results, self.total = Path(path), spec, results, total
        write_sweep(self.path, spec, results, total, replace=replace)
        journal = journal_path(self.path)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(journal)  # every cell it held is in the snapshot just written
        try:  # a new regular file (O_EXCL: never a FIFO or link planted meanwhile)
            self._fd: int | None = os.open(journal, os.O_WRONLY | os.O_CREAT | os.O_EXCL
                                           | os.O_APPEND | os.O_CLOEXEC | os.O_NOFOLLOW,
                                           0o644)
        except OSError as exc:
            raise ArchiveError(f"{self.path}: archive: cannot create its journal {journal} "
                               f"({exc.strerror}); finish with --resume") from None
        self._id = spec.sweep_id
        self._snapshot_cells = len(results)  # the cells the snapshot on disk holds
        self._snapshot_time = time.monotonic()

    def add(self, result: Repeat) -> None:
        """Store one finished cell; it counts as done only once its line is written."""
        assert self._fd is not None
        row = {SWEEP_KEY: self._id, **cell_row(result)}
        line = (json.dumps(row, separators=(",", ":")) + "\n").encode()
        try:
            view = memoryview(line)
            while view:
                view = view[os.write(self._fd, view):]
        except OSError as exc:
            raise ArchiveError(f"{self.path}: archive: cannot append a cell "
                               f"({exc.strerror}); finish with --resume") from None
        self.results[result.key] = result
        if (len(self.results) >= max(2 * self._snapshot_cells, SNAPSHOT_MIN_CELLS)
                or time.monotonic() - self._snapshot_time > SNAPSHOT_SECONDS):
            self.snapshot()

    def snapshot(self) -> None:
        """Rewrite the archive with every stored cell and empty the journal."""
        write_sweep(self.path, self.spec, self.results, self.total)
        assert self._fd is not None
        os.ftruncate(self._fd, 0)
        self._snapshot_cells = len(self.results)
        self._snapshot_time = time.monotonic()

    def close(self) -> None:
        """Final snapshot (unless the last one holds every stored cell: the journal is
        empty then); the journal is removed."""
        if self._fd is None:
            return
        if len(self.results) != self._snapshot_cells:
            self.snapshot()
        os.close(self._fd)
        self._fd = None
        with contextlib.suppress(FileNotFoundError):
            os.unlink(journal_path(self.path))


def read_journal(path: Path, spec: SweepSpec) -> list[Repeat]:
    """The complete lines of an archive's journal as cells (none without a journal).

    A last line without its newline was cut short by a kill and is ignored; a blank line
    (whitespace only: a hand edit, a disk that padded a block) holds no cell and is
    skipped. A damaged line elsewhere (a cut line another line was written after) is an
    ArchiveError naming the line and the remedy: delete it and ``--resume``, which runs
    its cell again (cells are reproducible from the seed, so nothing is lost)."""
    journal = journal_path(path)
    text = read_regular(journal, "journal")  # a FIFO there is refused, never waited on
    if text is None:
        return []
    cells, sweep_id = [], spec.sweep_id
    for number, line in enumerate(text.split(b"\n")[:-1], 1):  # the rest is cut short
        where = f"journal {journal.name} line {number}"
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except ValueError as exc:
            raise ArchiveError(f"{where}: damaged ({exc}); delete that line from "
                               f"{journal} and run `camopt sweep --resume {path}` (its cell "
                               "is run again)") from None
        if not isinstance(row, dict) or row.pop(SWEEP_KEY, None) != sweep_id:
            raise ArchiveError(f"{where}: not a line of this sweep (its {SWEEP_KEY} is "
                               f"not {sweep_id}); remove the journal to drop it")
        cells.append(_cell(row, spec, where))
    return cells


class CellDoc(TypedDict):
    """A sweep cell as its journal line stores it (the stored names: ``seed`` is the
    repeat's index, ``objective`` its ``fun``; ``x`` SI; ``history`` per iteration)."""

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
    history: dict[str, list[float]]


def _plain(value: Any) -> Any:
    """A numpy scalar as the Python one (JSON)."""
    return value.item() if isinstance(value, np.generic) else value


def cell_row(r: Repeat) -> CellDoc:
    """A cell as its journal line stores it (plain JSON values, the stored names)."""
    return {"point": _plain(r.point), "seed": _plain(r.index), "objective": _plain(r.fun),
            "feasible": _plain(r.feasible), "success": _plain(r.success),
            "nfev": _plain(r.nfev), "nit": _plain(r.nit), "wall_s": _plain(r.wall_s),
            "converged_nit": _plain(r.converged_nit),
            "nfev_to_target": _plain(r.nfev_to_target),
            "x": np.asarray(r.x, dtype=float).tolist(),
            "history": {k: np.asarray(v).tolist() for k, v in r.history.items()}}


def _cell(a: RawDoc, spec: SweepSpec, where: str) -> Repeat:
    """A stored cell (journal line or /cells row) as the Repeat it was; its spawn key and
    seed identifier follow from the seed index (child k of SeedSequence(run.seed))."""
    expected = sorted(_FIELDS)
    if sorted(a) != expected:
        raise ArchiveError(f"{where}: cell fields {sorted(a)}, expected {expected}")
    wrong = [name for name in _FIELDS if not _TYPES[name](a[name])]
    if wrong:
        raise ArchiveError(f"{where}: {wrong[0]} = {str(a[wrong[0]])[:40]}: not a "
                           f"{_TYPE_NAMES[wrong[0]]}")
    n_points, (start, stop) = len(spec.points()), spec.seeds
    if not (0 <= a["point"] < n_points and start <= a["seed"] < stop):
        raise ArchiveError(f"{where}: grid point or seed outside the sweep")
    k = a["seed"]
    return Repeat(**{attr: a[name] for name, attr in _ATTRS.items()},
                  x=np.asarray(a["x"], dtype=float), spawn_key=(k,),
                  seed=seed_id(np.random.SeedSequence(spec.entropy, spawn_key=(k,))),
                  message="", violation=float("nan"),
                  history={key: np.asarray(v) for key, v in a["history"].items()})


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)  # JSON true is no grid point


def _is_real(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_reals(v: Any) -> bool:
    return isinstance(v, list) and all(_is_real(e) for e in v)


_TYPES = {**{name: _is_real for name in _SCALARS}, **{name: _is_int for name in _INTS},
          **{name: lambda v: isinstance(v, bool) for name in _BOOLS}, "x": _is_reals,
          "history": lambda v: isinstance(v, dict) and all(
              isinstance(k, str) and _is_reals(e) for k, e in v.items())}
_TYPE_NAMES = {**{name: "number" for name in _SCALARS}, **{name: "integer" for name in _INTS},
               **{name: "boolean" for name in _BOOLS}, "x": "list of numbers",
               "history": "table of number lists"}


def load_sweep(path: str | Path) -> tuple[SweepSpec, dict[tuple[int, int], Repeat]]:
    """A sweep archive's spec and finished cells (snapshot and journal)."""
    path = Path(path)
    with open_archive(path) as f:
        if f.attrs.get("archive_kind") != "sweep":
            raise ArchiveError(f"{path}: file: a run archive, not a sweep archive")
        with damaged(path):
            check_schema(f, SCHEMA_VERSION, SWEEP_SCHEMA)
            spec = SweepSpec.from_json(str(f.attrs["spec"]), str(f.attrs["config_toml"]))
            _check_spec(spec)
            g = f["cells"]
            columns = sorted(k for k in g if k not in ("x", "history"))
            if columns != sorted(_SCALARS):
                raise ArchiveError(f"/cells: columns {columns}, expected {sorted(_SCALARS)}")
            data = {k: g[k][()].tolist() for k in _SCALARS}
            n = len(data["point"])
            if any(len(v) != n for v in data.values()):
                raise ArchiveError("/cells: columns of different lengths")
            xs = _unragged(g["x"], n)
            hist = {k: _unragged(v, n) for k, v in g["history"].items()}
            results = {}
            for i in range(n):
                row = {k: data[k][i] for k in _SCALARS}
                row.update(x=xs[i], history={k: v[i] for k, v in hist.items() if v[i]})
                r = _cell(row, spec, f"/cells row {i}")
                results[r.key] = r
            for r in read_journal(path, spec):
                results[r.key] = r
    return spec, results


SWEEP_SCHEMA = (("/", ("spec", "config_toml", "cells_total", "cells_done")), ("/cells", ()),
                ("/cells/x", ()), ("/cells/history", ()))


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
