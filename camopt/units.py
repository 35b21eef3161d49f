"""SI factors of the engineers' units that case-file field names carry (``l1_mm``,
``t0_ms``, ``theta1_deg``, ``shear_modulus_gpa``).

A config value in the unit its name says, times the factor, is SI: ``c.l1_mm * MM`` is in
metres, and an SI value divided by the factor is back in the name's unit (``x / MM`` for
a ``_mm`` output). Cases convert once, where the Problem is built from its config (the
config boundary); everything after that is SI. Millimetres and milliseconds have the
same factor but different names, so each reads as what it converts.
"""

from __future__ import annotations

import math

MM = 1e-3
"""millimetre -> metre"""
MS = 1e-3
"""millisecond -> second"""
DEG = math.pi / 180
"""degree -> radian"""
KN = 1e3
"""kilonewton -> newton"""
MPA = 1e6
"""megapascal -> pascal"""
GPA = 1e9
"""gigapascal -> pascal"""
