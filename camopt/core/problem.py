"""The Problem every case offers and the Evaluation it returns, vectorised over a population.

Decision vectors are SI. Each :class:`Variable` also carries the unit a person
reads (``s0_mm``) and the factor from SI to it, so archives and tables show
engineering units while the models stay SI.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from camopt.core.constraints import ACTIVE_TOL as ACTIVE_TOL
from camopt.core.constraints import FEASIBILITY_TOL as FEASIBILITY_TOL
from camopt.mechanics import Bools, Floats, Ints


@dataclass(frozen=True)
class Variable:
    """One design variable: SI bounds, display name with unit, and the SI-to-display factor
    (``display = SI * scale``); ``integer`` variables take whole values; ``symbol`` is the
    paper's name for it (``x9``)."""

    name: str
    lower: float
    upper: float
    scale: float = 1.0
    integer: bool = False
    symbol: str = ""


@dataclass(frozen=True)
class Evaluation:
    """Objective ``f`` (n_pop,), normalised constraints ``g`` (n_pop, n_constr), feasible iff
    all ``g <= 0``; ``extras`` holds per-candidate metrics (n_pop,) keyed by unit-carrying
    names (``tau_max_mpa``)."""

    f: Floats
    g: Floats
    extras: Mapping[str, Floats] = field(default_factory=dict)

    @property
    def violation(self) -> Floats:
        """Sum of constraint excesses over FEASIBILITY_TOL, (n_pop,); NaN counts as
        infinitely violated."""
        excess = np.asarray(self.g, dtype=float) - FEASIBILITY_TOL  # a new array
        excess[np.isnan(excess)] = np.inf
        return np.maximum(excess, 0.0, out=excess).sum(axis=1)

    @property
    def feasible(self) -> Bools:
        """(n_pop,) bool: no constraint violated and a finite objective: ``violation == 0``
        (every ``g <= FEASIBILITY_TOL``, NaN failing), read off a bool comparison rather
        than the violation's (n_pop, n_constr) float temporary (112 MB at 10^6 VCB
        samples, each time a tolerance analysis asks)."""
        return np.all(np.asarray(self.g) <= FEASIBILITY_TOL, axis=1) & np.isfinite(self.f)

    def take(self, index: Bools | Ints | int | slice) -> Evaluation:
        """The evaluation of a subset of candidates (keeps 2-D shapes); a slice gives views
        of these arrays, not copies (a tolerance analysis's 10^6 samples)."""
        idx = index if isinstance(index, slice) else np.atleast_1d(index)
        return Evaluation(self.f[idx], self.g[idx], {k: v[idx] for k, v in self.extras.items()})

    def where(self, mask: Bools, other: Evaluation) -> Evaluation:
        """Row-wise choice: this evaluation's rows where ``mask`` (n_pop,) is true, else
        ``other``'s (same population size, same extras)."""
        return Evaluation(
            f=np.where(mask, self.f, other.f),
            g=np.where(mask[:, None], self.g, other.g),
            extras={k: np.where(mask, v, other.extras[k]) for k, v in self.extras.items()},
        )

    @staticmethod
    def concat(evaluations: Sequence[Evaluation]) -> Evaluation:
        """The evaluations of several batches as one, in order (extras of the first)."""
        first = evaluations[0]
        return Evaluation(
            f=np.concatenate([e.f for e in evaluations]),
            g=np.concatenate([e.g for e in evaluations]),
            extras={k: np.concatenate([e.extras[k] for e in evaluations])
                    for k in first.extras},
        )


@dataclass(frozen=True)
class ObjectiveFloor:
    """The least objective any feasible design can reach in principle (``value``, in the
    objective's unit) and why, in words (``reason``): a bound from the model itself (an
    absolute value, an energy balance), not from a search."""

    value: float
    reason: str


def deb_best(f: ArrayLike, violation: ArrayLike) -> int:
    """Index of the best candidate by Deb's rules: least violation, then lowest objective
    (the one ranking camopt uses for populations, starts and repeats alike)."""
    return int(np.lexsort((np.asarray(f, dtype=float), np.asarray(violation, dtype=float)))[0])


class Problem:
    """Base of every case's problem: bounded variables, constraints, ``evaluate``.

    Optional capabilities a solver may need are Protocols in
    :mod:`camopt.core.capabilities` that a case's Problem subclasses to declare them.
    The single-design outputs below have generic defaults that a case refines.
    """

    variables: tuple[Variable, ...] = ()
    constraint_names: tuple[str, ...] = ()
    objective_name: str = "objective"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables)

    @property
    def n_var(self) -> int:
        return len(self.variables)

    @property
    def n_constr(self) -> int:
        return len(self.constraint_names)

    @property
    def lower(self) -> Floats:
        """SI lower bounds, (n_var,)."""
        return np.array([v.lower for v in self.variables], dtype=float)

    @property
    def upper(self) -> Floats:
        """SI upper bounds, (n_var,)."""
        return np.array([v.upper for v in self.variables], dtype=float)

    @property
    def integer(self) -> Bools:
        return np.array([v.integer for v in self.variables], dtype=bool)

    @property
    def scale(self) -> Floats:
        return np.array([v.scale for v in self.variables], dtype=float)

    def evaluate(self, X: Floats) -> Evaluation:  # pragma: no cover - abstract
        """Objective, constraints and search metrics of designs ``X`` (n_pop, n_var), SI."""
        raise NotImplementedError

    # ---- the unit cube ----------------------------------------------------------------
    def _box(self) -> tuple[Floats, Floats]:
        """(lower, upper - lower), built once per tuple of variables (local solvers map
        every single design through the unit cube: the arrays are not rebuilt per call)."""
        cache = self.__dict__.get("_box_cache")
        if cache is None or cache[0] is not self.variables:
            lower, upper = self.lower, self.upper
            cache = (self.variables, lower, upper - lower)
            self.__dict__["_box_cache"] = cache
        return cache[1], cache[2]

    def to_unit(self, X: Floats) -> Floats:
        """SI designs to bounds-normalised coordinates (0 at the lower, 1 at the upper bound)."""
        lower, span = self._box()
        return (np.asarray(X, dtype=float) - lower) / span

    def from_unit(self, U: Floats) -> Floats:
        """Bounds-normalised coordinates back to SI designs: ``lower + U (upper - lower)``."""
        lower, span = self._box()
        return lower + np.asarray(U, dtype=float) * span

    def sample(self, rng: np.random.Generator, n: int) -> Floats:
        """``n`` designs drawn uniformly within the bounds, (n, n_var), SI (integers not
        rounded: solvers snap)."""
        return self.from_unit(rng.random((n, self.n_var)))

    # ---- single-design output (generic defaults) --------------------------------------
    def describe(self, X: Floats) -> Evaluation:
        """As :meth:`evaluate`, plus descriptive metrics for tables (not the hot path)."""
        return self.evaluate(X)

    def metrics(self, x: Floats) -> Mapping[str, object]:
        """Headline metrics of one design ``x`` (n_var,) for the archive's ``/best``."""
        ev = self.describe(np.asarray(x, dtype=float)[None, :])
        return {k: float(v[0]) for k, v in ev.extras.items()}

    def analysis(self, x: Floats) -> dict[str, Floats]:
        """Curves of one design for the archive's ``/analysis`` (none by default)."""
        return {}

    def findings(self, x: Floats) -> Mapping[str, object]:
        """What the run found beyond the best design's metrics, as JSON-able data under
        top-level names of ``show --format json`` (an identification's model forms and
        identifiability); none by default."""
        return {}

    def objective_floor(self) -> ObjectiveFloor | None:
        """What no feasible design can go below (``camopt validate`` warns of a ``run.target``
        under it), or None when the case cannot say."""
        return None

    def initial_x(self) -> Floats | None:
        """The case's own starting design (SI) for local solvers, or None."""
        return None

    # ---- display units ----------------------------------------------------------------
    def to_display(self, x: Floats) -> dict[str, float]:
        """A single SI design as ``{name_with_unit: value}``."""
        return {v.name: float(xi * v.scale) for v, xi in zip(self.variables, x)}

    def from_display(self, values: Mapping[str, float]) -> Floats:
        """Build an SI design from ``{name_with_unit: value}``; every variable must be given."""
        missing = [v.name for v in self.variables if v.name not in values]
        unknown = sorted(set(values) - set(self.names))
        if missing or unknown:
            parts = []
            if missing:
                parts.append(f"missing {', '.join(missing)}")
            if unknown:
                parts.append(f"unknown {', '.join(unknown)}")
            raise ValueError(f"{'; '.join(parts)} (variables: {', '.join(self.names)})")
        return np.array([values[v.name] / v.scale for v in self.variables], dtype=float)

    def active(self, g_row: Floats) -> list[str]:
        """Names of the constraints at their bound (within ACTIVE_TOL) for one candidate."""
        return [n for n, gi in zip(self.constraint_names, g_row) if abs(gi) <= ACTIVE_TOL]

    def violated(self, g_row: Floats) -> list[str]:
        """Names of the constraints a candidate violates (NaN counts as violated)."""
        return [n for n, gi in zip(self.constraint_names, g_row) if not gi <= FEASIBILITY_TOL]
