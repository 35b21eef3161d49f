"""A VCB breaker's parts as made: per-design draws of the case's tolerance fields, and what
they change: the linkage, the closing springs' compressions, the opening and contact
springs' rates (the loads), every friction torque, the efficiency and the cam profile's
radial error (an offset of the follower law's a0)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.dynamics import MotionParameters
from camopt.cases.vcb.model import Loads, VcbModel
from camopt.errors import ConfigError
from camopt.mechanics import Bools, Floats, Ints, cam
from camopt.units import DEG, MM, N_PER_MM

LINK_FIELDS = ("l1_mm", "l3_mm", "l4_mm", "l5_mm", "theta1_deg")
"""The linkage fields of ``[case]`` in the order of a linkage row (``designs``)."""
PART_FIELDS = ("kc1_precompression_mm", "kc2_precompression_mm", "opening_k_n_per_mm",
               "wipe_k_n_per_mm", "cam_friction_nm", "efficiency", "cam_profile_error_mm")
"""The parts' fields of ``[case]`` a design can take per row in either step: the closing
springs' compressions in the opened state (their free lengths as made), the opening and
contact springs' rates, the friction and efficiency, the cam profile's radial error."""


@dataclass(frozen=True)
class Parts:
    """Each design's parts as made, one row per design (SI); None: the config's value.
    ``link`` (n, 5); ``pre`` the closing springs' compressions (n, 2) m; ``opening_k``,
    ``wipe_k`` the opening spring's and all contact springs' rates (n, 1) N/m;
    ``friction_scale`` (n,) every friction torque of every parameter set times this;
    ``efficiency_shift`` (n,) added to every efficiency below 1 (the forms with Eq 26's
    eps; a form without one keeps 1); ``profile_rad`` (n,) the follower's angle offset
    from the cam profile's radial error."""

    link: Floats | None = None
    pre: Floats | None = None
    opening_k: Floats | None = None
    wipe_k: Floats | None = None
    friction_scale: Floats | None = None
    efficiency_shift: Floats | None = None
    profile_rad: Floats | None = None

    def take(self, rows: Bools | Ints) -> Parts:
        """The parts of the designs ``rows`` (bool or index array)."""
        return Parts(*(None if v is None else v[rows] for v in
                       (self.link, self.pre, self.opening_k, self.wipe_k, self.friction_scale,
                        self.efficiency_shift, self.profile_rad)))


def case_pre(c: VcbConfig, n: int) -> Floats:
    """(n, 2) m: the case's closing-spring compressions in the opened state, every row."""
    return np.tile([c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM], (n, 1))


def parts_of(n: int, fields: Mapping[str, Floats], allowed: tuple[str, ...], c: VcbConfig,
             model: VcbModel) -> Parts:
    """The :class:`Parts` of n rows from per-row case fields (their units); a field
    outside ``allowed`` is refused (a :class:`ConfigError` naming the ones that can)."""
    unknown = sorted(set(fields) - set(allowed))
    if unknown:
        raise ConfigError("case", unknown[0], "cannot vary per design; fields that can: "
                          f"{', '.join(allowed) or 'none'}")

    def col(name: str) -> Floats:
        return np.broadcast_to(np.asarray(fields[name], dtype=float), (n,))
    link = None
    if any(f in fields for f in LINK_FIELDS):
        link = np.tile(model.vendor_link, (n, 1))
        for i, name in enumerate(LINK_FIELDS):
            if name in fields:
                link[:, i] = col(name) * (DEG if name.endswith("_deg") else MM)
    pre = None
    if "kc1_precompression_mm" in fields or "kc2_precompression_mm" in fields:
        pre = np.column_stack([
            col(f) if f in fields else np.full(n, float(getattr(c, f)))
            for f in ("kc1_precompression_mm", "kc2_precompression_mm")]) * MM
    profile = None
    if "cam_profile_error_mm" in fields:
        profile = profile_offset(model, c, col("cam_profile_error_mm"))
    return Parts(
        link=link, pre=pre,
        opening_k=col("opening_k_n_per_mm")[:, None] * N_PER_MM
        if "opening_k_n_per_mm" in fields else None,
        wipe_k=c.wipe_count * col("wipe_k_n_per_mm")[:, None] * N_PER_MM
        if "wipe_k_n_per_mm" in fields else None,
        friction_scale=col("cam_friction_nm") / c.cam_friction_nm
        if "cam_friction_nm" in fields and c.cam_friction_nm > 0 else None,
        efficiency_shift=col("efficiency") - c.efficiency if "efficiency" in fields
        else None,
        profile_rad=profile)


def loads_of(load: Loads, efficiency: float, parts: Parts | None) -> Loads:
    """The resisting loads ``load`` with the parts' spring rates and efficiency
    (``efficiency``, the case's, plus the part's shift) per row."""
    if parts is None or (parts.opening_k is None and parts.wipe_k is None
                         and parts.efficiency_shift is None):
        return load
    eff = load.efficiency if parts.efficiency_shift is None \
        else efficiency + parts.efficiency_shift
    return replace(load, opening_k=load.opening_k if parts.opening_k is None
                   else parts.opening_k,
                   wipe_k=load.wipe_k if parts.wipe_k is None else parts.wipe_k,
                   efficiency=eff)


def as_made(sets: MotionParameters, k: int, n: int, moved: Floats, parts: Parts | None,
            efficiency: float) -> MotionParameters:
    """``k`` parameter sets for n designs (k n rows, set-major): each design's latch
    ``moved`` (n,) from the identified one moves every set's, and its parts scale the
    friction and shift the efficiency (an unset efficiency is the case's ``efficiency``;
    1, a form without Eq 26's eps, stays 1)."""
    rows = sets.repeat(n)
    out = replace(rows, release_offset_rad=np.asarray(rows.release_offset_rad)
                  + np.tile(moved, k))
    if parts is None:
        return out
    if parts.friction_scale is not None:
        scale = np.tile(parts.friction_scale, k)
        out = replace(out, friction_nm=np.asarray(out.friction_nm) * scale,
                      release_friction_nm=None if out.release_friction_nm is None
                      else np.asarray(out.release_friction_nm) * scale)
    if parts.efficiency_shift is not None:
        shift = np.tile(parts.efficiency_shift, k)
        eff = (np.full(k * n, efficiency) if out.efficiency is None
               else np.asarray(out.efficiency, dtype=float))
        out = replace(out, efficiency=np.where(eff < 1.0, eff + shift, eff))
    return out


def profile_offset(model: VcbModel, c: VcbConfig, error_mm: Floats | float) -> Floats:
    """The follower's angle offset (rad) from a cam profile made ``error_mm`` oversize
    (a uniform offset along its normal): the roller sits that much further from O, so
    the follower angle at the base circle moves by the change of Eq 10's base angle,
    and (first order, docs/assumptions.md) by the same along the stroke."""
    rp = model.rb + model.rf + c.node_clearance_mm * MM
    return np.asarray(cam.base_angle(model.l2, model.l6, rp + np.asarray(error_mm) * MM)
                      - cam.base_angle(model.l2, model.l6, rp), dtype=float)


def profiled(A: Floats, parts: Parts | None, model: VcbModel, c: VcbConfig) -> Floats:
    """The follower law's coefficients ``A`` with the cam profile's error (the row's,
    else the config's ``cam_profile_error_mm``) in a0."""
    if parts is not None and parts.profile_rad is not None:
        offset: Floats | float = parts.profile_rad
    elif c.cam_profile_error_mm:
        offset = float(profile_offset(model, c, c.cam_profile_error_mm))
    else:
        return A
    A = A.copy()
    A[:, 0] += offset
    return A
