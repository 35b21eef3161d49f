"""``[case]`` of the VCB closing mechanism (Kang, Huang & Yang 2023); the identifications'
are in :mod:`camopt.cases.vcb.identify_config`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, ClassVar, Literal

from pydantic import Field, ValidationInfo, model_validator

from camopt.config.models import (
    PLAUSIBILITY_KEY,
    AsTuple,
    Bounds,
    CaseConfig,
    FieldRole,
    Pair,
    Plausible,
    Positive,
    Strict,
)

# Physical ranges of a medium-voltage breaker mechanism of this family: a value outside is a
# unit slip (metres into mm) or a typo; run.check_plausibility = false accepts it.
Length = Annotated[Positive, Plausible(1.0, 2000.0)]  # mm
FORCE_RATIO = 100.0
"""A closing spring's preload within this factor of the loads it closes against (either
way): beyond it a rate was typed in another unit (VcbMechanism._units_agree)."""
# a link of a 12 kV breaker mechanism: tens to hundreds of mm (Sec 2.3: 70-140 mm; Eq 42
# searches 70-150 mm); below 20 mm it is a length typed in cm (14.8 for 148 mm)
LinkLength = Annotated[Positive, Plausible(20.0, 2000.0)]  # mm
# a closing velocity in m/s: a vacuum interrupter closes at 0.5-2 m/s; 900 is mm/s typed
VelocityBand = Annotated[Pair | None, Plausible(0.0, 20.0)]  # m/s
Stroke = Annotated[Positive, Plausible(0.1, 500.0)]  # mm: strokes, compressions, clearances
Rate = Annotated[Positive, Plausible(0.01, 10_000.0)]  # N/mm
Modulus = Annotated[Positive, Plausible(1.0, 1000.0)]  # GPa
StressMpa = Annotated[Positive, Plausible(10.0, 10_000.0)]  # MPa
Mass = Annotated[Positive, Plausible(1e-3, 1000.0)]  # kg
Inertia = Annotated[Positive, Plausible(1e-7, 10.0)]  # kg m^2

ModelFormName = Literal["efficiency_coulomb", "coulomb", "efficiency_driven_coulomb",
                        "driven_coulomb", "fitted_efficiency"]
"""The model forms of :mod:`camopt.cases.vcb.forms` (which checks that the two agree)."""
RELEASE_TORQUE_MARGIN_MIN = 1.2  # assumed: docs/assumptions.md, "VCB: release and lift-off"
LATCH_ENERGY_MAX_J = 5.0  # assumed: docs/assumptions.md, "VCB: release and lift-off"
LIFT_OFF_FRACTION_MIN = 0.05  # assumed: docs/assumptions.md, "VCB: release and lift-off"
PRELOAD_SETTING_RANGE_MM = 5.0  # assumed: docs/assumptions.md, "VCB: factory setting"


# the parameter sets configs/vcb_identify_dynamics.toml finds consistent with the ADAMS
# data over the kept model forms (its `band.sets`, copied; configs/vcb.toml's dynamics_band:
# `camopt init vcb` prints it): the shipped form's fit and one more set, then the
# Coulomb-only form's fit and six sets (docs/assumptions.md, "VCB: model forms and band")
IDENTIFIED_BAND = (
    (5.77191e-04, 0.0, 2.88047, 2.01795, 14.0752, 11.5320, 11.5320, 0.85),
    (6.73501e-04, 0.0, 2.62303, 2.06484, 14.0811, 11.4450, 11.4450, 0.85),
    (5.45857e-04, 0.0, 3.37668, 2.36702, 16.2819, 15.8205, 15.8205, 1.0),
    (5.39430e-04, 0.0, 3.86767, 2.22606, 16.2853, 15.7734, 15.7734, 1.0),
    (6.49865e-04, 0.0, 2.98928, 2.65002, 16.2988, 15.7730, 15.7730, 1.0),
    (5.00000e-04, 0.0, 3.13591, 2.17846, 16.1459, 15.7405, 15.7405, 1.0),
    (6.60377e-04, 0.0, 2.90333, 2.22431, 16.2958, 15.6899, 15.6899, 1.0),
    (5.00000e-04, 0.0, 3.84972, 2.05527, 16.3107, 15.9045, 15.9045, 1.0),
    (5.78443e-04, 0.0, 3.50285, 2.22727, 16.4043, 15.8452, 15.8452, 1.0),
)


BandRow = Annotated[tuple[float, float, float, float, float, float]
                    | tuple[float, float, float, float, float, float, float, float], AsTuple]
"""A parameter set of the band: (cam_inertia_kg_m2, follower_inertia_kg_m2, rod_mass_kg,
contacts_mass_kg, release_offset_deg, cam_friction_nm[, release_friction_nm,
efficiency]): six values are the shipped form (the free rotation's friction the
same, the case's efficiency), eight any model form's (camopt/cases/vcb/forms.py)."""


def roles_of(role: FieldRole, names: str) -> dict[str, FieldRole]:
    """``role`` for each of the whitespace-separated field ``names``."""
    return dict.fromkeys(names.split(), role)


VCB_ROLES: dict[str, FieldRole] = {
    **roles_of("hardware", """reference_label reference_cam_points reference_law l1_mm l2_mm
        l3_mm l4_mm l5_mm theta1_deg pivot_b_mm pivot_g_mm crank_l8_mm preset_qox_deg rb_mm rf_mm
        beta_mm gamma_mm node_clearance_mm theta0_deg s1_bar_mm node_cam_deg node_fractions
        kc1_n_per_mm kc2_n_per_mm kc1_precompression_mm kc2_precompression_mm
        opening_k_n_per_mm opening_stretch_closed_mm wipe_k_n_per_mm wipe_count
        wipe_compression_closed_mm contact_gap_mm cam_modulus_gpa poisson
        contact_length_mm shear_yield_mpa cam_design tolerance_class cam_profile_error_mm
        preload_setting_range_mm preload_setting_resolution_mm"""),
    **roles_of("identified", """rod_arm_offset_deg opening_arm_ratio free_contact_force_n
        alpha efficiency cam_inertia_kg_m2 follower_inertia_kg_m2 rod_mass_kg
        contacts_mass_kg release_offset_deg cam_friction_nm latch_delay_ms spring_mass_kg
        rod_damping_n_s_per_m dynamics_band band_coupler_mass_kg band_follower_inertia_kg_m2"""),
    **roles_of("requirement", """rod_travel_mm rod_travel_tolerance_mm closing_velocity_m_s
        require_latch pressure_angle_max_deg forbid_lift_off latch_energy_min_j
        latch_energy_max_j release_torque_margin_min lift_off_fraction_min
        stress_constraint phi_max_deg life_friction_rise life_spring_relaxation"""),
    **roles_of("solver setting", """step cam_archive dynamics_steps objective_form positions penalty
        a1_bounds a2_bounds a3_bounds a4_bounds a5_bounds release_offset_bounds_deg
        velocity_setting_bounds_m_s kc1_bounds_n_per_mm kc2_bounds_n_per_mm l1_bounds_mm
        l3_bounds_mm l4_bounds_mm l5_bounds_mm theta1_bounds_deg"""),
}
"""Every VCB ``[case]`` field's role (``docs/cases/vcb.md``, ``camopt init vcb``): what
describes the breaker, what must be re-identified after a geometry change, what a design
must meet, and what only steers camopt. ``alpha`` and ``efficiency`` are losses (Eq 1,
Eq 26): identified, not drawn. ``cam_design`` is the cam step 2 keeps (hardware once
chosen); ``cam_archive`` only where camopt reads it from."""


class CamDesign(Strict):
    """A step-1 design: cubic coefficients (rad, per rad^k) and closing spring rates."""

    a0: float | None = Field(None, description="phi at theta_c = 0; None: from Eq 8")
    a1: float
    a2: float
    a3: float
    a4: float = Field(0.0, description="quartic term (beyond the paper; 0: its cubic)")
    a5: float = Field(0.0, description="quintic term (beyond the paper; 0: its cubic)")
    release_offset_deg: float | None = Field(
        None, gt=0, lt=90, description="the closing latch's release offset (beyond the paper; "
        "None: the case's release_offset_deg)")
    kc1_n_per_mm: Positive
    kc2_n_per_mm: Positive


class VcbMechanism(CaseConfig):
    """The mechanism every VCB ``[case]`` describes (the two design steps and the
    identifications alike): four-bar and pivots, cam, springs and loads, dynamics and
    its band, contact stress, and the objective's form; validated on their own (the
    follower law's nodes, the phi_max and closing-velocity bands)."""

    field_roles: ClassVar[Mapping[str, FieldRole]] = VCB_ROLES
    kind: Literal["vcb"] = "vcb"
    step: Literal["cam", "fourbar"] = Field(
        "cam", description="cam: a1, a2, a3, kc1, kc2 (Eq 37); fourbar: l1, l3, l4, l5, "
        "theta1 (Eq 41)")
    reference_label: str = Field(
        "vendor, Sec 2.3 and Table 2", min_length=1, max_length=200,
        description="name of the reference design, the breaker these fields describe (its "
        "cam: reference_cam_points or Eq 8's nodes; its springs: kc1, kc2), shown beside "
        "every optimum as 'reference: <label>'")
    reference_cam_points: str | None = Field(
        None, description="the reference design's cam as a points file (CSV with "
        "cam_angle_deg and follower_angle_deg, as camopt export writes; relative to the "
        "working folder or the case file): its follower law (camopt/cases/vcb/cam_points.py) "
        "replaces the one from Eq 8's nodes; unset: the nodes")
    reference_law: list[float] | None = Field(
        None, min_length=4, max_length=6, description="the reference cam's follower law "
        "a0..ad (rad/rad^k, degree 3 to 5): what reading reference_cam_points gives (filled "
        "in when the case file is read; may be given instead); unset: Eq 8's nodes")
    # four-bar and pivots (Sec 2.3)
    l1_mm: LinkLength = Field(139.79, description="fixed link BE (Sec 2.3)")
    l2_mm: LinkLength = Field(70.0, description="follower (input) link BD (Sec 2.3)")
    l3_mm: LinkLength = Field(124.7, description="coupler DL (Sec 2.3)")
    l4_mm: LinkLength = Field(140.0, description="output arm EL (Sec 2.3)")
    l5_mm: LinkLength = Field(90.0, description="output arm EM to the insulated rod (Sec 2.3)")
    theta1_deg: float = Field(-121.98, description="fixed-link angle (Table 7 initial)")
    pivot_b_mm: Pair = Field((-72.0, -55.0), description="follower pivot B (cam pivot O at 0,0) "
                                                         "(Sec 2.3)")
    pivot_g_mm: Pair = Field((50.0, 200.0), description="closing springs' fixed end G (Sec 2.3)")
    crank_l8_mm: Length = Field(25.0, description="closing springs' crank OQ on the cam shaft "
                                "(Sec 2.3, assumed reading)")
    preset_qox_deg: float = Field(95.0, description="angle QOX in the opened state (Sec 2.3)")
    rod_arm_offset_deg: float = Field(
        7.46, description="angle of EM from the extension of LE beyond E (identified: "
        "configs/vcb_identify.toml, 18.0 mm rod travel)")
    # cam (Sec 2.2-2.3)
    rb_mm: Length = Field(23.0, description="base circle radius (Sec 2.3)")
    rf_mm: Length = Field(15.0, description="roller radius (Sec 2.3)")
    alpha: Positive = Field(0.95, description="loss coefficient of contact (Eq 1)")
    beta_mm: float = Field(2.0, ge=0, description="cam-roller clearance (Eq 1)")
    gamma_mm: float = Field(1.0, ge=0, description="hook-roller clearance (Eq 1)")
    node_clearance_mm: float = Field(
        1.0, ge=0, description="clearance in Eqs 2 and 8 that reproduces a0..a3 (not beta)")
    theta0_deg: float = Field(4.0, ge=0, description="pre-rotation before contact (Sec 2.2 Step 8)")
    s1_bar_mm: Stroke = Field(16.0, description="overall displacement of M (Eq 1)")
    node_cam_deg: list[float] = Field([0.0, 70.0, 100.0, 140.0], description="theta_ci (Fig 4)")
    node_fractions: list[float] = Field([0.0, 0.7, 0.9, 1.0], description="s2i / s2bar (Fig 4)")
    # springs and loads (Table 2, Sec 3.2)
    kc1_n_per_mm: Rate = Field(7.72, description="vendor closing spring 1 (Table 2)")
    kc2_n_per_mm: Rate = Field(9.33, description="vendor closing spring 2 (Table 2)")
    kc1_precompression_mm: Stroke = Field(140.0, description="spring 1, opened state (Table 2)")
    kc2_precompression_mm: Stroke = Field(100.0, description="spring 2, opened state (Table 2)")
    opening_k_n_per_mm: Rate = Field(16.6, description="opening spring (Table 2)")
    opening_stretch_closed_mm: Stroke = Field(33.6, description="opening spring, closed state "
                                              "(Table 2)")
    opening_arm_ratio: Positive = Field(
        1.85, description="opening-spring elongation per mm of rod travel, r7/r6 "
        "(identified, at its physical bound)")
    wipe_k_n_per_mm: Rate = Field(82.4, description="one contact (wipe) spring (Table 2)")
    wipe_count: int = Field(3, ge=1, description="contact springs, one per phase (assumed)")
    wipe_compression_closed_mm: Stroke = Field(17.0, description="closed state, vendor (Table 2)")
    contact_gap_mm: Stroke = Field(11.0, description="rod travel where contacts touch (Sec 3.2)")
    free_contact_force_n: float = Field(
        0.0, description="self-closing force of the interrupters before touch (identified)")
    efficiency: float = Field(0.85, gt=0, le=1, description="mechanical efficiency (Eq 26)")
    cam_profile_error_mm: float = Field(
        0.0, ge=-1.0, le=1.0, description="radial error of the cam profile as made, a uniform "
        "offset along its normal (+: oversize); the follower sits that much further out "
        "(tolerance analysis; 0: the profile as designed) (camopt option)")
    rod_travel_mm: Stroke = Field(
        18.0, description="rod travel the breaker needs, opened to closed (Sec 3.2)")
    rod_travel_tolerance_mm: Stroke = Field(
        0.2, description="allowed deviation of the rod travel (constraint, steps 1 and 2) "
                         "(assumed, docs/assumptions.md)")
    # opening and closing dynamics (Sec 3.2, camopt/cases/vcb/dynamics.py); parameters
    # identified on the vendor's ADAMS data: configs/vcb_identify_dynamics.toml
    cam_inertia_kg_m2: Inertia = Field(
        5.8e-4, description="cam, shaft, crank and closing springs about O (identified)")
    follower_inertia_kg_m2: float = Field(
        0.0, ge=0, le=10.0, description="follower BD, roller and four-bar input about B, "
        "kg m^2 (the ADAMS data do not separate it from rod_mass_kg: docs/assumptions.md)")
    rod_mass_kg: Mass = Field(
        2.8807, description="output link, arm and insulated rods as a mass at the rod "
        "(identified)")
    contacts_mass_kg: Mass = Field(
        2.0181, description="the three moving contacts together (identified)")
    release_offset_deg: float = Field(
        14.07, gt=0, lt=90, description="the charged spring crank's angle past its dead "
        "centre when the closing latch lets go (identified; 19.04 = QOX 95 deg)")
    cam_friction_nm: float = Field(
        11.53, ge=0, le=1000.0, description="Coulomb friction torque referred to the cam shaft, "
        "against the cam whenever it turns, beyond Eq 26's efficiency (identified)")
    spring_mass_kg: float = Field(
        0.0, ge=0, le=100.0, description="the closing springs' own mass moving with their "
        "free ends, effective (a third of both springs' mass): an inertia (dL/dtheta)^2 on "
        "the cam (identified by camopt calibrate where curves need it; 0: rigid springs)")
    rod_damping_n_s_per_m: float = Field(
        0.0, ge=0, le=1e5, description="viscous damping on the rod (dashpot, buffer), "
        "force per rod speed (identified by camopt calibrate where curves need it; 0: none)")
    latch_delay_ms: float | None = Field(
        None, ge=0, le=1000.0, description="the close command to the closing latch's "
        "release (coil and latch), ms; with it a run reports closing_time_ms, command to "
        "the contacts' touch as an analyser reads it (IEC 62271-100's closing time; "
        "camopt calibrate's --out writes it; identified); none: only times from the release")
    dynamics_band: list[BandRow] = Field(
        default_factory=lambda: list[BandRow](IDENTIFIED_BAND), max_length=64,
        description="parameter sets (BandRow: six values, or eight with the free "
        "rotation's friction and the efficiency of any model form) consistent with the "
        "ADAMS data within their reading error widened by the kept forms' residuals: every "
        "closing velocity, time and latch energy is reported as the band over them "
        "(configs/vcb_identify_dynamics.toml, its band.sets)")
    band_coupler_mass_kg: float = Field(
        0.2, ge=0, le=50.0, description="the coupler DL's own mass (kg) the band adds to "
        "each model form's fit as one more parameter set (the identified model's coupler "
        "is massless): half at each joint, on the follower and the output link "
        "(camopt/cases/vcb/forms.py; assumed: a steel bar 125 x 20 x 10 mm, "
        "docs/assumptions.md); 0: no such set")
    band_follower_inertia_kg_m2: float = Field(
        5e-4, ge=0, le=10.0, description="the follower BD's own inertia about B with its "
        "roller (kg m^2) the same set adds (assumed: a steel lever 70 x 20 x 12 mm and "
        "its roller, docs/assumptions.md); 0: none")
    dynamics_steps: int = Field(
        400, ge=50, le=100_000, description="graded cam-angle intervals of the work-energy "
        "integration (independent of positions; a sixteenth of them, at least 16, for the "
        "free rotation from the release) (camopt option)")
    closing_velocity_m_s: VelocityBand = Field(
        None, description="bounds on the average closing velocity (constraint; Sec 2.1 asks "
        "0.9 +- 0.2 m/s); none: reported only")
    require_latch: bool = Field(
        False, description="constraint: the cam reaches the end of the stroke (no stall) "
        "with at least latch_energy_min_j of kinetic energy left (camopt option)")
    pressure_angle_max_deg: float | None = Field(
        None, gt=0, lt=90, description="constraint on the cam's pressure angle (Sec 2.3 names "
        "45 deg allowable); none: reported only")
    forbid_lift_off: bool = Field(
        False, description="constraint: the cam never pulls the roller (torque it passes on "
        ">= 0 along the closing) (camopt option)")
    latch_energy_min_j: float = Field(
        0.0, ge=0, description="kinetic energy the hook needs at the end of the stroke "
        "(assumed, docs/assumptions.md)")
    latch_energy_max_j: float = Field(
        LATCH_ENERGY_MAX_J, gt=0, description="kinetic energy the prop and stop may absorb "
        "at the end of the stroke, the band's greatest (constraint with require_latch; a "
        "requirement always) (assumed: ~the contact springs' work over 1.2 mm of overtravel; "
        "docs/assumptions.md)")
    life_friction_rise: float = Field(
        0.0, ge=0.0, le=2.0, description="end of life: every friction torque this share "
        "higher than as built (0.25: +25 %), the factory setting's nut held; a design is "
        "judged at the start and at the end of its life, each requirement at its worse "
        "(0: no life check) (assumed; docs/assumptions.md, \"VCB: life\")")
    life_spring_relaxation: float = Field(
        0.0, ge=0.0, lt=0.5, description="end of life: the closing springs' force in the "
        "charged (opened) state this share lower than as built (relaxation: their "
        "compression there shortened by the share), with life_friction_rise (assumed; "
        "docs/assumptions.md, \"VCB: life\")")
    release_torque_margin_min: float = Field(
        RELEASE_TORQUE_MARGIN_MIN, ge=1.0, le=100.0, description="least eps T_s / T_f at "
        "the release, the closing springs' torque on the cam at rest against the friction "
        "torque, in every set of the band (constraint with require_latch; a requirement "
        "always) (assumed: a spring 5 % soft and friction 10 % high still release; "
        "docs/assumptions.md)")
    lift_off_fraction_min: float = Field(
        LIFT_OFF_FRACTION_MIN, ge=0.0, lt=1.0, description="least torque the cam passes to "
        "the roller, as a share of the springs' mean driving torque over the stroke "
        "(constraint with forbid_lift_off; a requirement always) (assumed; docs/assumptions.md)")
    # contact stress (Table 1, Eqs 27-31)
    cam_modulus_gpa: Modulus = Field(210.0, description="E of cam and roller (S45C) (Table 1)")
    poisson: float = Field(0.3, ge=0, lt=0.5, description="Poisson's ratio (Table 1)")
    contact_length_mm: Length = Field(15.0, description="cam-roller contact length (assumed)")
    shear_yield_mpa: StressMpa = Field(1194.0, description="tau_y = 0.577 sigma_y (Table 1)")
    stress_constraint: bool = Field(True, description="require tau_max <= shear_yield (Eq 31)")
    # objective (Eqs 39-40)
    objective_form: Literal["net", "abs_sum"] = Field(
        "net", description="net: |surplus| of Eq 26 in J, exact; abs_sum: sum |Fo - Fr/eps| "
        "in N, as printed")
    positions: int = Field(140, ge=10, le=1_000_000,
                           description="Ns, cam positions over 0-140 deg (sampled curves) (Eq 39)")
    penalty: float = Field(1e6, ge=0, description="M in Eq 39")
    phi_max_deg: Pair = Field((23.0, 26.0),
                              description="bounds on the follower's maximum angle (Eq 40)")

    @model_validator(mode="after")
    def _nodes(self) -> VcbMechanism:
        if len(self.node_cam_deg) != 4 or len(self.node_fractions) != 4:
            raise ValueError("node_cam_deg and node_fractions need four values (Eq 7)")
        nodes, fractions = self.node_cam_deg, self.node_fractions
        if nodes[0] != 0 or any(b <= a for a, b in zip(nodes, nodes[1:])) or nodes[-1] > 300:
            raise ValueError("node_cam_deg: cam angles start at 0 and increase, at most "
                             "300 deg (Eq 7; the cam must leave the roller within a turn)")
        if any(b <= a for a, b in zip(fractions, fractions[1:])) or not (
                0 <= fractions[0] and fractions[-1] <= 1):
            raise ValueError("node_fractions: increasing fractions of the stroke in [0, 1]")
        if self.reference_cam_points is not None and not self.reference_cam_points.strip():
            raise ValueError("reference_cam_points: an empty file name")
        return self

    @model_validator(mode="after")
    def _units_agree(self, info: ValidationInfo) -> VcbMechanism:
        """Typed units checked against each other (each value alone may be in range): a
        base circle below half the roller radius or half the follower stroke is centimetres
        typed (``rb_mm = 2.3``); a closing spring whose preload force is more than
        :data:`FORCE_RATIO` times the loads it closes against (opening spring and contact
        springs at the closed state), or less than 1/:data:`FORCE_RATIO` of them, is N/m
        or kN/mm typed (``kc1_n_per_mm = 7720``). ``run.check_plausibility = false``
        accepts them."""
        if (info.context or {}).get(PLAUSIBILITY_KEY) is False:
            return self
        least = max(self.rf_mm, self.s1_bar_mm) / 2
        if self.rb_mm < least:
            raise ValueError(
                f"rb_mm: {self.rb_mm:g} mm is below half the roller radius (rf_mm "
                f"{self.rf_mm:g}) or half the follower stroke (s1_bar_mm {self.s1_bar_mm:g}): "
                f"no cam that small drives this roller (centimetres typed? {10 * self.rb_mm:g}"
                f" mm); set run.{PLAUSIBILITY_KEY} = false to accept it")
        load = (self.opening_k_n_per_mm * self.opening_stretch_closed_mm
                + self.wipe_count * self.wipe_k_n_per_mm * self.wipe_compression_closed_mm)
        for key in ("kc1", "kc2"):
            rate = getattr(self, f"{key}_n_per_mm")
            force = rate * getattr(self, f"{key}_precompression_mm")
            if not load / FORCE_RATIO <= force <= load * FORCE_RATIO:
                hint = "N/m typed?" if force > load else "kN/mm typed?"
                raise ValueError(
                    f"{key}_n_per_mm: {rate:g} N/mm preloads the spring to {force:.0f} N, "
                    f"against {load:.0f} N of opening and contact springs at the closed state "
                    f"(more than {FORCE_RATIO:g} times apart: {hint}); set "
                    f"run.{PLAUSIBILITY_KEY} = false to accept it")
        return self

    @model_validator(mode="after")
    def _bands(self) -> VcbMechanism:
        if self.phi_max_deg[0] >= self.phi_max_deg[1]:
            raise ValueError("phi_max_deg: lower bound must be below upper bound")
        v = self.closing_velocity_m_s
        if v is not None and not 0 <= v[0] < v[1]:
            raise ValueError("closing_velocity_m_s: need 0 <= lower < upper")
        return self


class VcbCamStep(VcbMechanism):
    """Step 1's search (Eqs 37-38): the follower law's coefficients, the closing spring
    rates and, beyond the paper, the law's higher terms and the closing latch."""

    a1_bounds: Bounds = Field(Bounds(lower=0, upper=0.5), description="Eq 38")
    a2_bounds: Bounds = Field(Bounds(lower=0, upper=0.5), description="Eq 38")
    a3_bounds: Bounds = Field(Bounds(lower=-0.5, upper=0), description="Eq 38")
    a4_bounds: Bounds | None = Field(
        None, description="beyond the paper: the follower law's quartic term a4 (rad/rad^4) "
        "becomes a design variable; unset: the paper's cubic (Eq 9)")
    a5_bounds: Bounds | None = Field(
        None, description="beyond the paper: the quintic term a5 (rad/rad^5), with a4; unset: "
        "no quintic term")
    release_offset_bounds_deg: Bounds | None = Field(
        None, description="beyond the paper: where the closing latch holds the charged spring "
        "crank (past its dead centre) becomes a design variable, release_offset_deg; the "
        "band's sets keep their spread about it; unset: the identified release_offset_deg")
    velocity_setting_bounds_m_s: Bounds | None = Field(
        None, description="beyond the paper: every breaker is set at the factory, its closing "
        "springs' preload turned by a nut until the analyser reads the design's reference "
        "closing velocity, velocity_setting_m_s, a design variable within these bounds "
        "(docs/tolerance.md, \"VCB: factory setting\"); unset: every breaker as its parts "
        "are made")
    preload_setting_range_mm: float = Field(
        PRELOAD_SETTING_RANGE_MM, gt=0, le=100, description="how far the setting nut may "
        "move both closing springs' compression from the design's, either way (mm; "
        "constraint with velocity_setting_bounds_m_s) (assumed; docs/assumptions.md)")
    preload_setting_resolution_mm: float = Field(
        0.0, ge=0, le=10, description="the smallest step the fitter sets the nut by (mm; "
        "a nut locked on one of six flats of an M20 x 2.5 guide rod: 0.42; shims: their "
        "thickness); each breaker's travel is the nearest multiple, so its set velocity "
        "misses the setting by up to half a step's worth; 0: continuous (assumed; "
        "docs/assumptions.md)")
    kc1_bounds_n_per_mm: Bounds = Field(Bounds(lower=4, upper=10),
                                        description="Eq 38 widened, docs/assumptions.md")
    kc2_bounds_n_per_mm: Bounds = Field(Bounds(lower=4, upper=10),
                                        description="Eq 38 widened, docs/assumptions.md")

    @model_validator(mode="after")
    def _law_terms(self) -> VcbCamStep:
        if self.a5_bounds is not None and self.a4_bounds is None:
            raise ValueError("a5_bounds needs a4_bounds: the law's terms are taken in "
                             "order (a quintic has a quartic term)")
        r = self.release_offset_bounds_deg
        if self.kind == "vcb" and r is not None and not 0 < r.lower <= r.upper < 90:
            raise ValueError("release_offset_bounds_deg: the latch holds the crank past its "
                             "dead centre: 0 < lower <= upper < 90 deg")
        v = self.velocity_setting_bounds_m_s
        if v is not None and not 0 < v.lower <= v.upper <= 20:
            raise ValueError("velocity_setting_bounds_m_s: 0 < lower <= upper <= 20 m/s")
        return self


class VcbConfig(VcbCamStep):
    """12 kV VCB cam-linkage closing mechanism, Kang, Huang & Yang (2023): step 1 (the
    cam, :class:`VcbCamStep`) or step 2 (the four-bar from step 1's cam design, Eqs
    41-42), chosen by ``step``; one flat ``[case]`` table for both."""

    l1_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l3_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l4_bounds_mm: Bounds = Field(Bounds(lower=70, upper=150), description="Eq 42")
    l5_bounds_mm: Bounds = Field(Bounds(lower=50, upper=100), description="Eq 42")
    theta1_bounds_deg: Bounds = Field(Bounds(lower=-180, upper=-90), description="Eq 42")
    cam_design: CamDesign | None = Field(None, description="step-1 design used by step 2 (Sec 3.3)")
    cam_archive: str | None = Field(
        None, description="run archive whose best design is the step-1 design (step 2) "
                          "(camopt option)")

    @model_validator(mode="after")
    def _fourbar_step(self) -> VcbConfig:
        if self.kind != "vcb" or self.step != "fourbar":
            return self
        for name in ("a4_bounds", "a5_bounds", "release_offset_bounds_deg",
                     "velocity_setting_bounds_m_s"):
            if getattr(self, name) is not None:
                raise ValueError(f"{name}: a step-1 (cam) design variable; step "
                                 "'fourbar' takes the cam design, its latch included, "
                                 "from cam_design or cam_archive")
        if self.cam_design is None and self.cam_archive is None:
            raise ValueError("step 'fourbar' needs the step-1 design: set cam_design or "
                             "cam_archive")
        return self
