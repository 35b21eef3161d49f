"""One verdict over several judgements of the same VCB breakers (every kept model form, or
the start and the end of life). Each constraint takes its worst; each metric is reduced by
the rule :data:`REDUCTIONS` declares for it (a metric not declared keeps the first
judgement's value): a requirement holds only if it holds under every judgement, so a
lower end is the least, a higher end the greatest, a count of failing sets the total or
the worst, the nut the longest travel any judgement needs."""

from __future__ import annotations

import warnings
from dataclasses import replace
from enum import Enum

import numpy as np

from camopt.cases.vcb.band import BANDED, band_ends
from camopt.cases.vcb.life import LIFE_END_METRICS
from camopt.cases.vcb.setting import longest
from camopt.core.problem import Evaluation
from camopt.mechanics import Floats


class Reduction(Enum):
    """How a metric's values under several judgements become one."""

    LEAST = "least"
    """The least, NaN ignored (a lower end; a worst-is-least metric: latched 0 or 1)."""
    GREATEST = "greatest"
    """The greatest, NaN ignored (a higher end; a worst-is-greatest metric)."""
    LEAST_OR_NAN = "least or NaN"
    """The least, NaN if any is NaN (a velocity undefined where a set never closes)."""
    GREATEST_OR_NAN = "greatest or NaN"
    """The greatest, NaN if any is NaN."""
    COUNT = "count"
    """A count of sets: the sum over different sets (the forms), else the worst (the
    same sets at the start and the end of life)."""
    LONGEST = "longest"
    """The nut travel of largest magnitude, with its sign."""


def _band_ends() -> dict[str, Reduction]:
    out: dict[str, Reduction] = {}
    for name in BANDED:
        low, high = band_ends(name)
        out[low], out[high] = Reduction.LEAST, Reduction.GREATEST
    return out


REDUCTIONS: dict[str, Reduction] = {
    "closing_velocity_low_m_s": Reduction.LEAST_OR_NAN,
    "closing_velocity_high_m_s": Reduction.GREATEST_OR_NAN,
    "latch_kinetic_energy_low_j": Reduction.LEAST,
    "latch_kinetic_energy_high_j": Reduction.GREATEST,
    "release_torque_margin_low": Reduction.LEAST,
    "closing_time_low_ms": Reduction.LEAST,
    "closing_time_high_ms": Reduction.GREATEST,
    **_band_ends(),
    "latched": Reduction.LEAST,
    "lift_off_torque_ratio": Reduction.LEAST,
    "cam_torque_min_nm": Reduction.LEAST,
    "pickup_tau_mpa": Reduction.GREATEST,
    "band_sets": Reduction.COUNT,
    "band_sets_not_latched": Reduction.COUNT,
    "preload_setting_mm": Reduction.LONGEST,
}
"""Each reduced metric's rule (a ``life_end_`` prefix takes its metric's). Not declared,
the first judgement's value: the identified form's, or the start of life's."""


def reduce(rule: Reduction, stack: Floats, sum_counts: bool) -> Floats:
    """``stack`` (judgements, n) reduced by ``rule`` to (n,)."""
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns stay NaN
        if rule is Reduction.COUNT:
            return np.asarray(stack.sum(axis=0) if sum_counts else stack.max(axis=0))
        if rule is Reduction.LONGEST:
            return longest(stack)
        if rule is Reduction.LEAST_OR_NAN:
            return np.asarray(np.min(stack, axis=0))
        if rule is Reduction.GREATEST_OR_NAN:
            return np.asarray(np.max(stack, axis=0))
        if rule is Reduction.LEAST:
            return np.asarray(np.nanmin(stack, axis=0))
        return np.asarray(np.nanmax(stack, axis=0))


def worst_of(each: list[Evaluation], penalty: float, sum_counts: bool = False,
             life_end: Evaluation | None = None) -> Evaluation:
    """One verdict over several judgements ``each`` of the same breakers: each constraint
    at its worst, g = max_j g_j; the objective the first's with the worst violation's
    penalty, f = f_1 - p sum(max(g_1, 0)) + p sum(max(g, 0)) (Eq 39's penalty on the
    verdict's constraints); the metrics by :data:`REDUCTIONS`. ``sum_counts``: the
    judgements are under different sets (the forms), so their set counts add up.
    ``life_end``: its :data:`LIFE_END_METRICS` reported as ``life_end_*``."""
    g = np.max([e.g for e in each], axis=0)
    violation = np.clip(g, 0, None).sum(axis=1)
    first = each[0]
    own = np.clip(first.g, 0, None).sum(axis=1)
    with np.errstate(invalid="ignore"):  # inf - inf: no finite objective either way
        base = np.where(own == 0, first.f, first.f - penalty * own)
    f = np.where(np.isfinite(base) & np.isfinite(violation), base + penalty * violation,
                 np.inf)
    extras = dict(first.extras)
    for key in extras:
        rule = REDUCTIONS.get(key.removeprefix("life_end_"))
        if rule is not None:
            extras[key] = reduce(rule, np.array([e.extras[key] for e in each], dtype=float),
                                 sum_counts)
    if life_end is not None:
        extras.update({f"life_end_{k}": life_end.extras[k] for k in LIFE_END_METRICS
                       if k in life_end.extras})
    return Evaluation(f=f, g=g, extras=extras)


def over_life(start: Evaluation, end: Evaluation, constraint_names: tuple[str, ...],
              penalty: float) -> Evaluation:
    """The verdict on breakers judged as built (``start``) and at the end of their life
    (``end``, :mod:`.life`): :func:`worst_of` both, the end's metrics reported too; the
    preload nut's reach (``preload_setting``) judged as built alone, since the nut is set
    once, at the factory."""
    if "preload_setting" in constraint_names:
        column = constraint_names.index("preload_setting")
        end = replace(end, g=end.g.copy())
        end.g[:, column] = start.g[:, column]
    return worst_of([start, end], penalty, life_end=end)
