"""A current cam entered as points: cam angle against follower angle.

A CSV with a header naming ``cam_angle_deg`` (or ``cam_angle_rad``) and
``follower_angle_deg`` (or ``follower_angle_rad``): the cam angle theta_c from the cam
meeting the roller and the follower's angle phi of Eq 6 (the names and meaning of the
analysis curves ``camopt export --format csv`` writes, so an exported cam reads back). The
points must cover the stroke, 0 to the case's last node angle (``node_cam_deg``, 140 deg
in the paper). The follower law is the polynomial phi = sum a_k theta_c^k (Eq 9) of the
least degree from 3 (the paper's cubic) to 5 that passes every point within
:data:`FIT_TOLERANCE_DEG`; a cam no such polynomial follows is refused with the residual
(the model's law is a polynomial: a cam it cannot represent would be simulated wrongly).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from camopt.cases.vcb.curves import read_table
from camopt.errors import ConfigError
from camopt.mechanics import Floats
from camopt.units import DEG

CAM_COLUMNS = {"cam_angle_deg": DEG, "cam_angle_rad": 1.0}
FOLLOWER_COLUMNS = {"follower_angle_deg": DEG, "follower_angle_rad": 1.0}
FIT_TOLERANCE_DEG = 0.01
"""Largest distance (deg) of a point from the fitted law: a drawing's or a measuring
machine's resolution, well below the 0.1 deg that changes the closing velocity by 0.1 %."""
MAX_POINTS = 100_000
COVER_DEG = 0.5
"""The points must reach within this of both ends of the stroke (deg)."""


def read_cam_points(path: str | Path, end: float) -> Floats:
    """The follower-law coefficients a0..ad (rad/rad^k, (d + 1,), d = 3..5) of the cam in
    a points file (module docstring); ``end`` the stroke's last cam angle (rad)."""
    name = str(path)
    _, data = read_table(path, (CAM_COLUMNS, FOLLOWER_COLUMNS), "cam_points", MAX_POINTS)
    theta, phi = data[:, 0], data[:, 1]
    if len(theta) < 8:
        raise ConfigError(name, "cam_points", f"{len(theta)} points: at least 8 are needed "
                          "to fit a law")
    if np.any(np.diff(theta) <= 0):
        k = int(np.argmax(np.diff(theta) <= 0))
        raise ConfigError(name, f"line {k + 3}", "cam angles must increase")
    if abs(theta[0]) > COVER_DEG * DEG or theta[-1] < end - COVER_DEG * DEG:
        raise ConfigError(name, "cam_points", f"the points cover {theta[0] / DEG:g} to "
                          f"{theta[-1] / DEG:g} deg; the stroke is 0 to {end / DEG:g} deg")
    worst = np.inf
    for degree in (3, 4, 5):
        a = np.polynomial.polynomial.polyfit(theta, phi, degree)
        worst = float(np.max(np.abs(np.polynomial.polynomial.polyval(theta, a) - phi)))
        if worst <= FIT_TOLERANCE_DEG * DEG:
            return np.asarray(a)
    raise ConfigError(name, "cam_points", f"no polynomial law of degree 3 to 5 follows the "
                      f"points within {FIT_TOLERANCE_DEG:g} deg (the quintic misses by "
                      f"{worst / DEG:.3g} deg)")
