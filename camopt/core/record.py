"""One solver repeat as typed data: a run's repeat, a sweep's cell and a loaded archive's
repeat are the same record, :class:`Repeat`. Pure data (numpy only).

The first six fields carry ``scipy.optimize.OptimizeResult``'s names and meaning (``x``,
``fun``, ``success``, ``message``, ``nfev``, ``nit``); the rest are camopt's own. The
archives keep their documented names on disk (``objective`` for ``fun``, a sweep cell's
``seed`` for ``index``: docs/archive.md), so archives of every schema still load.

:class:`RunRecord` is a whole run as the archive writes it: the repeats, the best one,
and the names, scales and constraint names of the design space, so that the archive reads
plain data and never a driver or a live Problem.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from camopt.core.documents import AdjustmentUse, RobustCheck, Row
from camopt.mechanics import Floats

if TYPE_CHECKING:  # annotations only: the record stays pure data (numpy only)
    from camopt.config import LoadedConfig
    from camopt.core.problem import Problem


RequirementYield = TypedDict("RequirementYield", {
    "name": str, "yield": float, "half_spread": "float | None"})
"""One requirement's share of the draws that meet it, and its quantity's half spread
(5 to 95 %; None for a flag)."""

class ExpectedYield(TypedDict, total=False):
    value: float | None
    low: float | None
    high: float | None
    samples: int
    seed: int
    vary: list[str]
    requirements: list[RequirementYield]
    adjustments: list[AdjustmentUse]
    command: str
    reason: str
    estimated: str
"""The best design's quick expected yield under the case's default tolerances
(:func:`camopt.engine.tolerance.expected_yield`): the share of ``samples`` draws meeting
every requirement with its Clopper-Pearson interval (``low``, ``high``), the draws'
``seed`` and tolerances (``vary``), each requirement's share, the factory's adjustments
where the case models them, and the ``command`` that repeats it; without tolerances,
``value`` None and the ``reason``; ``estimated`` where ``show`` made it for an older
archive."""


def _empty() -> NDArray[np.float64]:
    return np.zeros(0)


@dataclass(frozen=True, eq=False)
class Repeat:
    """One solver repeat: its result and its convergence history.

    ``success`` is camopt's one definition of a successful run
    (:func:`camopt.core.stats.succeeded`: a finite objective, feasible, at or below
    ``run.target`` when set) for a repeat whose solver stopped without failing. No stop
    reason of camopt's solvers is a failure (each is a budget, a convergence test or
    exhausted starts); a solver that fails says so by reporting its best infeasible (a
    multi-start solver without a converged start reports objective +inf), so such a
    repeat is never a success.

    Repeat ``index`` k drew every random number from child k of
    ``SeedSequence(run.seed)`` (spawn key ``(k,)``) in a run and in a sweep alike.
    Fields a source does not store load empty: a sweep archive stores no ``g``,
    ``violation`` (NaN), ``message`` or ``notes``; no archive stores a repeat's
    ``table`` (a run archive holds the best repeat's as the run's table)."""

    x: NDArray[np.float64]
    """(n_var,) the repeat's best design, SI."""
    fun: float
    """Its objective, in the unit of the problem's ``objective_name`` (+inf: none found)."""
    success: bool
    message: str
    """Why the solver stopped (:class:`camopt.solvers.StopReason`'s text)."""
    nfev: int
    nit: int
    index: int
    """k: the repeat's place in the run, a sweep cell's seed index."""
    spawn_key: tuple[int, ...]
    seed: int
    """A 63-bit integer drawn from the repeat's seed sequence (an identifier)."""
    feasible: bool
    violation: float
    """Total constraint excess of ``x`` (``Evaluation.violation``; 0 when feasible)."""
    converged_nit: int
    """First iteration (1-based) from which the best objective stays within 1e-6 of its
    final value (:func:`camopt.engine.driver.converged_iteration`)."""
    nfev_to_target: int
    """Evaluations until the best design was feasible and at or below ``run.target``
    (feasible without a target); -1: never."""
    wall_s: float
    history: dict[str, Floats] = field(default_factory=dict)
    """Per iteration (n_iter,): ``nfev``, ``best_objective``, ``best_violation``,
    ``mean_objective``."""
    g: NDArray[np.float64] = field(default_factory=_empty)
    """(n_constr,) normalised constraint values of ``x``, feasible where <= 0."""
    notes: tuple[str, ...] = ()
    table: list[Row] = field(default_factory=list)
    """The solver's rows (every start, every coil count, the Pareto set)."""
    nominal_x: NDArray[np.float64] | None = None
    """Robust runs: the best design seen whose nominal evaluation is feasible."""
    point: int = 0
    """A sweep cell's grid point (0 in a run)."""

    @property
    def key(self) -> tuple[int, int]:
        """A sweep cell's place: (grid point, seed index)."""
        return (self.point, self.index)


@dataclass
class RunRecord:
    """Everything a run archive holds: the config as run, every finished repeat, the best
    one with its metrics and analysis curves, and the design space in plain data.

    ``names`` (n_var,) are the variables' display names (unit in the name), ``scale``
    (n_var,) the SI-to-display factors (``display = SI * scale``), ``constraint_names``
    (n_constr,) name the columns of each repeat's ``g``; ``objective_name`` names ``fun``.
    ``problem`` is the live Problem the run used, for in-process callers (tests, benches);
    the archive never reads it."""

    config: LoadedConfig
    seed: int
    repeats: list[Repeat]
    best: Repeat
    metrics: dict[str, object]
    analysis: dict[str, Floats]
    names: tuple[str, ...]
    scale: NDArray[np.float64]
    constraint_names: tuple[str, ...]
    objective_name: str
    interrupted: bool = False
    """True when Ctrl-C (or SIGTERM) or a failure stopped the run: ``repeats`` holds the
    finished ones."""
    robust_check: RobustCheck | None = None
    """Robust runs: the final check of the best design (``robust``) and of the best design
    seen whose nominal evaluation is feasible (``nominal``), :func:`camopt.engine.robust.check`."""
    failure: str | None = None
    """What stopped the run when it was not a signal (a worker process died)."""
    problem: Problem | None = field(default=None, repr=False, compare=False)
    findings: dict[str, Any] = field(default_factory=dict)
    """:meth:`Problem.findings` of the best design (JSON-able): what the archive stores as
    ``findings`` and ``show`` reports under its own names."""
    expected_yield: ExpectedYield | None = None
    """The quick default-tolerance yield estimate of the best design
    (:func:`camopt.engine.tolerance.expected_yield`), set by ``camopt run`` before writing."""


def seed_id(seq: np.random.SeedSequence) -> int:
    """A repeat's ``seed``: a 63-bit integer drawn from its seed sequence (fits int64)."""
    return int(seq.generate_state(1, np.uint64)[0] >> np.uint64(1))


def nfev_to_target(history: dict[str, Floats], target: float | None) -> int:
    """Evaluations after the first iteration whose best design was feasible and, with a
    ``target``, at or below it, from a repeat's ``history``; -1: none was (or the history
    lacks ``nfev``, ``best_objective`` or ``best_violation``)."""
    if not {"nfev", "best_objective", "best_violation"} <= set(history):
        return -1
    ok = np.asarray(history["best_violation"]) == 0
    if target is not None:
        ok &= np.asarray(history["best_objective"]) <= target
    return int(history["nfev"][np.argmax(ok)]) if ok.any() else -1
