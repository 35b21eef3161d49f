"""Fast acting switch, Clauss & Papalambros (1982): minimum closure time of a slider crank."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from camopt.cases.fast_switch.paper import OPTIMUM, PAPER
from camopt.cases.fast_switch.requirements import requirements
from camopt.cases.registry import (
    CaseSpec,
    ToleranceClass,
    config_at,
    problem_at,
    register_case,
)

if TYPE_CHECKING:  # imported on first use: __getattr__ below
    from camopt.cases.fast_switch.config import FastSwitchConfig as FastSwitchConfig
    from camopt.cases.fast_switch.problem import FastSwitchProblem as FastSwitchProblem

TOLERANCES = {  # docs/assumptions.md, "Default tolerances"
    "sud_mm": "±1",  # undeformed (free) spring length
    "sf_mm": "±0.1", "s0_mm": "±0.1",  # installed lengths, set by machined stops
    "r2_mm": "±0.05", "r3_mm": "±0.05",  # link lengths
    # the spring as made (assumed): drawn wire and coiled diameter; through d^4 / D^3 they
    # move its rate by about ±4 % and ±3 % (R13) and its stress (R14/R15)
    "case.wire_diameter_mm": "±0.02", "case.spring_diameter_mm": "±1%",
}
TOLERANCE_CLASSES = {
    "graded": ToleranceClass(
        {**TOLERANCES, "sud_mm": "±0.5", "case.wire_diameter_mm": "±0.01",
         "case.spring_diameter_mm": "±0.5%"},
        source="springs coiled from selected wire and graded by force at a test length: "
        "half the standard class's free length, wire and coil diameter tolerances",
        relative_cost=1.3),
}

SPEC = register_case(CaseSpec(
    kind="fast_switch", config=config_at("camopt.cases.fast_switch.config:FastSwitchConfig"),
    problem=problem_at("camopt.cases.fast_switch.problem:FastSwitchProblem"),
    default_solver="enumeration",
    summary="minimum closure time of a spring-driven slider-crank switch",
    paper_source="Clauss & Papalambros (1982), UM-MEAM-81-3",
    figures="camopt.cases.fast_switch.figures:figures", paper=PAPER, tolerances=TOLERANCES,
    tolerance_classes=TOLERANCE_CLASSES,
    requirements=requirements, reference="paper's optimum, Eq 92", reference_values=OPTIMUM,
    variable_names=lambda config: ("coils", "sf_mm", "sud_mm", "s0_mm", "r3_mm", "r2_mm"),
))


def __getattr__(name: str) -> Any:
    """The config model and the problem class, imported on first use (the spec names
    them)."""
    if name == "FastSwitchConfig":
        return SPEC.config
    if name == "FastSwitchProblem":
        return SPEC.problem
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
