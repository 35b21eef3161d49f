"""12 kV VCB closing mechanism, Kang, Huang & Yang (2023), Machines 11:150: the cam and
closing springs (step 1), the four-bar (step 2), and the identification of what the paper
leaves out (kind ``vcb_identify``).

The specs name their problems as ``"module:Class"`` (imported when a problem is built,
:func:`camopt.cases.registry.problem_at`), and ``VcbProblem``, ``VcbIdentification`` and
``VcbDynamicsIdentification`` are imported from here on first use (PEP 562): ``camopt init
vcb`` or ``show`` of a VCB archive do not import the model and its dynamics, nor a
``vcb`` case the identifications, nor their configs (start-up time)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from camopt.cases.registry import (
    Adjustment,
    ArchiveLoader,
    CaseSpec,
    OverlayCurve,
    ProfileCircle,
    ProfileCurve,
    ToleranceClass,
    config_at,
    problem_at,
    register_case,
)
from camopt.cases.vcb.config import CamDesign, VcbConfig
from camopt.cases.vcb.paper import PAPER
from camopt.cases.vcb.requirements import requirements
from camopt.config.models import CaseConfig
from camopt.errors import ConfigError
from camopt.units import DEG

if TYPE_CHECKING:  # imported on first use: __getattr__ below
    from camopt.cases.vcb.identify import (
        VcbDynamicsIdentification as VcbDynamicsIdentification,
    )
    from camopt.cases.vcb.identify import VcbIdentification as VcbIdentification
    from camopt.cases.vcb.identify_config import VcbDynamicsIdentifyConfig
    from camopt.cases.vcb.problem import VcbProblem as VcbProblem

SOURCE = "Kang, Huang & Yang (2023), Machines 11:150"
TOLERANCES = {  # class "standard", docs/tolerance.md, "Tolerance classes"
    # closing springs' rates as spring makers hold them without grading (EN 15800 toleran-
    # ces the force at a test length, not the rate; ungraded springs: ±10 % on rate)
    "kc1_n_per_mm": "±10%", "kc2_n_per_mm": "±10%",
    "l1_mm": "±0.05", "l3_mm": "±0.05", "l4_mm": "±0.05", "l5_mm": "±0.05",  # step 2
    "theta1_deg": "±0.05",
    "release_offset_deg": "±0.25",  # the closing latch's seat, where it is a design variable
    # the reference velocity a breaker is set to, where the factory sets it: the analyser's
    # reading error (±2 %, as the ADAMS data's in configs/vcb.toml)
    "velocity_setting_m_s": "±2%",
    "case.l1_mm": "±0.05", "case.l3_mm": "±0.05", "case.l4_mm": "±0.05",  # step 1
    "case.l5_mm": "±0.05", "case.theta1_deg": "±0.05",
    # the parts beyond the closing springs' rates (docs/tolerance.md, "VCB's
    # parts"; docs/assumptions.md, "VCB: tolerances of the parts"):
    # closing springs' free lengths (EN 15800 grade 2 tolerances the free length; the
    # springs' L0 is not given: +-1.5 mm assumed), as their compressions when opened
    "case.kc1_precompression_mm": "±1.5", "case.kc2_precompression_mm": "±1.5",
    # opening spring and contact springs: ungraded, as the closing springs (±10 % on rate)
    "case.opening_k_n_per_mm": "±10%", "case.wipe_k_n_per_mm": "±10%",
    # friction varies with lubrication, temperature and wear (±20-30 %): every set's
    # friction torque ±25 %, and the efficiency forms' loss 1 - eps = 0.15 by ±0.03 (±20 %)
    "case.cam_friction_nm": "±25%", "case.efficiency": "±0.03",
    # the cam profile's radial error, a CNC-milled profile (the EMB's class "milled")
    "case.cam_profile_error_mm": "±0.03",
}


def _factory_class(spring_pct: float, free_length_mm: float, friction_pct: float,
                   loss: float) -> dict[str, str]:
    """The standard class with every spring held to ``spring_pct`` on rate and the closing
    springs' free lengths to ``free_length_mm``, the friction torque to ``friction_pct``
    and the loss 1 - eps to ``loss``: the classes of a breaker as built and timed."""
    springs = ("kc1_n_per_mm", "kc2_n_per_mm", "case.opening_k_n_per_mm",
               "case.wipe_k_n_per_mm")
    free = ("case.kc1_precompression_mm", "case.kc2_precompression_mm")
    return {**TOLERANCES, **{k: f"±{spring_pct:g}%" for k in springs},
            **{k: f"±{free_length_mm:g}" for k in free},
            "case.cam_friction_nm": f"±{friction_pct:g}%", "case.efficiency": f"±{loss:g}"}


TOLERANCE_CLASSES = {
    "graded": ToleranceClass(
        {**TOLERANCES, "kc1_n_per_mm": "±5%", "kc2_n_per_mm": "±5%"},
        source="closing springs graded by force at a test length (sorted after coiling), "
        "±5 % on rate; the rest as the standard class", relative_cost=1.3),
    # ungraded springs, the breaker run in with a specified grease before its timing test
    # (docs/tolerance.md, "Adjustments at assembly and the end of life"): where the nut
    # sets each breaker, the friction as built, not the springs, is what limits the yield
    "run_in": ToleranceClass(
        {**TOLERANCES, "case.cam_friction_nm": "±10%", "case.efficiency": "±0.015"},
        source="ungraded springs as the standard class; a specified grease and a run-in "
        "before the factory timing test (friction ±10 %, the loss 1 - eps ±10 %), as "
        "class controlled without grading any spring", relative_cost=1.3),
    # the breaker as built and timed at the factory (docs/tolerance.md, "VCB: what the
    # friction tolerance leaves"): every spring graded, a specified grease and a run-in
    # before the timing test, so friction varies as the grease and the fit do, not with
    # temperature and wear over the breaker's life (the other classes' ±25 %)
    "controlled": ToleranceClass(
        _factory_class(5, 0.75, 10, 0.015),
        source="every spring graded by force (±5 % on rate, free lengths ±0.75 mm), a "
        "specified grease and a run-in before the factory timing test (friction ±10 %, "
        "the loss 1 - eps ±10 %): the yield as built and timed, not over the breaker's life",
        relative_cost=1.6),
    # the breaker built from sorted springs and accepted on its friction (docs/tolerance.md,
    # "VCB: the class that reaches 0.95"): every spring 100 % load-tested and sorted into
    # +-3 % classes (free lengths with them, +-0.5 mm), and a friction acceptance test at
    # the factory (the slow-close torque measured; a breaker outside +-5 % re-greased and
    # run in again): the yield of breakers that pass it, as built and timed
    "matched": ToleranceClass(
        _factory_class(3, 0.5, 5, 0.0075),
        source="every spring 100 % load-tested and sorted into ±3 % classes (free lengths "
        "±0.5 mm), and a friction acceptance test at the factory (slow-close torque within "
        "±5 %, the loss 1 - eps ±5 %; outside: re-greased and run in again): the yield of "
        "breakers that pass it, as built and timed", relative_cost=2.2),
}


def resolve(config: CaseConfig, load: ArchiveLoader) -> CaseConfig:
    """The values a VCB case file takes from other files: the reference cam's law from
    ``reference_cam_points`` and step 2's cam from ``cam_archive``."""
    return resolve_cam_archive(resolve_reference_cam(config, load), load)


def resolve_reference_cam(config: CaseConfig, load: ArchiveLoader) -> CaseConfig:
    """``reference_cam_points`` read into ``reference_law`` (the follower law of the
    points: :func:`camopt.cases.vcb.cam_points.read_cam_points`, over the stroke 0 to the
    last node angle)."""
    assert isinstance(config, VcbConfig)
    if not config.reference_cam_points:
        return config
    from camopt.cases.vcb.cam_points import read_cam_points  # its curves: when named only

    path = load.locate("case.reference_cam_points", config.reference_cam_points)
    a = read_cam_points(path, config.node_cam_deg[-1] * DEG)
    return config.model_copy(update={"reference_law": [float(v) for v in a]})


def resolve_cam_archive(config: CaseConfig, load: ArchiveLoader) -> CaseConfig:
    """Step 2 with ``cam_archive``: the step-1 run's best design becomes ``cam_design``."""
    assert isinstance(config, VcbConfig)
    if not config.cam_archive:
        return config
    run = load("case.cam_archive", config.cam_archive)
    x = run.best.x
    if run.kind != "vcb" or run.case.get("step") != "cam" or "a1" not in x:
        raise ConfigError(config.cam_archive, "case.cam_archive",
                          "not a VCB step-1 (cam) run archive")
    if "velocity_setting_m_s" in x:  # step 2 has no factory setting: it would judge it unset
        raise ConfigError(config.cam_archive, "case.cam_archive",
                          "its breakers are set at the factory (velocity_setting_m_s); "
                          "step 'fourbar' does not model the setting")
    design = CamDesign(a0=run.best.metrics["a0"], a1=x["a1"], a2=x["a2"], a3=x["a3"],
                       a4=x.get("a4", 0.0), a5=x.get("a5", 0.0),
                       release_offset_deg=x.get("release_offset_deg"),
                       kc1_n_per_mm=x["kc1_n_per_mm"], kc2_n_per_mm=x["kc2_n_per_mm"])
    return config.model_copy(update={"cam_design": design})


def variable_names(config: VcbConfig) -> tuple[str, ...]:
    """The VCB Problem's variables for ``config`` (``VcbProblem.__init__``), by name only:
    step 1 the law's coefficients and spring rates, with the optional release offset and
    velocity setting; step 2 the four-bar's lengths and angle."""
    if config.step != "cam":
        return ("l1_mm", "l3_mm", "l4_mm", "l5_mm", "theta1_deg")
    names: tuple[str, ...] = ("a1", "a2", "a3", "kc1_n_per_mm", "kc2_n_per_mm")
    names += tuple(n for n, b in (("a4", config.a4_bounds), ("a5", config.a5_bounds))
                   if b is not None)
    if config.release_offset_bounds_deg is not None:
        names += ("release_offset_deg",)
    if config.velocity_setting_bounds_m_s is not None:
        names += ("velocity_setting_m_s",)
    return names


def form_parameters(config: VcbDynamicsIdentifyConfig) -> tuple[str, ...]:
    """The dynamics identification's variables: its model form's parameters (the forms'
    table imports the closing dynamics, not the numba kernel; no model is built)."""
    from camopt.cases.vcb.forms import get_form

    return get_form(config.model_form).parameters


VCB = register_case(CaseSpec(
    kind="vcb", config=VcbConfig, problem=problem_at("camopt.cases.vcb.problem:VcbProblem"),
    default_solver="de_gr",
    summary="VCB closing mechanism: cam + closing springs (step 1) or four-bar (step 2)",
    paper_source=SOURCE, figures="camopt.cases.vcb.figures:figures", paper=PAPER,
    profiles=(ProfileCurve("cam-profile", ("profile_x_mm",), ("profile_y_mm",)),
              ProfileCurve("cam-pitch-curve", ("pitch_x_mm",), ("pitch_y_mm",))),
    circles=(ProfileCircle("base-circle", "rb_mm"),
             ProfileCircle("roller", "rf_mm", ("pitch_x_mm", "pitch_y_mm"))),
    outline="camopt.cases.vcb.outline:outline",
    profile_tolerance="case.cam_profile_error_mm",
    overlays=tuple(OverlayCurve(f"closing_{what}", f"Closing: movable contact {what}",
                                "time_ms", f"dyn_contact_{key}",
                                "time from the springs' release (ms)", label)
                   for what, key, label in (("travel", "travel_mm", "displacement (mm)"),
                                            ("velocity", "velocity_m_s", "velocity (m/s)"))
                   ) + (OverlayCurve("rod_travel", "Rod travel along the stroke",
                                     "cam_angle_deg", "rod_travel_mm",
                                     "cam angle theta_c (deg)", "rod travel s1 (mm)"),),
    resolve=resolve, tolerances=TOLERANCES,
    tolerance_classes=TOLERANCE_CLASSES, requirements=requirements,
    reference="vendor, Sec 2.3 and Table 2",
    adjustments=(Adjustment(
        "closing springs' preload nut", "preload_setting_mm", "preload_setting_range_mm",
        "mm", "the analyser's contact velocity to velocity_setting_m_s"),),
    calibration="camopt.cases.vcb.calibration_run:run",
    variable_names=lambda config: variable_names(config),
))
VCB_IDENTIFY = register_case(CaseSpec(
    kind="vcb_identify", config=config_at("camopt.cases.vcb.identify_config:VcbIdentifyConfig"),
    problem=problem_at("camopt.cases.vcb.identify:VcbIdentification"),
    default_solver="de_gr",
    summary="fits the VCB parameters the paper omits to the numbers it reports",
    paper_source=SOURCE,
    variable_names=lambda config: ("rod_arm_offset_deg", "opening_arm_ratio",
                                   "free_contact_force_n"),
))
VCB_IDENTIFY_DYNAMICS = register_case(CaseSpec(
    kind="vcb_identify_dynamics",
    config=config_at("camopt.cases.vcb.identify_config:VcbDynamicsIdentifyConfig"),
    problem=problem_at("camopt.cases.vcb.identify:VcbDynamicsIdentification"),
    default_solver="de_gr",
    summary="fits the VCB dynamics' parameters to the vendor design's seven ADAMS data",
    paper_source=SOURCE,
    variable_names=lambda config: form_parameters(config),
))

_PROBLEMS = {"VcbProblem": VCB, "VcbIdentification": VCB_IDENTIFY,
             "VcbDynamicsIdentification": VCB_IDENTIFY_DYNAMICS}


def __getattr__(name: str) -> Any:
    """The problem classes, imported on first use (their specs name them)."""
    if name in _PROBLEMS:
        return _PROBLEMS[name].problem
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
