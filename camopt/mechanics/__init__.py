"""Pure-numpy physics shared by the cases: springs, linkages, cams, contact, dynamics.

Functions of arrays in SI units; they broadcast over a population and samples. Their
signatures use the two aliases below: ``Floats`` for a float64 array of any shape and
``FloatsLike`` for a float or such an array (what the functions accept).
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

Floats: TypeAlias = NDArray[np.float64]
FloatsLike: TypeAlias = "float | NDArray[np.float64]"
