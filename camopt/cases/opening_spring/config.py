"""``[case]`` of the 40 kA VCB opening spring (Ahn, Cho, Park & Kim)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from camopt.config.models import Bounds, CaseConfig, Plausible, Positive

# Physical ranges of a breaker's opening mechanism (distribution to transmission class): a
# value outside is a unit slip (metres into mm, s into ms) or a typo; run.check_plausibility
# = false accepts it.
Length = Annotated[float, Plausible(-5000.0, 5000.0)]
Time = Annotated[float, Plausible(0.0, 1000.0)]
Gap = Annotated[Positive, Plausible(0.1, 1000.0)]
Stiffness = Annotated[Positive, Plausible(1e-3, 1e5)]
FreeLength = Annotated[Positive, Plausible(1.0, 5000.0)]
Inertia = Annotated[Positive, Plausible(1e-6, 1000.0)]
Force = Annotated[float, Plausible(-1e6, 1e6)]
Mass = Annotated[float, Plausible(0.0, 1000.0)]
Arm = Annotated[float, Plausible(0.0, 5000.0)]
Gravity = Annotated[float, Plausible(0.0, 100.0)]


class OpeningSpringConfig(CaseConfig):
    """40 kA VCB opening spring by the energy method, Ahn, Cho, Park & Kim."""

    kind: Literal["opening_spring"] = "opening_spring"
    mode: Literal["design", "identify"] = Field(
        "design", description="design: solve spring parameters; identify: solve the lumped "
        "inertia and self-closing force from a published design (camopt option)")
    free: list[str] = Field(
        ["k_n_per_mm", "l0_mm"], description="parameters to solve for (the others are fixed "
        "at the values below) (camopt option)")
    desired_coefficients: list[float] = Field(
        [-0.105, 3.42, 2.34e2, -2.53e3], description="Eq 7: theta(t) = c0 + c1 t + c2 t^2 + "
        "c3 t^3, t in s")
    t0_ms: Time = Field(15.85, description="Eq 6: contact separation")
    ts_ms: Time = Field(25.80, description="Eq 6: contacts 10 mm apart")
    gap_mm: Gap = Field(10.0, description="Eq 6: contact gap D")
    lever_arm_mm: Positive | None = Field(
        None, description="contact lever d; None derives it from Eq 6 (gap reached at ts)")
    precision_points_ms: list[float] = Field(
        [15.85, 24.85, 25.80], description="times on Eq 7 of the precision points; the first "
        "is the initial point")
    # spring design (Table 1 'original' by default)
    k_n_per_mm: Stiffness = Field(14.59, description="stiffness of each of the two springs "
                                  "(Table 1)")
    l0_mm: FreeLength = Field(128.0, description="free length (Table 1)")
    u_mm: Length = Field(83.0, description="ground point A, x (Table 1)")
    v_mm: Length = Field(207.0, description="ground point A, y (Table 1)")
    s_mm: Length = Field(135.0, description="link point B along OD (Table 1)")
    t_mm: Length = Field(0.0, description="link point B across OD (Sec 4.3: zero)")
    spring_count: int = Field(2, ge=1, le=100, description="symmetric opening springs (Table 1)")
    # lumped dynamics (not in the paper; identified or assumed, docs/assumptions.md)
    inertia_kg_m2: Inertia = Field(0.5436, description="I_o of the follower about O (identified: "
                                   "configs/opening_spring_identify.toml)")
    self_closing_force_n: Force = Field(
        210.4, description="F_r per contact; positive resists opening (identified: "
        "configs/opening_spring_identify.toml)")
    contact_mass_kg: Mass = Field(1.5, ge=0,
                                  description="m_c, one moving contact assembly (assumed)")
    contact_count: int = Field(3, ge=1, le=100, description="three phases (three-phase breaker)")
    follower_mass_kg: Mass = Field(0.0, ge=0, description="m_f (lumped into I_o if 0) (assumed)")
    follower_centroid_mm: Arm = Field(0.0, ge=0, description="C_f (assumed)")
    follower_centroid_deg: float = Field(0.0, description="psi = angle C_f O B (assumed)")
    gravity: Gravity = Field(9.81, ge=0, description="m/s^2 (standard gravity)")
    regularization: float = Field(
        0.0, ge=0, description="weight of a pull toward the original design (pins the "
        "least-squares optimum) (camopt option)")
    original: dict[str, float] = Field(
        {"k_n_per_mm": 14.59, "l0_mm": 128.0, "u_mm": 83.0, "v_mm": 207.0, "s_mm": 135.0},
        description="Table 1 original design (regularisation target and comparison)")
    compare_designs: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="more designs to simulate beside this one, "
        "{label = {k_n_per_mm = ..., ...}}; unlisted parameters take the values above "
        "(camopt option)")
    k_bounds_n_per_mm: Bounds = Field(Bounds(lower=5, upper=60), description="search bounds "
                                                                             "(search range)")
    l0_bounds_mm: Bounds = Field(Bounds(lower=50, upper=250), description="search bounds "
                                                                          "(search range)")
    u_bounds_mm: Bounds = Field(Bounds(lower=0, upper=200), description="search bounds "
                                                                        "(search range)")
    v_bounds_mm: Bounds = Field(Bounds(lower=100, upper=300), description="search bounds "
                                                                          "(search range)")
    s_bounds_mm: Bounds = Field(Bounds(lower=60, upper=200), description="search bounds "
                                                                         "(search range)")
    inertia_bounds_kg_m2: Bounds = Field(Bounds(lower=0.01, upper=5),
                                         description="identify (search range)")
    self_closing_bounds_n: Bounds = Field(Bounds(lower=-2000, upper=2000),
                                          description="identify (search range)")

    @model_validator(mode="after")
    def _check(self) -> OpeningSpringConfig:
        known = {"k_n_per_mm", "l0_mm", "u_mm", "v_mm", "s_mm", "inertia_kg_m2",
                 "self_closing_force_n"}
        unknown = [n for n in self.free if n not in known]
        if unknown:
            raise ValueError(f"free: unknown parameter {unknown[0]!r}; known: "
                             f"{', '.join(sorted(known))}")
        if len(self.precision_points_ms) < 2:
            raise ValueError("precision_points_ms: give at least two points")
        if len(self.desired_coefficients) != 4:
            raise ValueError("desired_coefficients: four values (Eq 7)")
        return self
