"""Optional capabilities a case's Problem declares and a solver may require.

A case declares a capability by subclassing the Protocol beside :class:`~camopt.problem.
Problem` (``class EmbCamProblem(Problem, Repairable)``); a solver lists the Protocols it
needs in ``requires``. The check is made on the Problem *class* when a case file is
validated (``issubclass``), so a solver that cannot run a case is bad input before any
work, never a silent fallback in the middle of a run (nevergrad's class qualifiers).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray


@runtime_checkable
class HasFamily(Protocol):
    """A discrete one-degree-of-freedom family of designs left by monotonicity analysis
    (Clauss 1982, Eq 86); the ``enumeration`` solver walks it."""

    def family(self) -> NDArray:
        """Every member of the family, (n_members, n_var), SI."""
        ...


@runtime_checkable
class Repairable(Protocol):
    """Case-specific corrections of a swarm (Yan 2023's "improved PSO", Sec 3.3.4)."""

    def repair(self, X: NDArray, rng: np.random.Generator,
               probability: Mapping[str, float]) -> NDArray:
        """Corrected copies of designs ``X`` (n, n_var); correction ``k`` is applied to a
        design with ``probability[k]``."""
        ...

    def repair_schedule(self) -> Mapping[str, tuple[float, float]]:
        """Each correction's trigger probability at the first and the last iteration."""
        ...


@runtime_checkable
class HasResiduals(Protocol):
    """Equations whose roots are the designs (precision points, Ahn et al. Sec 3)."""

    def residuals(self, X: NDArray) -> NDArray:
        """Residuals of designs ``X`` (n, n_var), shape (n, n_equations), dimensionless."""
        ...


CAPABILITIES = {"family": HasFamily, "repair": Repairable, "residuals": HasResiduals}
"""Capability names as a solver's error messages and ``camopt solvers`` spell them."""


def capability_name(protocol: type) -> str:
    """The short name of a capability Protocol (``Repairable`` -> ``repair``)."""
    return next((k for k, v in CAPABILITIES.items() if v is protocol), protocol.__name__)
