"""What a VCB closing mechanism must meet (Kang, Huang & Yang 2023), whatever the run
optimised: the breaker's rod travel, the follower swing of Eq 40, the cam's contact stress
below shear yield, no undercut, the allowable pressure angle, a closing velocity of
0.9 +- 0.2 m/s (Sec 2.1) and a stroke that latches. Limits come from the run's ``[case]``
where it holds them, else from the paper."""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

from camopt.cases.vcb.config import (
    LATCH_ENERGY_MAX_J,
    LIFT_OFF_FRACTION_MIN,
    PRELOAD_SETTING_RANGE_MM,
    RELEASE_TORQUE_MARGIN_MIN,
)
from camopt.core.requirements import Requirement

CLOSING_VELOCITY_M_S = (0.7, 1.1)  # Sec 2.1: 0.9 +- 0.2 m/s
PRESSURE_ANGLE_MAX_DEG = 45.0  # Sec 2.3: allowable pressure angle


def requirements(case: Mapping[str, Any], names: Collection[str]) -> tuple[Requirement, ...]:
    """The requirements of a ``vcb`` run's designs; ``names`` are the quantities its
    designs report (the closing-velocity band is read from its low and high ends when the
    dynamics report them, else from the average)."""
    travel, tol = float(case["rod_travel_mm"]), float(case["rod_travel_tolerance_mm"])
    lo_v, hi_v = case.get("closing_velocity_m_s") or CLOSING_VELOCITY_M_S
    v_source = ("config closing_velocity_m_s" if case.get("closing_velocity_m_s")
                else "Sec 2.1: 0.9 ± 0.2 m/s")
    psi = case.get("pressure_angle_max_deg")
    reqs = [
        Requirement("cam latches at the end of the stroke", "latched", flag=True,
                    source="Sec 3.2: the breaker closes and latches",
                    failing="does not latch (the cam stalls before the end of its stroke)"),
        Requirement("rod travel", "rod_travel_mm", "mm", travel - tol, travel + tol,
                    source="Sec 3.2; ± config rod_travel_tolerance_mm",
                    failing="the breaker's stroke changes"),
    ]
    if "closing_velocity_low_m_s" in names and "closing_velocity_high_m_s" in names:
        reqs += [Requirement("closing velocity, low end", "closing_velocity_low_m_s", "m/s",
                             lower=float(lo_v), source=v_source),
                 Requirement("closing velocity, high end", "closing_velocity_high_m_s", "m/s",
                             upper=float(hi_v), source=v_source)]
    else:
        reqs.append(Requirement("average closing velocity", "closing_velocity_avg_m_s", "m/s",
                                float(lo_v), float(hi_v), source=v_source))
    reqs += [
        Requirement("cam contact shear stress", "tau_max_mpa", "MPa",
                    upper=float(case["shear_yield_mpa"]),
                    source="Table 1 shear yield, Eq 31 (config shear_yield_mpa)"),
        Requirement("follower swing", "phi_max_deg", "deg", float(case["phi_max_deg"][0]),
                    float(case["phi_max_deg"][1]), source="Eq 40 (config phi_max_deg)"),
        Requirement("pressure angle", "pressure_angle_max_deg", "deg",
                    upper=float(psi if psi is not None else PRESSURE_ANGLE_MAX_DEG),
                    source="config pressure_angle_max_deg" if psi is not None
                    else "Sec 2.3: allowable 45 deg"),
        Requirement("cam curvature radius, convex part (no undercut)", "curvature_min_mm",
                    "mm",
                    lower=float(case["rf_mm"]), source="Sec 2.3: > roller radius rf_mm"),
    ]
    if case.get("require_latch") and case.get("latch_energy_min_j"):
        low = "latch_kinetic_energy_low_j" in names  # the band's least, when reported
        reqs.append(Requirement("kinetic energy left to latch" + (", low end" if low else ""),
                                "latch_kinetic_energy_low_j" if low
                                else "latch_kinetic_energy_j", "J",
                                lower=float(case["latch_energy_min_j"]),
                                source="config latch_energy_min_j (assumed)"))
    reqs += dynamic_requirements(case, names)
    return tuple(reqs)


def dynamic_requirements(case: Mapping[str, Any], names: Collection[str]
                         ) -> list[Requirement]:
    """What the closing dynamics must show whether or not the run searched for it: the
    closing springs start the cam with a margin over the friction at the release (the
    band's least ratio where a band is reported), and the cam keeps pressing the roller
    (least cam torque a share of the mean driving torque). None without the dynamics."""
    reqs = []
    if "band_sets_not_latched" in names:
        reqs.append(Requirement(
            "band sets in which the cam does not close",
            "band_sets_not_latched", upper=0.0, count=True,
            source="every kept model form and set (docs/assumptions.md)",
            failing="the closing depends on which model form or parameter set is right"))
    high = "latch_kinetic_energy_high_j" in names
    if high or "latch_kinetic_energy_j" in names:
        reqs.append(Requirement(
            "latch energy to absorb" + (", high end" if high else ""),
            "latch_kinetic_energy_high_j" if high else "latch_kinetic_energy_j", "J",
            upper=float(case.get("latch_energy_max_j", LATCH_ENERGY_MAX_J)),
            source="config latch_energy_max_j (assumed)",
            failing="the prop and stop take more than they are assumed to absorb"))
    if "release_torque_margin" in names:
        low = "release_torque_margin_low" in names
        reqs.append(Requirement(
            "release torque / friction" + (", low end" if low else ""),
            "release_torque_margin_low" if low else "release_torque_margin",
            lower=float(case.get("release_torque_margin_min", RELEASE_TORQUE_MARGIN_MIN)),
            source="config release_torque_margin_min (assumed)",
            failing="a slightly soft spring or stiff bearing keeps the cam at its release"))
    if "pickup_tau_mpa" in names:
        reqs.append(Requirement(
            "pick-up impact shear stress (cam on roller)", "pickup_tau_mpa", "MPa",
            upper=float(case["shear_yield_mpa"]),
            source="Eq 31 at the impact's Hertz peak force, band's worst (docs/assumptions.md)",
            failing="the cam's blow on the resting roller yields the contact"))
    if "preload_setting_mm" in names:
        reach = float(case.get("preload_setting_range_mm", PRELOAD_SETTING_RANGE_MM))
        reqs.append(Requirement(
            "closing springs' factory setting (nut travel)", "preload_setting_mm", "mm",
            -reach, reach, source="config preload_setting_range_mm (assumed)",
            failing="the nut cannot set the breaker to its reference closing velocity"))
    if "lift_off_torque_ratio" in names:
        reqs.append(Requirement(
            "least cam torque / mean drive (lift-off)", "lift_off_torque_ratio",
            lower=float(case.get("lift_off_fraction_min", LIFT_OFF_FRACTION_MIN)),
            source="config lift_off_fraction_min (assumed)",
            failing="the roller comes near to lifting off the cam"))
    return reqs
