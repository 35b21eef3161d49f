"""The band of a VCB design's closing: its extremes over the identified parameters and
the parameter sets of ``dynamics_band`` (every kept model form)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from camopt.cases.vcb.dynamics import ClosingEvents, ClosingMotion, closing_events
from camopt.cases.vcb.loads import Loads
from camopt.cases.vcb.model import VcbModel
from camopt.cases.vcb.motion import ClosingCurves, MotionParameters
from camopt.mechanics import Bools, Floats, Ints
from camopt.units import MS


@dataclass(frozen=True)
class MotionBand:
    """Extremes of the closing per design (n,) over the identified parameters and the
    parameter sets equally consistent with the ADAMS data (``dynamics_band``): average
    closing velocity (m/s; 0 under a set with which the contacts never meet), latched under
    every set, least and greatest kinetic energy at the latch (J), least reach (fraction
    of the stroke), least release torque ratio (eps T_s / T_f at the release), the number
    of parameter sets (``sets``, the identified one included; one for all, or (n,) where
    the designs were judged under different model forms) and of those under which
    the cam does not release and latch (``not_latched``), and the least and greatest of
    every :data:`BANDED` motion quantity (SI)."""

    velocity_low: Floats
    velocity_high: Floats
    latched: Bools
    kinetic_low: Floats
    kinetic_high: Floats
    reach_low: Floats
    release_ratio_low: Floats
    sets: int | Ints
    not_latched: Ints
    low: dict[str, Floats]
    high: dict[str, Floats]

    @classmethod
    def of(cls, nominal: ClosingEvents, members: ClosingEvents | None = None, k: int = 0
           ) -> MotionBand:
        """The band of ``nominal`` (n designs) and ``members`` (k sets x n designs)."""
        def stack(name: str) -> Floats:
            first = getattr(nominal, name)[None, :]
            if members is None:
                return first
            return np.concatenate([first, getattr(members, name).reshape(k, -1)])
        # contacts that never meet close at zero speed: finite, so that a search starting
        # among stalling designs still sees how far it is from the requirement
        v = np.nan_to_num(stack("closing_velocity_avg"), nan=0.0)
        fields = {field: stack(field) for field, _, _ in BANDED.values()}
        latched = np.asarray(stack("latched"), dtype=bool)
        with np.errstate(invalid="ignore"):
            return cls(velocity_low=v.min(axis=0), velocity_high=v.max(axis=0),
                       latched=np.asarray(latched.all(axis=0)),
                       kinetic_low=stack("final_kinetic").min(axis=0),
                       kinetic_high=stack("final_kinetic").max(axis=0),
                       reach_low=stack("reach").min(axis=0),
                       release_ratio_low=stack("release_torque_ratio").min(axis=0),
                       sets=k + 1, not_latched=(~latched).sum(axis=0),
                       low={f: a.min(axis=0) for f, a in fields.items()},
                       high={f: a.max(axis=0) for f, a in fields.items()})


BANDED = {
    "touch_velocity_m_s": ("touch_velocity", "_m_s", 1.0),
    "cam_contact_time_ms": ("cam_contact_time", "_ms", MS),
    "touch_time_ms": ("touch_time", "_ms", MS),
    "release_to_latch_ms": ("closing_time", "_ms", MS),
    "pickup_impact_energy_j": ("pickup_loss", "_j", 1.0),
}
"""Reported with their band: extra name -> (ClosingMotion field, the name's unit suffix,
SI factor); the band's extras insert low/high before the unit (``touch_time_low_ms``).
Times run from the release of the closing springs: ``touch_time_ms`` to the contacts'
touch, ``release_to_latch_ms`` to the latch (the motion's field ``closing_time``); the
analyser's closing time, command to touch (``closing_time_ms``), adds the case's
``latch_delay_ms`` (:meth:`camopt.cases.vcb.problem.VcbProblem`'s extras)."""


def band_ends(name: str) -> tuple[str, str]:
    """The names of the band's lower and higher ends of a :data:`BANDED` extra: low/high
    before its unit (``touch_time_ms`` -> ``touch_time_low_ms``, ``touch_time_high_ms``)."""
    unit = BANDED[name][1]
    return name.replace(unit, "_low" + unit), name.replace(unit, "_high" + unit)



def band_motion(m: VcbModel, nominal: ClosingMotion, A: Floats, kc: Floats, link: Floats,
                rod_offset: float, loads: Loads, sets: MotionParameters, k: int, steps: int,
                pre: Floats | None = None, member_pre: Floats | None = None) -> MotionBand:
    """The band of n designs (follower law ``A``, spring rates ``kc``, linkage ``link``,
    n rows each; ``loads`` per design): their closing under ``k`` parameter sets each
    (``sets``: k x n rows, set-major) beside the ``nominal`` closing, one vectorised
    call. ``pre`` (n, 2) m the closing springs' compressions as made, or ``member_pre``
    (k x n, 2) each set's own (a breaker set at the factory under that set)."""
    if member_pre is not None:
        events = closing_events(m, np.tile(A, (k, 1)), np.tile(kc, (k, 1)),
                                np.tile(link, (k, 1)), rod_offset, loads.tiled(k), sets,
                                steps, pre=member_pre)
    else:
        events = closing_events(m, A, kc, link, rod_offset, loads, sets, steps, sets=k,
                                pre=pre)
    return MotionBand.of(nominal, events, k)


def _scattered(pieces: Sequence[np.ndarray], groups: Sequence[Ints], n: int) -> np.ndarray:
    """One array of n rows from ``pieces``, piece i's rows going to rows ``groups[i]``."""
    first = np.asarray(pieces[0])
    out = np.empty((n, *first.shape[1:]), dtype=first.dtype)
    for rows, piece in zip(groups, pieces, strict=True):
        out[rows] = piece
    return out


def merged_motion(motions: Sequence[ClosingMotion], groups: Sequence[Ints], n: int
                  ) -> ClosingMotion:
    """The closing of n designs from ``motions`` of row groups ``groups`` (their row
    indices): every per-design field put back in row order, the curves on first use."""
    def curves() -> ClosingCurves:
        each = [m.curves() for m in motions]
        return ClosingCurves(theta_c=each[0].theta_c, **{
            f.name: _scattered([getattr(c, f.name) for c in each], groups, n)
            for f in fields(ClosingCurves) if f.name != "theta_c"})
    return ClosingMotion(curves=curves, **{
        f.name: _scattered([getattr(m, f.name) for m in motions], groups, n)
        for f in fields(ClosingMotion) if f.name != "curves"})


def merged_band(bands: Sequence[MotionBand], groups: Sequence[Ints], n: int) -> MotionBand:
    """The band of n designs from ``bands`` of row groups ``groups`` (their row indices):
    each design's extremes and counts as its group's, ``sets`` per design (n,)."""
    def put(pieces: list[np.ndarray]) -> np.ndarray:
        return _scattered(pieces, groups, n)
    return MotionBand(
        **{f.name: put([getattr(b, f.name) for b in bands]) for f in fields(MotionBand)
           if f.name not in ("sets", "low", "high")},
        sets=put([np.full(len(b.latched), b.sets) for b in bands]),
        low={k: put([b.low[k] for b in bands]) for k in bands[0].low},
        high={k: put([b.high[k] for b in bands]) for k in bands[0].high})
