"""``[case]`` of the EMB negative-radius roller cam (Yan, Chen, Yan & Hang 2023)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from camopt.config.models import AsTuple, Bounds, CaseConfig, Plausible, Positive

# Physical ranges of a brake cam (a bicycle brake to a truck's): a value outside is a unit
# slip (metres into mm) or a typo; run.check_plausibility = false accepts it.
SmallLength = Annotated[Positive, Plausible(1e-3, 100.0)]
Length = Annotated[Positive, Plausible(0.1, 1000.0)]
Stress = Annotated[Positive, Plausible(10.0, 10_000.0)]


class EmbCamConfig(CaseConfig):
    """EMB negative-radius roller cam, Yan, Chen, Yan & Hang (2023)."""

    kind: Literal["emb_cam"] = "emb_cam"
    clearance_mm: SmallLength = Field(1.0, description="x1, brake clearance (Sec 3.1)")
    deformation_mm: SmallLength = Field(1.0, description="x2, caliper deformation at full force "
        "(Sec 3.1)")
    k_kn_per_mm3: Annotated[Positive, Plausible(1e-3, 1e6)] = Field(
        50.0, description="K in F = K (s - x1)^3; the text's kN/mm is a misprint (Sec 3.1)")
    r_st_mm: Length = Field(15.0, description="initial polar radius (Sec 3.1)")
    r_g_mm: Length = Field(20.0, description="inner radius of the driven bearing (Sec 3.1)")
    key_points: int = Field(10, ge=4, le=40, description="N, spline key points (assumed)")
    samples_per_segment: int = Field(40, ge=4, le=1000,
                                     description="profile samples between key points (assumed, "
        "docs/assumptions.md)")
    weights: list[float] = Field(
        [1.0, 0.02, 1.0, 0.05, 0.2, 1.0],
        description="w1..w6 of Eq 27: clearance angle (rad), torque-slope variance "
        "((N m/rad)^2), peak torque (N m), curvature steps (mm), tan alpha before and after "
        "the clearance is taken up (assumed)")
    allowable_stress_mpa: Stress = Field(2500.0, description="[sigma]_H (assumed)")
    z_e_sqrt_mpa: Positive = Field(189.8, description="Z_E for steel on steel (handbook value)")
    contact_length_mm: Length = Field(20.0, description="L, contact line length (assumed)")
    lift_tolerance_mm: Positive = Field(
        0.002, description="|s(end) - s_max| allowed: the paper's 2 mm held to +-0.002 mm by "
        "default; a looser value (e.g. 0.01) lets the clamping force drop with the lift "
        "(K x2^3: -3 % at 0.99 mm) and so flatters the torque (assumed, docs/assumptions.md)")
    screw_lead_mm: Length | None = Field(
        2.40, description="cap the rotation at that of this ball-screw lead (Eq 45); None: none")
    clearance_angle_max_rad: Positive | None = Field(
        1.72, description="cap on the clearance-elimination angle: the paper's design's "
        "(Sec 4.4); unset: no cap")
    torque_ramp_rms_max_pct: Positive | None = Field(
        None, description="optional cap on the torque's RMS deviation from a straight line "
        "over the clamping section, % of the peak (beyond the paper: configs/emb_linear.toml)")
    knot_density: Annotated[tuple[float, float, float], AsTuple] | None = Field(
        None, description="None: key points evenly spaced in profile angle (Eq 25); "
        "[centre, peak, width]: their density peaks 'peak' times higher around the fraction "
        "'centre' of the profile (Gaussian of that width)")
    penalty_p1: float = Field(100.0, ge=0, description="P1 of Eq 30")
    penalty_p2: float = Field(100.0, ge=0, description="P2 of Eq 30 (per unit of err)")
    kappa_bounds: Bounds | None = Field(
        None, description="initial tangent angle (rad); None: [0, acos(r_st / 2 r_g)] (Eq 21)")
    offset_bounds_mm: Bounds = Field(Bounds(lower=0, upper=20), description="e, 0 < e < r_g "
        "(Sec 3.3)")
    radius_bounds_mm: Bounds | None = Field(
        None, description="key radii; None: [r_st, 2 r_g] (repair keeps r_j < r_g + e) "
                          "(search range)")
