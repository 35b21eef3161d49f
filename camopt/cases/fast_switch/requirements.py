"""What a fast acting switch must meet (Clauss & Papalambros 1982): the spring within
its wire's strength (R14/R15), the crank's initial angle within the arcing limit (R4),
the joint load within its rating (R20), an underdamped closure (R19) and every constraint
of the full model (R1-R21). Limits from the run's ``[case]``."""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

from camopt.core.requirements import Requirement


def requirements(case: Mapping[str, Any], names: Collection[str]) -> tuple[Requirement, ...]:
    """The requirements of a ``fast_switch`` run's designs."""
    return (
        Requirement("spring stress margin below wire strength", "spring_stress_margin_pct",
                    "%", lower=0.0, source="R14/R15, Eqs 22-23 (A d^-m)",
                    scale=100.0),  # the margin is -100 R14/R15: the constraints' scale
        Requirement("initial crank angle (arcing limit)", "theta20_deg", "deg",
                    upper=float(case["max_initial_angle_deg"]),
                    source="R4, Eq 9 (config max_initial_angle_deg)"),
        Requirement("joint load", "joint_load_n", "N", upper=float(case["max_joint_load_n"]),
                    source="R20, Eq 41 (config max_joint_load_n)"),
        Requirement("damping ratio", "xi", "", upper=1.0, source="R19, Eq 40"),
        Requirement("full model's constraints R1-R21 met", "full_model_feasible", flag=True,
                    source="Sec 2, R1-R21", failing="violates the full model (R1-R21)"),
    )
