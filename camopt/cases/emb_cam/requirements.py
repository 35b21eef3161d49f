"""What an EMB cam must meet (Yan, Chen, Yan & Hang 2023): the clamping lift x1 + x2
within its tolerance, Hertz contact stress below the allowable, no distortion of the
roller's path (Eq 28), and the options the run's ``[case]`` sets (rotation cap of Eq 45,
clearance angle of Sec 4.4)."""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from typing import Any

from camopt.core.requirements import Requirement


def requirements(case: Mapping[str, Any], names: Collection[str]) -> tuple[Requirement, ...]:
    """The requirements of an ``emb_cam`` run's designs."""
    lift = float(case["clearance_mm"]) + float(case["deformation_mm"])
    tol = float(case["lift_tolerance_mm"])
    reqs = [
        Requirement("lift (clearance + deformation)", "lift_mm", "mm", lift - tol, lift + tol,
                    source="Sec 3.1 x1 + x2; ± config lift_tolerance_mm",
                    failing="the clamping force is off"),
        Requirement("contact stress", "contact_stress_max_mpa", "MPa",
                    upper=float(case["allowable_stress_mpa"]),
                    source="Eq 28 [σ]H (config allowable_stress_mpa)"),
        Requirement("profile curvature radius", "curvature_max_mm", "mm",
                    upper=float(case["r_g_mm"]), source="Eq 28 (config r_g_mm)"),
    ]
    if case.get("screw_lead_mm"):
        reqs.append(Requirement("rotation", "max_rotation_rad", "rad",
                                upper=2 * math.pi * lift / float(case["screw_lead_mm"]),
                                source="Eq 45 (config screw_lead_mm)"))
    if case.get("clearance_angle_max_rad") is not None:
        reqs.append(Requirement("clearance angle", "clearance_angle_rad", "rad",
                                upper=float(case["clearance_angle_max_rad"]),
                                source="Sec 4.4 (config clearance_angle_max_rad)"))
    return tuple(reqs)
