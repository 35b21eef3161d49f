"""The factory setting of a VCB breaker: both closing springs' compressions in the opened
state moved by one preload nut travel d until the average closing velocity (what the
breaker analyser reads) is the design's ``velocity_setting_m_s``, d a whole number of the
nut's steps where it has a resolution.

d solves v(d)^2 = v_set^2 (:func:`nut_travel`) by one secant step from d = 0 and
:data:`SETTING_TRIAL_MM`: the kinetic energy at the touch is affine in d (the springs'
energy is linear in their compression), so v^2 is nearly so, and the step leaves < 1e-3
m/s under every parameter set, twenty times inside the analyser's 2 %
(tests/cases/test_vcb_setting.py, on random designs and parts). Two repairs run on the
rows that need them only: a weak breaker (a stall at a trial) and a long travel."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from typing import TypeVar, cast

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.dynamics import closing_events
from camopt.cases.vcb.loads import Loads
from camopt.cases.vcb.model import VcbModel
from camopt.cases.vcb.motion import MotionParameters
from camopt.mechanics import Floats, Ints
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


def nut_setting(velocity: Callable[[Floats, Ints], Floats], base: Floats,
                target: Floats, sets: int, reach_mm: float, step_mm: float = 0.0
                ) -> tuple[Floats, Setting]:
    """The nut travel that sets n breakers under ``sets`` parameter sets each (k n rows,
    set-major, the fit first): ``velocity(pre, rows)`` the average closing velocity of
    rows ``rows`` with closing-spring compressions ``pre`` (len(rows), 2) m (NaN: the
    contacts never meet), ``base`` (k n, 2) the compressions as made, ``target`` (k n,)
    the set velocity. The needed d is +inf where no travel within reach brings the
    contacts together; with ``step_mm`` > 0 it is the nearest whole number of steps (the
    fitter turns the nut by flats or adds shims); the applied d is clipped to
    +- ``reach_mm`` (the nut's end). Returns the fit's set compressions (n, 2) and the
    :class:`Setting`."""
    rows = len(base)
    n = rows // sets

    def squared_speed(d: Floats, which: Ints) -> Floats:
        return np.asarray(np.nan_to_num(velocity(base[which] + d[:, None], which),
                                        nan=0.0) ** 2)

    reach = reach_mm * MM
    needed = nut_travel(squared_speed, target ** 2, SETTING_TRIAL_MM * MM, reach)
    step = step_mm * MM
    if step > 0:
        needed = np.where(np.isfinite(needed), np.round(needed / step) * step, needed)
    pre = base + np.clip(needed, -reach, reach)[:, None]
    return pre[:n], Setting(pre[n:] if sets > 1 else None, needed.reshape(sets, n))


def nut_travel(squared_speed: Callable[[Floats, Ints], Floats], target: Floats,
               trial: float, reach: float) -> Floats:
    """The nut travel d (m, (rows,)) at which each row's squared closing velocity,
    ``squared_speed(d, rows)`` (0 where the breaker stalls), is ``target``; +inf where no
    travel within ``reach`` closes it at all.

    One secant step from d = 0 and ``trial``, then two repairs, each on its rows only: a
    row that stalls at either trial (a weak breaker: off the secant's line, not
    necessarily beyond the nut's reach) is tried at the nut's end and one trial short of it
    (the end itself where only the end closes and reaches the velocity); a row whose step
    went further than two trials from its nearest point (a long extrapolation: the set
    velocity 0.7 % off at 26 mm, 4e-5 after the second step) takes a second secant step
    from there to the first step's travel (clipped to the reach)."""
    rows = np.arange(len(target))
    d_a, d_b = np.zeros(len(rows)), np.full(len(rows), trial)
    w_a, w_b = squared_speed(d_a, rows), squared_speed(d_b, rows)
    needed = _secant(d_a, d_b, w_a, w_b, target)
    near_d, near_w = d_b.copy(), w_b.copy()  # the point each row's step started from
    weak = np.flatnonzero((w_a == 0) | (w_b == 0))
    if weak.size and reach > trial:
        d_c, d_d = np.full(weak.size, reach - trial), np.full(weak.size, reach)
        w_c, w_d = squared_speed(d_c, weak), squared_speed(d_d, weak)
        line = _secant(d_c, d_d, w_c, w_d, target[weak])
        closes_at_end = (w_d > 0) & (w_d >= target[weak])
        needed[weak] = np.where(np.isfinite(line), line,
                                np.where(closes_at_end, reach, np.inf))
        near_d[weak], near_w[weak] = d_d, w_d
    far = np.flatnonzero(np.isfinite(needed) & (np.abs(needed - near_d) > 2 * trial)
                         & (near_w > 0))
    if far.size:
        d_e = np.clip(needed[far], -reach, reach)
        w_e = squared_speed(d_e, far)
        line = _secant(near_d[far], d_e, near_w[far], w_e, target[far])
        needed[far] = np.where(np.isfinite(line), line, needed[far])
    return needed


def _secant(d_a: Floats, d_b: Floats, w_a: Floats, w_b: Floats, goal: Floats
            ) -> Floats:
    """The root of the line through (d_a, w_a), (d_b, w_b) at ``goal``; +inf where either
    point stalls (w = 0) or the line is flat."""
    with np.errstate(divide="ignore", invalid="ignore"):
        found = d_b + (goal - w_b) * (d_b - d_a) / (w_b - w_a)
    return np.where(np.isfinite(found) & (w_a > 0) & (w_b > 0), found, np.inf)


_Rows = TypeVar("_Rows")


def rows_of(value: _Rows, rows: Ints, total: int) -> _Rows:
    """``value`` (an array, or a dataclass of arrays and shared numbers) at ``rows`` of its
    ``total`` rows: every array whose first axis has ``total`` rows is indexed, the rest
    (one value for every row) kept."""
    if isinstance(value, np.ndarray):
        return cast(_Rows, value[rows]) if value.ndim and len(value) == total else value
    return replace(value, **{f.name: rows_of(getattr(value, f.name), rows, total)  # type: ignore[type-var]
                             for f in fields(value)  # type: ignore[arg-type]
                             if isinstance(getattr(value, f.name), np.ndarray)})


def set_at_factory(m: VcbModel, c: VcbConfig, A: Floats, kc: Floats, link: Floats,
                   rod_offset: float, loads: Loads, params: MotionParameters, base: Floats,
                   velocity: Floats, sets: int) -> tuple[Floats, Setting]:
    """n breakers (follower law ``A``, spring rates ``kc``, linkage ``link``, n rows each;
    ``loads`` per breaker) set by the preload nut under ``sets`` parameter sets each
    (``params``: sets x n rows, set-major, the fit first): ``base`` (n, 2) the closing
    springs' compressions as made, ``velocity`` (n,) the velocity each breaker is set to.
    The analyser's reading is the closing's average velocity
    (:func:`~camopt.cases.vcb.dynamics.closing_events`, one vectorised call over the rows
    a trial needs); the travel within ``preload_setting_range_mm`` at
    ``preload_setting_resolution_mm`` (:func:`nut_setting`, whose result this is)."""
    n = len(A)
    A_rows, kc_rows, link_rows = (np.tile(a, (sets, 1)) for a in (A, kc, link))
    loads = loads.tiled(sets)

    def velocity_of(pre: Floats, rows: Ints) -> Floats:
        total = sets * n
        return closing_events(
            m, rows_of(A_rows, rows, total), rows_of(kc_rows, rows, total),
            rows_of(link_rows, rows, total), rod_offset, rows_of(loads, rows, total),
            rows_of(params, rows, total), c.dynamics_steps, pre=pre).closing_velocity_avg

    return nut_setting(velocity_of, np.tile(base, (sets, 1)), np.tile(velocity, sets), sets,
                       c.preload_setting_range_mm, c.preload_setting_resolution_mm)
