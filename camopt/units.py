"""SI factors of the engineers' units that case-file field names carry (``l1_mm``,
``t0_ms``, ``theta1_deg``, ``shear_modulus_gpa``).

A config value in the unit its name says, times the factor, is SI: ``c.l1_mm * MM`` is in
metres, and an SI value divided by the factor is back in the name's unit (``x / MM`` for
a ``_mm`` output). Cases convert once, where the Problem is built from its config (the
config boundary); everything after that is SI. Millimetres and milliseconds have the
same factor but different names, so each reads as what it converts.

Outputs go the other way: ``x * TO_MM`` is ``x`` in millimetres. The ``TO_`` factors are
the exact reciprocals a person would write (``1 / MM`` is 1000.0 exactly), so an output
converted with them is bit for bit what ``x * 1e3`` gave; a division by a factor
(``sigma / MPA``) is kept a division for the same reason.
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
N_PER_MM = 1e3
"""newton per millimetre -> newton per metre (a spring rate)"""
SQRT_MPA = math.sqrt(MPA)
"""square-root megapascal -> square-root pascal (an elasticity coefficient, Hertz's Z_E)"""

TO_MM = 1 / MM
"""metre -> millimetre (1000.0 exactly)"""
TO_MS = 1 / MS
"""second -> millisecond (1000.0 exactly)"""
TO_DEG = 1 / DEG
"""radian -> degree (180 / pi exactly)"""
TO_N_PER_MM = 1 / N_PER_MM
"""newton per metre -> newton per millimetre (0.001 exactly)"""
