"""``[case]`` of the fast acting switch (Clauss & Papalambros 1982): Nomenclature parameters."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camopt.config.models import Bounds, CaseConfig, Plausible, Positive

# Physical ranges of a switch of this family (a bench-top to a substation switch): a value
# outside is a unit slip (metres into mm) or a typo; run.check_plausibility = false accepts it.
Length = Annotated[Positive, Plausible(1.0, 5000.0)]
Mass = Annotated[Positive, Plausible(1e-3, 1000.0)]
WireDiameter = Annotated[Positive, Plausible(0.1, 50.0)]
Stress = Annotated[Positive, Plausible(10.0, 10_000.0)]
Modulus = Annotated[Positive, Plausible(1.0, 1000.0)]
Load = Annotated[Positive, Plausible(1.0, 1e7)]
# the family is enumerated coil by coil; a helical spring beyond 1000 coils is not a spring
MAX_COILS = 1000


class FastSwitchConfig(CaseConfig):
    """Fast acting switch, Clauss & Papalambros (1982): Nomenclature parameters."""

    kind: Literal["fast_switch"] = "fast_switch"
    link2_length_mm: Length = Field(200.0, description="L, total length of link 2 (paper's "
        "Nomenclature)")
    half_piston_mm: Length = Field(50.0, description="p4, one-half piston length (paper's "
        "Nomenclature)")
    m2_kg: Mass = Field(0.5, description="M2, mass of part 2 (paper's Nomenclature)")
    m3_kg: Mass = Field(0.75, description="M3, mass of part 3 (paper's Nomenclature)")
    m4_kg: Mass = Field(0.5, description="M4, mass of part 4 (piston) (paper's Nomenclature)")
    spring_diameter_mm: Length = Field(20.0, description="D, spring coil diameter (paper's "
        "Nomenclature)")
    wire_diameter_mm: WireDiameter = Field(2.0, description="d, spring wire diameter (paper's "
        "Nomenclature)")
    wire_strength_a_mpa: Stress = Field(1880.0, description="A, wire strength coefficient "
        "(paper's Nomenclature)")
    wire_strength_exponent: float = Field(0.186, ge=0, lt=1, description="m, strength exponent "
        "(paper's Nomenclature)")
    wire_strength_d_unit: Literal["m", "mm"] = Field(
        "m",
        description="unit of d inside A*d**-m; 'm' reproduces Table 1, 'mm' is Shigley's "
        "(see docs/assumptions.md)",
    )
    shear_modulus_gpa: Modulus = Field(
        207.0, description="G as printed (207 GPa reproduces Table 1; steel is about 79 GPa)"
    )
    max_initial_angle_deg: float = Field(
        30.0, gt=0, le=90, description="W, largest initial angle of part 2 (arcing) "
                                       "(paper's Nomenclature)"
    )
    max_joint_load_n: Load = Field(1500.0, description="F_rated, joint strength (paper's "
        "Nomenclature)")
    min_coils: int = Field(3, ge=1, le=MAX_COILS, description="practical least number of coils "
        "(assumed)")
    max_coils: int = Field(42, ge=1, le=MAX_COILS,
                           description=f"largest coil count searched (at most {MAX_COILS}) "
                           "(camopt option)")
    branch: Literal["I", "II", "both"] = Field(
        "both", description="sign of sf - sud allowed: I (sf >= sud), II (sf <= sud) or both "
                            "(Monotonicity Analysis: the paper's cases I and II)"
    )
    reduced_form: Literal["corrected", "printed"] = Field(
        "corrected",
        description="7-variable statement: 'printed' as in the paper (has errors), or "
        "'corrected' (loop equations solved exactly, right arcsine branch) (camopt option)",
    )
    sf_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x3 search bounds "
                                                                         "(search range)")
    sud_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x4 search bounds "
                                                                          "(search range)")
    s0_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x5 search bounds "
                                                                         "(search range)")
    r3_bounds_mm: Bounds = Field(Bounds(lower=10, upper=600), description="x6 search bounds "
                                                                          "(search range)")
    r2_bounds_mm: Bounds = Field(Bounds(lower=1, upper=200), description="x7 search bounds "
                                                                         "(search range)")

    @model_validator(mode="after")
    def _coils_ordered(self) -> FastSwitchConfig:
        if self.min_coils >= self.max_coils:
            raise ValueError(f"min_coils {self.min_coils} must be below max_coils {self.max_coils}")
        return self
