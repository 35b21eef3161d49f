"""Pydantic models of a case file: ``[case]``, ``[solver]`` and ``[run]``.

Units: a field whose name ends in ``_mm``, ``_deg``, ``_kg``, ``_gpa`` ... is in
that unit; everything else is SI or unitless. Cases convert to SI when they
build their Problem.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Positive = Annotated[float, Field(gt=0)]


class Strict(BaseModel):
    """Base of every config model: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class Bounds(Strict):
    """A closed interval ``[lower, upper]`` with ``lower < upper``."""

    lower: float
    upper: float

    @model_validator(mode="before")
    @classmethod
    def _from_pair(cls, value: object) -> object:
        if isinstance(value, (list, tuple)):
            if len(value) != 2:
                raise ValueError("bounds must be a pair [lower, upper]")
            return {"lower": value[0], "upper": value[1]}
        return value

    @model_validator(mode="after")
    def _ordered(self) -> Bounds:
        if not self.lower < self.upper:
            raise ValueError(f"lower bound {self.lower} must be below upper bound {self.upper}")
        return self

    def as_list(self) -> list[float]:
        return [self.lower, self.upper]


class RunSection(Strict):
    """``[run]``: naming, seeding and repeats of a run."""

    name: str = Field("run", description="name of the run; the archive is runs/<name>-<time>.h5")
    seed: int = Field(0, ge=0, description="root seed; repeats get SeedSequence(seed).spawn(n)")
    repeats: int = Field(1, ge=1, description="independent repeats of the solver")
    target: float | None = Field(
        None, description="objective at or below which a feasible repeat counts as a success"
    )
    min_success_rate: float | None = Field(
        None, ge=0, le=1, description="sweep --check fails below this success rate"
    )


class SolverOptions(Strict):
    """Base of every solver's options; ``name`` selects the solver."""

    name: str


class CaseConfig(Strict):
    """Base of every case's parameters; ``kind`` selects the case."""

    kind: str


class FastSwitchConfig(CaseConfig):
    """Fast acting switch, Clauss & Papalambros (1982): Nomenclature parameters."""

    kind: Literal["fast_switch"] = "fast_switch"
    link2_length_mm: Positive = Field(200.0, description="L, total length of link 2")
    half_piston_mm: Positive = Field(50.0, description="p4, one-half piston length")
    m2_kg: Positive = Field(0.5, description="M2, mass of part 2")
    m3_kg: Positive = Field(0.75, description="M3, mass of part 3")
    m4_kg: Positive = Field(0.5, description="M4, mass of part 4 (piston)")
    spring_diameter_mm: Positive = Field(20.0, description="D, spring coil diameter")
    wire_diameter_mm: Positive = Field(2.0, description="d, spring wire diameter")
    wire_strength_a_mpa: Positive = Field(1880.0, description="A, wire strength coefficient")
    wire_strength_exponent: float = Field(0.186, ge=0, lt=1, description="m, strength exponent")
    wire_strength_d_unit: Literal["m", "mm"] = Field(
        "m",
        description="unit of d inside A*d**-m; 'm' reproduces Table 1, 'mm' is Shigley's "
        "(see docs/assumptions.md)",
    )
    shear_modulus_gpa: Positive = Field(
        207.0, description="G as printed (207 GPa reproduces Table 1; steel is about 79 GPa)"
    )
    max_initial_angle_deg: float = Field(
        30.0, gt=0, le=90, description="W, largest initial angle of part 2 (arcing)"
    )
    max_joint_load_n: Positive = Field(1500.0, description="F_rated, joint strength")
    min_coils: int = Field(3, ge=1, description="practical least number of coils")
    max_coils: int = Field(42, ge=1, description="largest coil count searched")
    branch: Literal["I", "II", "both"] = Field(
        "both", description="sign of sf - sud allowed: I (sf >= sud), II (sf <= sud) or both"
    )
    reduced_form: Literal["corrected", "printed"] = Field(
        "corrected",
        description="7-variable statement: 'printed' as in the paper (has errors), or "
        "'corrected' (loop equations solved exactly, right arcsine branch)",
    )
    sf_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x3 search bounds")
    sud_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x4 search bounds")
    s0_bounds_mm: Bounds = Field(Bounds(lower=1, upper=400), description="x5 search bounds")
    r3_bounds_mm: Bounds = Field(Bounds(lower=10, upper=600), description="x6 search bounds")
    r2_bounds_mm: Bounds = Field(Bounds(lower=1, upper=200), description="x7 search bounds")

    @model_validator(mode="after")
    def _coils_ordered(self) -> FastSwitchConfig:
        if self.min_coils >= self.max_coils:
            raise ValueError(f"min_coils {self.min_coils} must be below max_coils {self.max_coils}")
        return self


Pair = tuple[float, float]


class CamDesign(Strict):
    """A step-1 design: cubic coefficients (rad, per rad^k) and closing spring rates."""

    a0: float | None = Field(None, description="phi at theta_c = 0; None: from Eq 8")
    a1: float
    a2: float
    a3: float
    kc1_n_per_mm: Positive
    kc2_n_per_mm: Positive


class VcbConfig(CaseConfig):
    """12 kV VCB cam-linkage closing mechanism, Kang, Huang & Yang (2023)."""

    kind: Literal["vcb"] = "vcb"
    step: Literal["cam", "fourbar"] = Field(
        "cam", description="cam: a1, a2, a3, kc1, kc2 (Eq 37); fourbar: l1, l3, l4, l5, "
        "theta1 (Eq 41)")
    # four-bar and pivots (Sec 2.3)
    l1_mm: Positive = Field(139.79, description="fixed link BE")
    l2_mm: Positive = Field(70.0, description="follower (input) link BD")
    l3_mm: Positive = Field(124.7, description="coupler DL")
    l4_mm: Positive = Field(140.0, description="output arm EL")
    l5_mm: Positive = Field(90.0, description="output arm EM to the insulated rod")
    theta1_deg: float = Field(-121.98, description="fixed-link angle (Table 7 initial)")
    pivot_b_mm: Pair = Field((-72.0, -55.0), description="follower pivot B (cam pivot O at 0,0)")
    pivot_g_mm: Pair = Field((50.0, 200.0), description="closing springs' fixed end G")
    crank_l8_mm: Positive = Field(25.0, description="closing springs' crank OQ on the cam shaft")
    preset_qox_deg: float = Field(95.0, description="angle QOX in the opened state")
    rod_arm_offset_deg: float = Field(
        0.0, description="angle of EM from the extension of LE beyond E (identified)")
    # cam (Sec 2.2-2.3)
    rb_mm: Positive = Field(23.0, description="base circle radius")
    rf_mm: Positive = Field(15.0, description="roller radius")
    alpha: Positive = Field(0.95, description="loss coefficient of contact (Eq 1)")
    beta_mm: float = Field(2.0, ge=0, description="cam-roller clearance (Eq 1)")
    gamma_mm: float = Field(1.0, ge=0, description="hook-roller clearance (Eq 1)")
    node_clearance_mm: float = Field(
        1.0, ge=0, description="clearance in Eqs 2 and 8 that reproduces a0..a3 (not beta)")
    theta0_deg: float = Field(4.0, ge=0, description="pre-rotation before contact")
    s1_bar_mm: Positive = Field(16.0, description="overall displacement of M (Eq 1)")
    node_cam_deg: list[float] = Field([0.0, 70.0, 100.0, 140.0], description="theta_ci (Fig 4)")
    node_fractions: list[float] = Field([0.0, 0.7, 0.9, 1.0], description="s2i / s2bar (Fig 4)")
    # springs and loads (Table 2, Sec 3.2)
    kc1_n_per_mm: Positive = Field(7.72, description="vendor closing spring 1")
    kc2_n_per_mm: Positive = Field(9.33, description="vendor closing spring 2")
    kc1_precompression_mm: Positive = Field(140.0, description="spring 1, opened state")
    kc2_precompression_mm: Positive = Field(100.0, description="spring 2, opened state")
    opening_k_n_per_mm: Positive = Field(16.6, description="opening spring")
    opening_stretch_closed_mm: Positive = Field(33.6, description="opening spring, closed state")
    opening_arm_ratio: Positive = Field(
        1.0, description="opening-spring elongation per mm of rod travel, r7/r6 (identified)")
    wipe_k_n_per_mm: Positive = Field(82.4, description="one contact (wipe) spring")
    wipe_count: int = Field(3, ge=1, description="contact springs, one per phase")
    wipe_compression_closed_mm: Positive = Field(17.0, description="closed state, vendor")
    contact_gap_mm: Positive = Field(11.0, description="rod travel where contacts touch")
    free_contact_force_n: float = Field(
        0.0, description="self-closing force of the interrupters before touch (identified)")
    efficiency: float = Field(0.85, gt=0, le=1, description="mechanical efficiency (Eq 26)")
    # contact stress (Table 1, Eqs 27-31)
    cam_modulus_gpa: Positive = Field(210.0, description="E of cam and roller (S45C)")
    poisson: float = Field(0.3, ge=0, lt=0.5, description="Poisson's ratio")
    contact_length_mm: Positive = Field(15.0, description="cam-roller contact length")
    shear_yield_mpa: Positive = Field(1194.0, description="tau_y = 0.577 sigma_y")
    stress_constraint: bool = Field(True, description="require tau_max <= shear_yield")
    # objective (Eqs 39-40)
    objective_form: Literal["net", "abs_sum"] = Field(
        "net", description="net: |sum (Fo - Fr/eps) ds| in J; abs_sum: sum |Fo - Fr/eps| "
        "in N, as printed")
    positions: int = Field(140, ge=10, description="Ns, cam positions over 0-140 deg")
    penalty: float = Field(1e6, ge=0, description="M in Eq 39")
    phi_max_deg: Pair = Field((23.0, 26.0), description="bounds on the follower's maximum angle")
    # search bounds
    a1_bounds: Bounds = Field(Bounds(lower=0, upper=0.5), description="Eq 38")
    a2_bounds: Bounds = Field(Bounds(lower=0, upper=0.5), description="Eq 38")
    a3_bounds: Bounds = Field(Bounds(lower=-0.5, upper=0), description="Eq 38")
    kc1_bounds_n_per_mm: Bounds = Field(Bounds(lower=4, upper=10), description="see assumptions")
    kc2_bounds_n_per_mm: Bounds = Field(Bounds(lower=4, upper=10), description="see assumptions")
    l1_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l3_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l4_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l5_bounds_mm: Bounds = Field(Bounds(lower=50, upper=100), description="Eq 42")
    theta1_bounds_deg: Bounds = Field(Bounds(lower=-180, upper=-90), description="Eq 42")
    cam_design: CamDesign | None = Field(None, description="step-1 design used by step 2")
    cam_archive: str | None = Field(
        None, description="run archive whose best design is the step-1 design (step 2)")

    @model_validator(mode="after")
    def _nodes(self) -> VcbConfig:
        if len(self.node_cam_deg) != 4 or len(self.node_fractions) != 4:
            raise ValueError("node_cam_deg and node_fractions need four values (Eq 7)")
        if self.phi_max_deg[0] >= self.phi_max_deg[1]:
            raise ValueError("phi_max_deg: lower bound must be below upper bound")
        return self


class VcbIdentifyConfig(VcbConfig):
    """Fit the VCB parameters the paper leaves out to the results it reports."""

    kind: Literal["vcb_identify"] = "vcb_identify"  # type: ignore[assignment]
    rod_travel_target_mm: Positive = Field(18.0, description="Sec 3.2: rod travel 18 mm")
    rod_travel_tolerance_mm: Positive = Field(0.5, description="scale of the travel residual")
    vendor_surplus_target_j: float = Field(
        1.75, description="Table 6 vendor objective 1.75e3, read as N mm")
    optimum_surplus_target_j: float = Field(0.0, description="Table 6 optimum: 1.74e-7")
    paper_optimum: CamDesign = Field(
        CamDesign(a1=0.238432, a2=0.000226, a3=-0.011492, kc1_n_per_mm=9.315336,
                  kc2_n_per_mm=7.788183), description="Table 6 DE-gr design")
    rod_offset_bounds_deg: Bounds = Field(Bounds(lower=-15, upper=15), description="unknown")
    opening_arm_bounds: Bounds = Field(
        Bounds(lower=0.1, upper=1.85), description="r7/r6; above 1.86 the opening spring "
        "would be compressed in the opened state")
    free_contact_bounds_n: Bounds = Field(
        Bounds(lower=0, upper=1000), description="self-closing force of three interrupters; "
        "it helps closing, so not negative")


class OpeningSpringConfig(CaseConfig):
    """40 kA VCB opening spring by the energy method, Ahn, Cho, Park & Kim."""

    kind: Literal["opening_spring"] = "opening_spring"
    mode: Literal["design", "identify"] = Field(
        "design", description="design: solve spring parameters; identify: solve the lumped "
        "inertia and self-closing force from a published design")
    free: list[str] = Field(
        ["k_n_per_mm", "l0_mm"], description="parameters to solve for (the others are fixed "
        "at the values below)")
    desired_coefficients: list[float] = Field(
        [-0.105, 3.42, 2.34e2, -2.53e3], description="Eq 7: theta(t) = c0 + c1 t + c2 t^2 + "
        "c3 t^3, t in s")
    t0_ms: float = Field(15.85, description="Eq 6: contact separation")
    ts_ms: float = Field(25.80, description="Eq 6: contacts 10 mm apart")
    gap_mm: Positive = Field(10.0, description="Eq 6: contact gap D")
    lever_arm_mm: Positive | None = Field(
        None, description="contact lever d; None derives it from Eq 6 (gap reached at ts)")
    precision_points_ms: list[float] = Field(
        [15.85, 24.85, 25.80], description="times on Eq 7 of the precision points; the first "
        "is the initial point")
    # spring design (Table 1 'original' by default)
    k_n_per_mm: Positive = Field(14.59, description="stiffness of each of the two springs")
    l0_mm: Positive = Field(128.0, description="free length")
    u_mm: float = Field(83.0, description="ground point A, x")
    v_mm: float = Field(207.0, description="ground point A, y")
    s_mm: float = Field(135.0, description="link point B along OD")
    t_mm: float = Field(0.0, description="link point B across OD (Sec 4.3: zero)")
    spring_count: int = Field(2, ge=1, description="symmetric opening springs")
    # lumped dynamics (not in the paper; identified or assumed, docs/assumptions.md)
    inertia_kg_m2: Positive = Field(0.5436, description="I_o of the follower about O")
    self_closing_force_n: float = Field(
        210.4, description="F_r per contact; positive resists opening")
    contact_mass_kg: float = Field(1.5, ge=0, description="m_c, one moving contact assembly")
    contact_count: int = Field(3, ge=1, description="three phases")
    follower_mass_kg: float = Field(0.0, ge=0, description="m_f (lumped into I_o if 0)")
    follower_centroid_mm: float = Field(0.0, ge=0, description="C_f")
    follower_centroid_deg: float = Field(0.0, description="psi = angle C_f O B")
    gravity: float = Field(9.81, ge=0, description="m/s^2")
    regularization: float = Field(
        0.0, ge=0, description="weight of a pull toward the original design (pins the "
        "least-squares optimum)")
    original: dict[str, float] = Field(
        {"k_n_per_mm": 14.59, "l0_mm": 128.0, "u_mm": 83.0, "v_mm": 207.0, "s_mm": 135.0},
        description="Table 1 original design (regularisation target and comparison)")
    compare_designs: dict[str, dict[str, float]] = Field(
        default_factory=dict, description="more designs to simulate beside this one, "
        "{label = {k_n_per_mm = ..., ...}}; unlisted parameters take the values above")
    k_bounds_n_per_mm: Bounds = Field(Bounds(lower=5, upper=60), description="search bounds")
    l0_bounds_mm: Bounds = Field(Bounds(lower=50, upper=250), description="search bounds")
    u_bounds_mm: Bounds = Field(Bounds(lower=0, upper=200), description="search bounds")
    v_bounds_mm: Bounds = Field(Bounds(lower=100, upper=300), description="search bounds")
    s_bounds_mm: Bounds = Field(Bounds(lower=60, upper=200), description="search bounds")
    inertia_bounds_kg_m2: Bounds = Field(Bounds(lower=0.01, upper=5), description="identify")
    self_closing_bounds_n: Bounds = Field(Bounds(lower=-2000, upper=2000), description="identify")

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


class EmbCamConfig(CaseConfig):
    """EMB negative-radius roller cam, Yan, Chen, Yan & Hang (2023)."""

    kind: Literal["emb_cam"] = "emb_cam"
    clearance_mm: Positive = Field(1.0, description="x1, brake clearance (Sec 3.1)")
    deformation_mm: Positive = Field(1.0, description="x2, caliper deformation at full force")
    k_kn_per_mm3: Positive = Field(
        50.0, description="K in F = K (s - x1)^3; the text's kN/mm is a misprint")
    r_st_mm: Positive = Field(15.0, description="initial polar radius")
    r_g_mm: Positive = Field(20.0, description="inner radius of the driven bearing")
    key_points: int = Field(10, ge=4, le=40, description="N, spline key points (assumed)")
    samples_per_segment: int = Field(40, ge=4, description="profile samples between key points")
    weights: list[float] = Field(
        [1.0, 0.02, 1.0, 0.05, 0.2, 1.0],
        description="w1..w6 of Eq 27: clearance angle (rad), torque-slope variance "
        "((N m/rad)^2), peak torque (N m), curvature steps (mm), tan alpha before and after "
        "the clearance is taken up (assumed)")
    allowable_stress_mpa: Positive = Field(2500.0, description="[sigma]_H (assumed)")
    z_e_sqrt_mpa: Positive = Field(189.8, description="Z_E for steel on steel")
    contact_length_mm: Positive = Field(20.0, description="L, contact line length (assumed)")
    lift_tolerance_mm: Positive = Field(0.01, description="|s(end) - s_max| allowed")
    screw_lead_mm: Positive | None = Field(
        2.40, description="cap the rotation at that of this ball-screw lead (Eq 45); None: none")
    clearance_angle_max_rad: Positive | None = Field(
        None, description="optional cap on the clearance-elimination angle")
    torque_ramp_rms_max_pct: Positive | None = Field(
        None, description="optional cap on the torque's RMS deviation from a straight line "
        "over the clamping section, % of the peak")
    knot_density: tuple[float, float, float] | None = Field(
        None, description="None: key points evenly spaced in profile angle (Eq 25); "
        "[centre, peak, width]: their density peaks 'peak' times higher around the fraction "
        "'centre' of the profile (Gaussian of that width)")
    penalty_p1: float = Field(100.0, ge=0, description="P1 of Eq 30")
    penalty_p2: float = Field(100.0, ge=0, description="P2 of Eq 30 (per unit of err)")
    kappa_bounds: Bounds | None = Field(
        None, description="initial tangent angle (rad); None: [0, acos(r_st / 2 r_g)] (Eq 21)")
    offset_bounds_mm: Bounds = Field(Bounds(lower=0, upper=20), description="e, 0 < e < r_g")
    radius_bounds_mm: Bounds | None = Field(
        None, description="key radii; None: [r_st, 2 r_g] (repair keeps r_j < r_g + e)")


CASE_CONFIGS: dict[str, type[CaseConfig]] = {
    "fast_switch": FastSwitchConfig,
    "vcb": VcbConfig,
    "vcb_identify": VcbIdentifyConfig,
    "opening_spring": OpeningSpringConfig,
    "emb_cam": EmbCamConfig,
}


def _toml_value(value: object) -> str:
    """One TOML value on one line (tables inline, so every field stays a single line)."""
    import tomli_w

    if isinstance(value, BaseModel):
        value = value.model_dump(mode="json", exclude_none=True)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def _section(title: str, model: BaseModel) -> list[str]:
    lines = [f"[{title}]"]
    for name, info in type(model).model_fields.items():
        value = getattr(model, name)
        if isinstance(value, Bounds):
            value = value.as_list()
        if isinstance(value, dict) and not value:
            lines += [f"# {info.description}", f"# {name} = {{ }}"] if info.description else []
            continue
        if info.description:
            lines.append(f"# {info.description}")
        if value is None:
            lines.append(f"# {name} =   (unset)")
        else:
            lines.append(f"{name} = {_toml_value(value)}")
    return lines


def template(kind: str, solver: SolverOptions) -> str:
    """A commented case file for ``kind`` with every default written out."""
    case = CASE_CONFIGS[kind]()
    lines = [f"# camopt case file for '{kind}'. Units are in the field names; others are SI.", ""]
    lines += _section("case", case) + [""]
    lines += _section("solver", solver) + [""]
    lines += _section("run", RunSection(name=kind))
    return "\n".join(lines) + "\n"
