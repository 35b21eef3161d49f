"""Run archives: one HDF5 file per run, written atomically, read back as a RunView.

Layout (schema 2, documented dataset by dataset in ``docs/archive.md``): root attributes
(versions, exact TOML, config as run, seed); ``/repeats/rNNN`` per repeat with growable
``history/*`` datasets; ``/best`` with ``metrics``; ``/analysis/<curve>``;
``/table/<column>``; ``/summary/<column>``. Design vectors (``x``) are stored in the units
their variable names say (``kc1_n_per_mm`` in N/mm); schema 1 stored them in SI with the
factor in ``variable_scale`` and is still read.

tomli_w, pydantic, the case and solver registries are imported where used: ``camopt show``
reads an archive without the config models.
"""

from __future__ import annotations

import contextlib
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import h5py
import numpy as np

from camopt.archive.files import atomic_write, claim, open_archive, passing_interrupt, versions
from camopt.archive.tables import read_table, write_table
from camopt.core.constraints import ACTIVE_TOL, FEASIBILITY_TOL
from camopt.core.record import ExpectedYield, Repeat, RunRecord, nfev_to_target
from camopt.core.runview import BestView, RunView
from camopt.core.stats import succeeded
from camopt.errors import ArchiveError, CamoptError
from camopt.mechanics import Floats

if TYPE_CHECKING:  # annotations only: no config models at import
    from camopt.config.raw import RawDoc

SCHEMA_VERSION = 2
READABLE_SCHEMAS = (1, 2)
NOTE_CHARS = 2000
"""A repeat's note or message is cut to this many characters when read: an archive handed
over may carry a 60 MB note, which ``show`` would otherwise spend minutes and gigabytes
laying out (the archive keeps it whole: ``h5dump`` shows it)."""
MAX_NOTES = 20
"""At most this many notes per repeat are read (the rest counted in a last note)."""
MAX_NOTES_CHARS = 1 << 20
"""A repeat's notes attribute longer than this is not parsed at all (one note says so)."""


def bounded_text(text: str) -> str:
    """``text`` cut to :data:`NOTE_CHARS` characters, saying how much was left out."""
    if len(text) <= NOTE_CHARS:
        return text
    return f"{text[:NOTE_CHARS]}... ({len(text) - NOTE_CHARS} more characters in the archive)"


def _bounded_notes(text: object, where: str) -> tuple[str, ...]:
    """A repeat's notes (a JSON list of strings), bounded: see :data:`NOTE_CHARS`."""
    text = str(text)
    if len(text) > MAX_NOTES_CHARS:
        return (f"({len(text)} characters of notes not read: over camopt's "
                f"{MAX_NOTES_CHARS}-character limit; h5dump shows them)",)
    notes = _json_list(text, where)
    kept = [bounded_text(str(n)) for n in notes[:MAX_NOTES]]
    if len(notes) > MAX_NOTES:
        kept.append(f"... {len(notes) - MAX_NOTES} more notes in the archive")
    return tuple(kept)


def _write(f: h5py.File, rec: RunRecord) -> None:
    cfg = rec.config
    attrs = {
        **versions(), "schema_version": SCHEMA_VERSION, "config_toml": cfg.text,
        "config_path": cfg.path, "overrides": json.dumps(list(cfg.overrides)),
        "config_effective": json.dumps(cfg.effective()), "config_as_run": as_run_toml(cfg),
        "case_kind": cfg.case.kind,
        "solver": cfg.solver.name, "run_name": cfg.run.name, "seed_entropy": str(rec.seed),
        "created": datetime.now(timezone.utc).isoformat(),
        "variables": json.dumps(list(rec.names)),
        "variable_scale": rec.scale, "constraints": json.dumps(list(rec.constraint_names)),
        "objective_name": rec.objective_name, "x_units": "display",
        "interrupted": rec.interrupted, "repeats_done": len(rec.repeats),
        **({"robust_check": json.dumps(rec.robust_check)} if rec.robust_check else {}),
        **({"findings": json.dumps(rec.findings)} if rec.findings else {}),
        **({"expected_yield": json.dumps(rec.expected_yield)} if rec.expected_yield else {}),
    }
    scale = rec.scale  # x in the units the variable names say
    f.attrs.update(attrs)
    reps = f.create_group("repeats")
    for r in rec.repeats:
        grp = reps.create_group(f"r{r.index:03d}")
        grp.attrs.update({"spawn_key": json.dumps(list(r.spawn_key)), "seed": r.seed,
                          "objective": r.fun, "feasible": r.feasible, "success": r.success,
                          "violation": r.violation,
                          "nfev": r.nfev, "nit": r.nit, "wall_s": r.wall_s, "message": r.message,
                          "converged_nit": r.converged_nit,
                          "notes": json.dumps(list(r.notes))})
        grp.create_dataset("x", data=np.asarray(r.x, dtype=float) * scale)
        grp.create_dataset("g", data=r.g)
        hist = grp.create_group("history")
        for key, values in r.history.items():
            hist.create_dataset(key, data=values, maxshape=(None,), chunks=True)
    best = f.create_group("best")
    best.attrs.update({"objective": rec.best.fun, "feasible": rec.best.feasible,
                       "repeat": rec.best.index})
    best.create_dataset("x", data=np.asarray(rec.best.x, dtype=float) * scale)
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


def as_run_toml(cfg: Any) -> str:
    """The config as run (overrides, ``--seed`` and ``--repeats`` applied) as TOML text that
    ``camopt run`` accepts; unset (None) values are left out, as TOML has no null."""
    import tomli_w

    def drop_none(value: Any) -> Any:
        if isinstance(value, dict):
            return {k: drop_none(v) for k, v in value.items() if v is not None}
        if isinstance(value, list):
            return [drop_none(v) for v in value]
        return value

    return tomli_w.dumps(drop_none(cfg.effective()))


def write_run(rec: RunRecord, path: str | Path, force: bool = False) -> Path:
    """Write ``rec`` to a temporary file beside ``path`` and move it into place when
    complete, holding the archive's lock (``files.claim``); without ``force`` an existing
    file is never replaced."""
    path = Path(path)
    with claim(path, force):
        return atomic_write(path, lambda f: _write(f, rec), replace=force)


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def load_run(path: str | Path) -> RunView:
    """A run archive as a :class:`RunView`; a sweep, a foreign file or a damaged archive is
    an ArchiveError (``<file>: archive: <what is wrong>``)."""
    with open_archive(path) as f:
        if f.attrs.get("archive_kind", "run") != "run":
            raise ArchiveError(f"{path}: file: a {f.attrs['archive_kind']} archive, not a "
                               "run archive")
        with damaged(path):
            check_schema(f, READABLE_SCHEMAS, RUN_SCHEMA)
            view = _load(f, path)
            check_variables(view)
        return view


def check_variables(view: RunView) -> None:
    """The stored variable names must be those the case's problem has for the stored
    config (a renamed or foreign ``variables`` attribute would otherwise show values under
    wrong names and make ``tolerance`` fail on a missing one). The stored ``[case]`` table
    is the config as validated when the run was written: names the case gives for it as
    stored (:meth:`~camopt.cases.registry.CaseSpec.stored_names`) that are the archive's
    are accepted without validating it again (no config model, no solver imported:
    ``show``'s start-up); anything else is decided on the config validated. A config this
    camopt no longer accepts (an archive of another version) cannot be rebuilt, so is not
    compared: it is shown as stored, and ``tolerance``, which must rebuild it, refuses it
    with the config's own error (docs/reliability.md)."""
    from camopt.cases import get_case

    try:
        spec = get_case(view.kind)
    except CamoptError:  # a kind this camopt does not know: shown as stored
        return
    if spec.stored_names(view.case) == tuple(view.variables):
        return
    from pydantic import ValidationError

    from camopt.cases import case_configs
    from camopt.config import validate_data
    from camopt.solvers.registry import solver_options

    try:  # engine.driver.validate's check, without importing the engine (start-up time)
        config = validate_data({"case": view.case, "solver": view.solver, "run": view.run},
                               solver_options(), case_configs(), view.path)
        with np.errstate(all="ignore"):  # a non-assembling design is the run's business
            names = spec.names_of(config.case)
    except (CamoptError, ValidationError):
        return
    if names != tuple(view.variables):
        raise ArchiveError(f"variables {', '.join(view.variables)} do not match case "
                           f"'{view.kind}' with its stored config ({', '.join(names)})")


# what load_run reads: (HDF5 path, attribute names)
RUN_SCHEMA = (
    ("/", ("config_toml", "config_effective", "case_kind", "variables", "variable_scale",
           "constraints", "objective_name", "created", "seed_entropy")),
    ("/repeats", ()),
    ("/best", ("objective", "feasible", "repeat")),
    ("/best/x", ()), ("/best/g", ()), ("/best/metrics", ()), ("/analysis", ()),
    ("/table", ("columns",)),
)
REPEAT_ATTRS = ("spawn_key", "seed", "objective", "feasible", "violation", "nfev", "nit",
                "wall_s", "message", "converged_nit", "notes")


def check_schema(f: h5py.File, version: int | tuple[int, ...],
                 schema: tuple[tuple[str, tuple[str, ...]], ...]) -> None:
    """Raise ArchiveError naming the first object or attribute ``schema`` lists that ``f``
    lacks, or a schema version this camopt cannot read (``version``: one or several)."""
    found = f.attrs["schema_version"]
    versions_ok = (version,) if isinstance(version, int) else version
    if not isinstance(found, (int, np.integer)) or int(found) not in versions_ok:
        said = " or ".join(str(v) for v in versions_ok)
        raise ArchiveError(f"schema_version {found!r}; this camopt reads version {said}")
    for where, attrs in schema:
        if where not in f:
            raise ArchiveError(f"missing {where}")
        missing = [a for a in attrs if a not in f[where].attrs]
        if missing:
            raise ArchiveError(f"{where}: missing attribute {missing[0]!r}")


@contextlib.contextmanager
def damaged(path: str | Path) -> Iterator[None]:
    """Turn whatever reading a damaged archive raises (a missing object, bad JSON, a
    flipped byte h5py cannot decode, a wrong type) into ``<file>: archive: <what>``."""
    try:
        yield
    except Exception as exc:
        passing_interrupt(exc)
        if isinstance(exc, ArchiveError) and str(exc).startswith(f"{path}: "):
            raise
        what = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ArchiveError(f"{path}: archive: damaged or incomplete: {what}") from None


def _json_list(text: object, what: str) -> list[Any]:
    value = json.loads(str(text))
    if not isinstance(value, list):
        raise ArchiveError(f"{what}: expected a JSON list")
    return value


@dataclass(frozen=True)
class _Layout:
    """What every reader of a run archive needs from its root: the variables and
    constraints, the config as run, and the factors from stored ``x`` to display units
    (``to_display``) and to SI (``to_si``), both (n_var,)."""

    names: tuple[str, ...]
    constraints: tuple[str, ...]
    config: RawDoc
    to_display: Floats
    to_si: Floats

    @property
    def target(self) -> float | None:
        return self.config["run"].get("target")


def _migrate(schema: int, variable_scale: Floats) -> tuple[Floats, Floats]:
    """The one place archives of older schemas are told apart: the factors from the stored
    ``x`` to display units and to SI. Schema 2 stores display units (SI * scale); schema 1
    stored SI. (Repeats of the oldest archives also lack ``success``:
    :func:`_success` derives it.)"""
    ones = np.ones_like(variable_scale)
    if schema >= 2:
        return ones, 1 / variable_scale
    return variable_scale, ones


def _success(attrs: Any, fun: float, feasible: bool, target: float | None) -> bool:
    """A repeat's ``success``: stored where the archive has it; else the same definition
    (:func:`camopt.core.stats.succeeded`) from what the archive holds."""
    if "success" in attrs:
        return bool(attrs["success"])
    return bool(succeeded([fun], [feasible], target)[0])


def _json_dict(text: object) -> RawDoc:
    """An optional JSON object attribute ({} when absent: older archives)."""
    if text is None:
        return {}
    value = json.loads(str(text))
    if not isinstance(value, dict):
        raise ArchiveError("expected_yield: expected a JSON object")
    return value


def _read_layout(f: h5py.File) -> _Layout:
    names = tuple(str(n) for n in _json_list(f.attrs["variables"], "variables"))
    constraints = tuple(str(c) for c in _json_list(f.attrs["constraints"], "constraints"))
    variable_scale = np.asarray(f.attrs["variable_scale"], dtype=float)
    if variable_scale.shape not in ((), (len(names),)):
        raise ArchiveError("variable_scale: one value per variable expected")
    config = json.loads(f.attrs["config_effective"])
    if not isinstance(config, dict) or not all(
            isinstance(config.get(k), dict) for k in ("case", "solver", "run")):
        raise ArchiveError("config_effective: expected case, solver and run tables")
    to_display, to_si = _migrate(int(f.attrs["schema_version"]), variable_scale)
    return _Layout(names, constraints, config, to_display, to_si)


def _read_repeat(grp: h5py.Group, key: str, layout: _Layout) -> Repeat:
    """Repeat ``/repeats/<key>`` (``x`` to SI, ``nfev_to_target`` from its history)."""
    a = grp.attrs
    missing = [k for k in REPEAT_ATTRS if k not in a]
    if missing or "x" not in grp or "history" not in grp:
        raise ArchiveError(f"/repeats/{key}: missing "
                           f"{missing[0] if missing else 'x or history'}")
    if grp["x"].shape != (len(layout.names),):
        raise ArchiveError(f"/repeats/{key}/x: {grp['x'].shape}, expected "
                           f"({len(layout.names)},)")
    history = {k: v[()] for k, v in grp["history"].items()}
    fun, feasible = float(a["objective"]), bool(a["feasible"])
    return Repeat(
        x=grp["x"][()] * layout.to_si, fun=fun,
        success=_success(a, fun, feasible, layout.target),
        message=bounded_text(str(a["message"])), nfev=int(a["nfev"]), nit=int(a["nit"]),
        index=int(key[1:]), spawn_key=tuple(json.loads(a["spawn_key"])),
        seed=int(a["seed"]), feasible=feasible, violation=float(a["violation"]),
        converged_nit=int(a["converged_nit"]),
        nfev_to_target=nfev_to_target(history, layout.target),
        wall_s=float(a["wall_s"]), history=history,
        g=grp["g"][()] if "g" in grp else np.zeros(0),
        notes=_bounded_notes(a["notes"], f"/repeats/{key}: notes"))


def _read_repeats(f: h5py.File, layout: _Layout) -> list[Repeat]:
    """Every repeat, in index order (``r999`` before ``r1000``)."""
    if len(f["repeats"]) == 0:
        raise ArchiveError("/repeats: no repeat")
    return [_read_repeat(f["repeats"][key], key, layout)
            for key in sorted(f["repeats"], key=lambda k: int(k[1:]))]


def _read_best(best: h5py.Group, layout: _Layout) -> BestView:
    g = best["g"][()]
    names, constraints = layout.names, layout.constraints
    if best["x"].shape != (len(names),) or g.shape != (len(constraints),):
        raise ArchiveError("/best: x or g does not match the variables and constraints")
    # a search only ever stores a design inside its finite bounds: a NaN or infinite best
    # (or a NaN objective) is damage, never a design to give a verdict on
    if not np.all(np.isfinite(best["x"][()])) or np.isnan(float(best.attrs["objective"])):
        raise ArchiveError("/best: the best design or its objective is not finite")
    return BestView(
        objective=float(best.attrs["objective"]),
        feasible=bool(best.attrs["feasible"]),
        x=dict(zip(names, (best["x"][()] * layout.to_display).tolist())),
        metrics=renamed_metrics({k: _plain(v) for k, v in best["metrics"].attrs.items()}),
        active=[c for c, gi in zip(constraints, g) if abs(gi) <= ACTIVE_TOL],
        violated=[c for c, gi in zip(constraints, g) if not gi <= FEASIBILITY_TOL],
        repeat=int(best.attrs["repeat"]))


OLD_NAMES = {"closing_time": "release_to_latch"}
"""Metrics renamed since: a VCB archive written before the analyser's vocabulary called
the release-to-latch time ``closing_time_ms`` (with ``_low``/``_high`` and a reference
prefix); ``closing_time_ms`` now means command to touch."""


def renamed_metrics(metrics: RawDoc) -> RawDoc:
    """An older archive's metrics under today's names (:data:`OLD_NAMES`), told apart by
    holding the old name without the new one; today's archives unchanged."""
    for old, new in OLD_NAMES.items():
        if any(new in k for k in metrics) or not any(f"{old}_" in k for k in metrics):
            continue
        metrics = {re.sub(rf"(^|_){old}_(low_|high_)?ms$", rf"\1{new}_\2ms", k): v
                   for k, v in metrics.items()}
    return metrics


def _load(f: h5py.File, path: str | Path) -> RunView:
    layout = _read_layout(f)
    repeats = _read_repeats(f, layout)
    config, attrs = layout.config, f.attrs
    return RunView(
        path=str(path), kind=str(attrs["case_kind"]),
        case={"kind": str(attrs["case_kind"]), **config["case"]},
        solver=config["solver"], run=config["run"],
        objective_name=str(attrs["objective_name"]), variables=layout.names,
        constraints=layout.constraints, best=_read_best(f["best"], layout),
        repeats=repeats, table=read_table(f["table"]),
        analysis={k: v[()] for k, v in f["analysis"].items()},
        config_toml=str(attrs["config_toml"]), created=str(attrs["created"]),
        camopt_version=str(attrs["camopt_version"]),
        seed_entropy=str(attrs["seed_entropy"]),
        interrupted=bool(attrs.get("interrupted", False)),
        repeats_done=len(repeats), config_as_run=str(attrs.get("config_as_run", "")),
        robust=config.get("robust") or {},
        robust_check=json.loads(attrs["robust_check"]) if "robust_check" in attrs else {},
        findings=json.loads(attrs["findings"]) if "findings" in attrs else {},
        expected_yield=cast(ExpectedYield, _json_dict(attrs.get("expected_yield"))),
        config_path=str(attrs.get("config_path", "")),
        versions={k: str(v) for k, v in attrs.items()
                  if k.endswith("_version") and k != "schema_version"},
    )
