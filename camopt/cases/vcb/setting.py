"""The factory setting of a VCB breaker: both closing springs' compressions in the opened
state moved by one preload nut travel d until the average closing velocity (what the
breaker analyser reads) is the design's ``velocity_setting_m_s``.

d solves v(d)^2 = v_set^2 by one secant step from d = 0 and :data:`SETTING_TRIAL_MM`:
the kinetic energy at the touch is affine in d (the springs' energy is linear in their
compression), so v^2 is nearly so, and the step leaves < 1e-3 m/s under every parameter
set, twenty times inside the analyser's 2 % (tests/cases/test_vcb_setting.py, on random
designs and parts); a second step cost a third more."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from camopt.mechanics import Floats
from camopt.units import MM

SETTING_TRIAL_MM = 2.0
"""The factory setting's trial nut travel (mm; the other trial is none): the secant's
two points."""


@dataclass(frozen=True)
class Setting:
    """A factory setting of n breakers under a form's k + 1 parameter sets: the band's
    other sets' set compressions ``member_pre`` (k n, 2) m, set-major as the band's rows
    (None without other sets), and the nut travel each set needs, ``needed`` (k + 1, n) m
    (the fit's first; +inf: none reaches the velocity)."""

    member_pre: Floats | None
    needed: Floats

    @property
    def longest(self) -> Floats:
        """(n,) the needed travel of the set that needs the most, with its sign."""
        return longest(self.needed)


def longest(travels: Floats) -> Floats:
    """(n,) each column's entry of largest magnitude, with its sign, of ``travels``
    (k, n): the nut must reach the set that needs the most, whichever way it turns."""
    index = np.argmax(np.abs(travels), axis=0)
    return np.take_along_axis(travels, index[None], axis=0)[0]


def nut_setting(velocity: Callable[[Floats], Floats], base: Floats, target: Floats,
                sets: int, reach_mm: float) -> tuple[Floats, Setting]:
    """The nut travel that sets n breakers under ``sets`` parameter sets each (k n rows,
    set-major, the fit first): ``velocity(pre)`` the average closing velocity of each row
    with closing-spring compressions ``pre`` (k n, 2) m (NaN: the contacts never meet),
    ``base`` (k n, 2) the compressions as made, ``target`` (k n,) the set velocity. The
    needed d is +inf where neither trial brings the contacts together (a stall at d = 0
    and at the trial); the applied d is clipped to +- ``reach_mm`` (the nut's end).
    Returns the fit's set compressions (n, 2) and the :class:`Setting`."""
    rows = len(base)
    n = rows // sets

    def squared_speed(d: Floats) -> Floats:
        return np.asarray(np.nan_to_num(velocity(base + d[:, None]), nan=0.0) ** 2)

    d_a, d_b = np.zeros(rows), np.full(rows, SETTING_TRIAL_MM * MM)
    w_a, w_b = squared_speed(d_a), squared_speed(d_b)  # the breaker as made, and a trial
    target_sq = target ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        needed = d_b + (target_sq - w_b) * (d_b - d_a) / (w_b - w_a)
    needed = np.where(np.isfinite(needed), needed, np.inf)
    reach = reach_mm * MM
    pre = base + np.clip(needed, -reach, reach)[:, None]
    return pre[:n], Setting(pre[n:] if sets > 1 else None, needed.reshape(sets, n))
