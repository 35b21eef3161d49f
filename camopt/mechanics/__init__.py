"""Pure-numpy physics shared by the cases: springs, linkages, cams, contact, dynamics.

Functions of arrays in SI units; they broadcast over a population and samples. Their
signatures use the aliases below: ``Floats`` for a float64 array of any shape and
``FloatsLike`` for a float or such an array (what the functions accept); the rest of
camopt also uses ``Bools`` (masks) and ``Ints`` (indices).
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

Floats: TypeAlias = NDArray[np.float64]
Bools: TypeAlias = NDArray[np.bool_]
"""A bool array (a mask: feasible rows, latched designs)."""
Ints: TypeAlias = NDArray[np.intp]
"""An index array (rows, an order, each draw's model variant)."""
FloatsLike: TypeAlias = "float | NDArray[np.float64]"
