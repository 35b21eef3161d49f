"""EMB negative-radius roller cam, Yan, Chen, Yan & Hang (2023), Actuators 12:329."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from camopt.cases.emb_cam.paper import PAPER
from camopt.cases.emb_cam.requirements import requirements
from camopt.cases.registry import (
    CaseSpec,
    ProfileCircle,
    ProfileCurve,
    ToleranceClass,
    config_at,
    problem_at,
    register_case,
)

if TYPE_CHECKING:  # imported on first use: __getattr__ below
    from camopt.cases.emb_cam.config import EmbCamConfig as EmbCamConfig
    from camopt.cases.emb_cam.problem import EmbCamProblem as EmbCamProblem

TOLERANCES = {  # docs/assumptions.md, "Default tolerances": a ground cam profile
    **{f"r{j}_mm": "±0.01" for j in range(1, 40)},  # key radii (those of the run apply)
    "e_mm": "±0.05",  # follower offset, a machined bore
}
TOLERANCE_CLASSES = {
    "milled": ToleranceClass(
        {**TOLERANCES, **{f"r{j}_mm": "±0.03" for j in range(1, 40)}},
        source="a CNC-milled profile, not ground: profile tolerance ~0.06 mm (±0.03 mm on "
        "a radius)", relative_cost=0.6),
}

SPEC = register_case(CaseSpec(
    kind="emb_cam", config=config_at("camopt.cases.emb_cam.config:EmbCamConfig"),
    problem=problem_at("camopt.cases.emb_cam.problem:EmbCamProblem"), default_solver="pso",
    summary="negative-radius roller cam of an electromechanical brake",
    paper_source="Yan, Chen, Yan & Hang (2023), Actuators 12:329",
    figures="camopt.cases.emb_cam.figures:figures", paper=PAPER,
    profiles=(ProfileCurve("cam-profile", ("profile_x_mm", "nonworking_x_mm"),
                           ("profile_y_mm", "nonworking_y_mm")),),
    circles=(ProfileCircle("base-circle", "r_st_mm"),),
    profile_tolerance="r1_mm",  # every key radius is held alike
    tolerances=TOLERANCES, tolerance_classes=TOLERANCE_CLASSES, requirements=requirements,
    reference="paper, Sec 4.4",
    reference_values={k: PAPER[k] for k in ("peak_torque_nm", "clearance_angle_rad")},
    variable_names=lambda config: (*(f"r{j}_mm" for j in range(1, config.key_points)),
                                   "kappa_rad", "e_mm"),
))


def __getattr__(name: str) -> Any:
    """The config model and the problem class, imported on first use (the spec names
    them)."""
    if name == "EmbCamConfig":
        return SPEC.config
    if name == "EmbCamProblem":
        return SPEC.problem
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
