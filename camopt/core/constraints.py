"""When a normalised constraint (``g <= 0`` feasible) counts as violated and when as
active: the two limits every reader of a design shares. A module of their own, so an
archive's reader (``show``) has them without :mod:`camopt.core.problem`'s classes
(start-up time); ``camopt.core.problem`` re-exports them."""

from __future__ import annotations

ACTIVE_TOL = 1e-4
"""A normalised constraint g with ``|g| <= ACTIVE_TOL`` counts as active (at its bound):
0.01 % of the bound, loose enough for gradient solvers that stop a margin inside."""
FEASIBILITY_TOL = 1e-9
"""Round-off allowance: a normalised constraint counts as violated only above this."""
