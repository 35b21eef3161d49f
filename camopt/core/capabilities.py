"""Optional capabilities a case's Problem declares and a solver may require.

A case declares a capability by subclassing the Protocol beside :class:`~camopt.core.problem.
Problem` (``class EmbCamProblem(Problem, Repairable)``); a solver lists the Protocols it
needs in ``requires``. The check is made on the Problem *class* when a case file is
validated (``issubclass``), so a solver that cannot run a case is bad input before any
work, never a silent fallback in the middle of a run (nevergrad's class qualifiers).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from camopt.core.documents import RobustCheck
from camopt.core.problem import Evaluation
from camopt.mechanics import Bools, Floats, Ints


@runtime_checkable
class HasFamily(Protocol):
    """A discrete one-degree-of-freedom family of designs left by monotonicity analysis
    (Clauss 1982, Eq 86); the ``enumeration`` solver walks it."""

    def family(self) -> Floats:
        """Every member of the family, (n_members, n_var), SI."""
        ...


@runtime_checkable
class Repairable(Protocol):
    """Case-specific corrections of a swarm (Yan 2023's "improved PSO", Sec 3.3.4)."""

    def repair(self, X: Floats, rng: np.random.Generator,
               probability: Mapping[str, float]) -> Floats:
        """Corrected copies of designs ``X`` (n, n_var); correction ``k`` is applied to a
        design with ``probability[k]``."""
        ...

    def repair_schedule(self) -> Mapping[str, tuple[float, float]]:
        """Each correction's trigger probability at the first and the last iteration."""
        ...


@runtime_checkable
class HasResiduals(Protocol):
    """Equations whose roots are the designs (precision points, Ahn et al. Sec 3)."""

    def residuals(self, X: Floats) -> Floats:
        """Residuals of designs ``X`` (n, n_var), shape (n, n_equations), dimensionless."""
        ...


@runtime_checkable
class VariesCase(Protocol):
    """Case fields the Problem can take per design instead of one value from its config
    (tolerance analysis of fixed parts: a link of the VCB's linkage). Cases without it
    still take tolerances on their design variables."""

    def case_fields(self) -> tuple[str, ...]:
        """The ``[case]`` fields that may vary per design (names as in the case file)."""
        ...

    def describe_with(self, X: Floats, fields: Mapping[str, Floats]) -> Evaluation:
        """As ``describe(X)``, with each named case field taking its own value per row:
        ``fields[name]`` (n,) in the field's unit (``l1_mm`` in mm)."""
        ...


@runtime_checkable
class HasVariants(Protocol):
    """Variants of the case's model that fit its data equally well (the VCB's kept model
    forms): robust design and ``camopt tolerance`` draw over them as over the tolerances,
    each draw judged under one variant, and report the yield over both and per variant
    (docs/tolerance.md, "Model forms in the draws"). A case with a single model offers
    none (an empty tuple)."""

    def variants(self) -> tuple[str, ...]:
        """The variants' names, in a fixed order (none: the case has one model)."""
        ...

    def describe_variants(self, X: Floats, fields: Mapping[str, Floats],
                          variant: Ints, detail: bool = True) -> Evaluation:
        """As ``describe_with(X, fields)`` (``fields`` may be empty), row ``i`` judged
        under variant ``variant[i]`` ((n,) int, an index into :meth:`variants`; -1: every
        variant at once, the case's own evaluation). ``detail=False``: the constraints,
        objective and the metrics ``evaluate`` gives, not the descriptive ones (robust
        design's draws read only the first two)."""
        ...


@runtime_checkable
class Stochastic(Protocol):
    """An evaluation on random draws renewed every generation (robust design,
    :mod:`camopt.engine.robust`): the candidates of one generation share one set of draws
    (common random numbers), so they are compared on the same parts.

    The driver asks for it (no solver requires it): ``reseed`` starts a repeat,
    ``new_generation`` renews the draws before every ask, ``select`` picks the repeat's
    result on fresh draws, and ``final_check`` checks the run's best design. A solver that
    keeps evaluations across generations may ask for it too: ``de_gr`` then evaluates its
    parents again on each generation's draws, so that a trial and its parent are compared
    on the same parts (docs/tolerance.md, "Parents on the same parts")."""

    notes: tuple[str, ...]
    """What the last ``select`` did beyond choosing, for the repeat's notes."""

    def reseed(self, seed: np.random.SeedSequence) -> None:
        """Start a repeat: its own draws from ``seed``, nothing carried over."""
        ...

    def new_generation(self) -> None:
        """Draw the next generation's perturbations, shared by every candidate."""
        ...

    def select(self, x: Floats, seed: np.random.SeedSequence
               ) -> tuple[Floats, Evaluation]:
        """The repeat's result from the solver's best ``x`` (n_var,), SI: a design and its
        evaluation (one row) judged on fresh draws from ``seed``."""
        ...

    def nominal_design(self) -> Floats | None:
        """The best design this repeat saw whose nominal evaluation is feasible, or None."""
        ...

    def draw_dependent(self, ev: Evaluation) -> Bools:
        """(n,) bool: the rows of an evaluation of this problem that depend on the draws.
        A screened candidate's do not (its columns are its nominal design's), so a solver
        that evaluates its parents again on new draws need not evaluate those."""
        ...

    def final_check(self, best: Floats, seen: Sequence[Floats], seed: int,
                    progress: Callable[[int, int], None] | None = None) -> RobustCheck:
        """The run's check of its best design and of the best of the repeats' ``seen``
        nominal designs, for the archive's ``robust_check`` (plain JSON data); ``progress``
        is told the rows done and in all as the check's chunks finish."""
        ...


@runtime_checkable
class Fittable(Protocol):
    """A model fitted to measured data by :mod:`camopt.core.fitting` (a case's calibration
    on measured curves): fitted coordinates q (n,), each a parameter or, where ``log``, the
    log of a positive one, searched inside [``lower``, ``upper``]; the model gives the
    residuals of rows of coordinates in units of the data's noise and its RMS misfit.
    Another case fits through the same seam by offering these."""

    lower: Floats
    """(n,) lower search bounds of the fitted coordinates."""
    upper: Floats
    """(n,) upper search bounds."""
    log: Bools
    """(n,) bool: the coordinate is the log of a positive parameter."""
    accuracy: Floats
    """(n,) how close the data must pin a parameter for it to count as identified:
    relative for a log coordinate (:data:`camopt.core.fitting.IDENTIFIED_WITHIN`), in
    the coordinate's unit otherwise."""
    bound_room: Floats
    """(n,) how near its search bound a coordinate that is not a log is "at" it (its
    unit); a log coordinate's room is the fitting module's rule."""

    def residuals(self, Q: Floats) -> Floats:
        """Normalised residuals (k, N), (model - measured) / noise, of the rows of ``Q``
        (k, n), one vectorised evaluation."""
        ...

    def rms(self, q: Floats) -> float:
        """The RMS misfit at ``q`` (n,) in the data's unit (not normalised)."""
        ...


CAPABILITIES = {"family": HasFamily, "repair": Repairable, "residuals": HasResiduals,
                "case_fields": VariesCase, "variants": HasVariants}
"""Capability names as a solver's error messages and ``camopt solvers`` spell them."""


def capability_name(protocol: type) -> str:
    """The short name of a capability Protocol (``Repairable`` -> ``repair``)."""
    return next((k for k, v in CAPABILITIES.items() if v is protocol), protocol.__name__)
