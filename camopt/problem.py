"""The Problem every case offers and the Evaluation it returns, vectorised over a population.

Decision vectors are SI. Each :class:`Variable` also carries the unit a person
reads (``s0_mm``) and the factor from SI to it, so archives and tables show
engineering units while the models stay SI.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

ACTIVE_TOL = 1e-4
"""A normalised constraint g with ``|g| <= ACTIVE_TOL`` counts as active (at its bound):
0.01 % of the bound, loose enough for gradient solvers that stop a margin inside."""
FEASIBILITY_TOL = 1e-9
"""Round-off allowance: a normalised constraint counts as violated only above this."""


@dataclass(frozen=True)
class Variable:
    """One design variable: SI bounds, display name with unit, and the SI-to-display factor."""

    name: str
    lower: float
    upper: float
    scale: float = 1.0
    integer: bool = False
    symbol: str = ""


@dataclass(frozen=True)
class Evaluation:
    """Objective ``f`` (n_pop,), normalised constraints ``g`` (n_pop, n_constr), feasible iff
    all ``g <= 0``; ``extras`` holds per-candidate metrics keyed by unit-carrying names."""

    f: NDArray
    g: NDArray
    extras: Mapping[str, NDArray] = field(default_factory=dict)

    @property
    def violation(self) -> NDArray:
        """Sum of constraint excesses over FEASIBILITY_TOL; NaN counts as infinitely violated."""
        g = np.where(np.isnan(self.g), np.inf, self.g)
        return np.clip(g - FEASIBILITY_TOL, 0.0, None).sum(axis=1)

    @property
    def feasible(self) -> NDArray:
        return (self.violation == 0.0) & np.isfinite(self.f)

    def take(self, index: NDArray | int) -> Evaluation:
        """The evaluation of a subset of candidates (keeps 2-D shapes)."""
        idx = np.atleast_1d(index)
        return Evaluation(self.f[idx], self.g[idx], {k: v[idx] for k, v in self.extras.items()})


class Problem:
    """Base of every case's problem: bounded variables, constraints, ``evaluate``.

    Optional capabilities a solver may look for: ``family()`` (enumeration),
    ``repair(X, rng, progress)`` (PSO corrections), ``residuals(X)`` (Newton),
    ``metrics(x)`` and ``analysis(x)`` (detailed single-design output for archives).
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
    def lower(self) -> NDArray:
        return np.array([v.lower for v in self.variables], dtype=float)

    @property
    def upper(self) -> NDArray:
        return np.array([v.upper for v in self.variables], dtype=float)

    @property
    def integer(self) -> NDArray:
        return np.array([v.integer for v in self.variables], dtype=bool)

    @property
    def scale(self) -> NDArray:
        return np.array([v.scale for v in self.variables], dtype=float)

    def evaluate(self, X: NDArray) -> Evaluation:  # pragma: no cover - abstract
        raise NotImplementedError

    def to_display(self, x: NDArray) -> dict[str, float]:
        """A single SI design as ``{name_with_unit: value}``."""
        return {v.name: float(xi * v.scale) for v, xi in zip(self.variables, x)}

    def from_display(self, values: Mapping[str, float]) -> NDArray:
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

    def active(self, g_row: NDArray) -> list[str]:
        """Names of the constraints at their bound (within ACTIVE_TOL) for one candidate."""
        return [n for n, gi in zip(self.constraint_names, g_row) if abs(gi) <= ACTIVE_TOL]
