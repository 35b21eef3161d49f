"""Slider-crank kinematics of the fast acting switch (Clauss 1982, Fig 1, Eqs 3 and 97).

Crank (link 2) of length r2 at angle theta2 from the pivot; coupler (part 3) of
length r3 at theta3 in the fourth quadrant; the piston pin lies on the pivot's
horizontal line at distance ``span = r2 cos theta2 + r3 cos theta3``.
"""

from __future__ import annotations

import numpy as np

from camopt.mechanics import Floats, FloatsLike


def crank_angle_for_span(r2: FloatsLike, r3: FloatsLike, span: FloatsLike) -> Floats:
    """cos(theta2) that closes the loop over ``span`` (law of cosines on Eq 3's first two lines).

    Values outside [-1, 1] mean the loop cannot close; callers turn that into a constraint.
    A zero span or crank (the pin on the pivot) has no such angle: the loop closes there
    only in the degenerate r2 = r3, whose crank angle is undetermined, so it is given
    ``inf`` (cannot close) by an explicit mask rather than a division by zero.
    """
    num = np.square(r2) + np.square(span) - np.square(r3)
    den = 2.0 * np.asarray(r2, dtype=float) * np.asarray(span, dtype=float)
    num, den = np.broadcast_arrays(num, den)
    return np.divide(num, den, out=np.full(num.shape, np.inf), where=den != 0)


def coupler_angle(r2: FloatsLike, r3: FloatsLike, theta2: FloatsLike, span: FloatsLike) -> Floats:
    """theta3 in [0, 2 pi) from r2 sin theta2 + r3 sin theta3 = 0 and the horizontal loop."""
    return np.mod(np.arctan2(-r2 * np.sin(theta2), span - r2 * np.cos(theta2)), 2.0 * np.pi)


def coupler_derivatives(r2: FloatsLike, r3: FloatsLike, theta2: FloatsLike
                        ) -> tuple[Floats, Floats, Floats, Floats, Floats]:
    """theta3, dtheta3/dtheta2, d2theta3/dtheta2^2, ds/dtheta2, d2s/dtheta2^2 along the motion.

    theta3 is taken on the fourth-quadrant branch (cos theta3 > 0) and s is the
    spring length, which grows as the crank turns toward 90 deg (Eq 3, lines 1-2).
    At the dead centre (cos theta3 = 0: r2 |sin theta2| >= r3, the coupler square to the
    slide) the 1-DOF model has no finite derivatives: d3, dd3, ds and dds are NaN there,
    by an explicit mask (no division by zero; the caller's motion stops being defined).
    """
    r2, r3, theta2 = np.asarray(r2), np.asarray(r3), np.asarray(theta2)
    sin3 = -r2 * np.sin(theta2) / r3
    cos3 = np.sqrt(np.clip(1.0 - sin3**2, 0.0, None))
    theta3 = np.mod(np.arctan2(sin3, cos3), 2.0 * np.pi)
    den = r3 * cos3
    num, den = np.broadcast_arrays(-r2 * np.cos(theta2), den)
    live = den != 0
    d3 = np.divide(num, den, out=np.full(num.shape, np.nan), where=live)
    dd3 = np.divide(r2 * np.sin(theta2) + r3 * sin3 * np.where(live, d3, 0.0) ** 2, den,
                    out=np.full(num.shape, np.nan), where=live)
    # s = g - p4 - r2 cos theta2 - r3 cos theta3 (Eq 3, line 2)
    ds = r2 * np.sin(theta2) + r3 * sin3 * d3
    dds = r2 * np.cos(theta2) + r3 * cos3 * d3**2 + r3 * sin3 * dd3
    return theta3, d3, dd3, ds, dds
