"""A run archive as typed data: what ``show``, ``compare``, plots, export and the cases'
figures read. Pure data (numpy only); :mod:`camopt.archive` builds it from HDF5."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from camopt.core.constraints import ACTIVE_TOL, FEASIBILITY_TOL
from camopt.core.documents import RobustCheck, Row
from camopt.core.record import ExpectedYield, Repeat, RunRecord
from camopt.mechanics import Floats

if TYPE_CHECKING:  # annotations only: no config models at import
    from camopt.config.raw import RawDoc


@dataclass(frozen=True)
class BestView:
    """The run's best design: variables in display units, metrics, and the constraints
    it meets with equality (``active``) or breaks (``violated``)."""

    objective: float
    feasible: bool
    x: dict[str, float]
    metrics: dict[str, Any]
    active: list[str]
    violated: list[str]
    repeat: int


@dataclass(frozen=True)
class RunView:
    """A loaded run archive.

    ``case``, ``solver`` and ``run`` are the config as run (``--set`` overrides, ``--seed``
    and ``--repeats`` included); ``analysis`` maps curve names (unit in the name) to 1-D
    arrays; ``table`` holds the solver's rows (e.g. every coil count, every start)."""

    path: str
    kind: str
    case: RawDoc
    solver: RawDoc
    run: RawDoc
    objective_name: str
    variables: tuple[str, ...]
    constraints: tuple[str, ...]
    best: BestView
    repeats: list[Repeat]
    """Every repeat stored, in index order (``x`` in SI, as the run had it)."""
    table: list[Row]
    analysis: dict[str, Floats] = field(repr=False, default_factory=dict)
    config_toml: str = ""
    created: str = ""
    camopt_version: str = ""
    seed_entropy: str = ""
    interrupted: bool = False
    """Ctrl-C stopped the run: ``repeats`` holds the finished ones (``repeats_done`` of
    ``run["repeats"]``)."""
    repeats_done: int = 0
    config_as_run: str = ""
    """The config as run as TOML (overrides applied; empty for schema-1 archives)."""
    versions: dict[str, str] = field(default_factory=dict)
    """Library versions the run was made with (``numpy_version``, ...)."""
    robust: RawDoc = field(default_factory=dict)
    """The ``[robust]`` table as run (empty: a nominal run)."""
    robust_check: RobustCheck = field(default_factory=lambda: RobustCheck())
    """Robust runs: the final check of the best design (``robust``) and of the best
    nominally feasible design seen (``nominal``) on fresh draws (docs/tolerance.md)."""
    findings: dict[str, Any] = field(default_factory=dict)
    """What the run found beyond the best design's metrics (``Problem.findings``: an
    identification's ``model_forms`` and ``identifiability``)."""
    config_path: str = ""
    """The case file the run read (as given on the command line)."""
    expected_yield: ExpectedYield = field(default_factory=lambda: ExpectedYield())
    """The quick default-tolerance yield estimate ``run`` stored
    (:func:`camopt.engine.tolerance.expected_yield`); {} in archives made before it."""

    @property
    def solver_name(self) -> str:
        return str(self.solver.get("name", ""))

    def histories(self, key: str = "best_objective") -> list[Floats]:
        """One history array per repeat (``best_objective``, ``nfev``, ...)."""
        return [np.asarray(r.history[key]) for r in self.repeats if key in r.history]


def design_values(run: RunView, values: Mapping[str, object] | None = None) -> dict[str, Any]:
    """A design's quantities by name for requirements: the best design's metrics,
    variables, objective and feasibility, or the reference design's ``values``."""
    if values is not None:
        return dict(values)
    best = run.best
    return {**best.metrics, **best.x, run.objective_name: best.objective,
            "feasible": float(best.feasible)}


def record_view(rec: RunRecord, path: str = "") -> RunView:
    """A run record as its archive will load (what the expected-yield estimate and the
    requirements read before the archive is written): variables in display units, the
    best design's metrics, its active and violated constraints."""
    cfg = rec.config
    effective = cfg.effective()
    g = np.asarray(rec.best.g, dtype=float)
    names = rec.constraint_names
    best = BestView(
        objective=float(rec.best.fun), feasible=bool(rec.best.feasible),
        x=dict(zip(rec.names, (np.asarray(rec.best.x) * rec.scale).tolist())),
        metrics=dict(rec.metrics),
        active=[c for c, gi in zip(names, g) if abs(gi) <= ACTIVE_TOL],
        violated=[c for c, gi in zip(names, g) if not gi <= FEASIBILITY_TOL],
        repeat=rec.best.index)
    return RunView(
        path=path or cfg.path, kind=cfg.case.kind,
        case={"kind": cfg.case.kind, **effective["case"]}, solver=effective["solver"],
        run=effective["run"], objective_name=rec.objective_name,
        variables=tuple(rec.names), constraints=tuple(names), best=best,
        repeats=list(rec.repeats), table=list(rec.best.table),
        robust=effective.get("robust") or {}, robust_check=rec.robust_check or {},
        config_path=str(cfg.path), expected_yield=rec.expected_yield or {})
