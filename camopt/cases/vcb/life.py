"""A VCB breaker at the end of its life: every friction torque times 1 +
``life_friction_rise`` and the closing springs relaxed, their compression in the charged
(opened) state times 1 - ``life_spring_relaxation`` (their force there that share lower).
The factory's preload nut stays where it was left: the setting is made once, as built."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.parts import Parts, case_pre
from camopt.cases.vcb.setting import Setting

LIFE_END_METRICS = ("closing_velocity_low_m_s", "closing_velocity_high_m_s",
                    "latch_kinetic_energy_low_j", "latch_kinetic_energy_high_j",
                    "release_torque_margin_low", "band_sets_not_latched")
"""The metrics reported again at the end of life (``life_end_`` + name), where the run
judges it: the verdict's worst alone does not say when a requirement binds."""


def ages(c: VcbConfig, search_dynamics: bool) -> bool:
    """Whether a design is judged at the end of its life too (``life_friction_rise`` or
    ``life_spring_relaxation``): only where the dynamics run (``search_dynamics``), which
    is all the end of life changes."""
    return search_dynamics and (c.life_friction_rise > 0 or c.life_spring_relaxation > 0)


def aged(c: VcbConfig, n: int, parts: Parts | None, setting: Setting | None
         ) -> tuple[Parts, Setting | None]:
    """n breakers as built (``parts``, set at the factory by ``setting``) at the end of
    their life: the friction scale times 1 + ``life_friction_rise``, the closing springs'
    compressions times 1 - ``life_spring_relaxation``, each set's own set compressions
    likewise (the nut unmoved)."""
    parts = Parts() if parts is None else parts
    keep, rise = 1.0 - c.life_spring_relaxation, 1.0 + c.life_friction_rise
    pre = parts.pre if parts.pre is not None else case_pre(c, n)
    scale = (np.ones(n) if parts.friction_scale is None else parts.friction_scale) * rise
    out = replace(parts, pre=pre * keep, friction_scale=scale)
    if setting is None or setting.member_pre is None:
        return out, setting
    return out, replace(setting, member_pre=setting.member_pre * keep)
