"""40 kA VCB opening spring by the energy method, Ahn, Cho, Park & Kim."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from camopt.cases.opening_spring.paper import PAPER
from camopt.cases.opening_spring.requirements import requirements
from camopt.cases.registry import (
    CaseSpec,
    ToleranceClass,
    config_at,
    problem_at,
    register_case,
)

if TYPE_CHECKING:  # imported on first use: __getattr__ below
    from camopt.cases.opening_spring.config import OpeningSpringConfig as OpeningSpringConfig
    from camopt.cases.opening_spring.problem import OpeningSpringProblem as OpeningSpringProblem

TOLERANCES = {  # class "standard", docs/tolerance.md, "Tolerance classes"
    "k_n_per_mm": "±10%", "l0_mm": "±1",  # ungraded spring: rate, free length
    "u_mm": "±0.05", "v_mm": "±0.05", "s_mm": "±0.05",  # pivot positions
}
TOLERANCE_CLASSES = {
    "graded": ToleranceClass(
        {**TOLERANCES, "k_n_per_mm": "±5%", "l0_mm": "±0.5"},
        source="spring graded by force at a test length, free length held to half",
        relative_cost=1.3),
}

SPEC = register_case(CaseSpec(
    kind="opening_spring",
    config=config_at("camopt.cases.opening_spring.config:OpeningSpringConfig"),
    problem=problem_at("camopt.cases.opening_spring.problem:OpeningSpringProblem"),
    default_solver="newton_pp",
    summary="opening spring of a 40 kA VCB for a specified opening motion (energy method)",
    paper_source="Ahn, Cho, Park & Kim, design of a spring-actuated linkage",
    figures="camopt.cases.opening_spring.figures:figures", paper=PAPER,
    tolerances=TOLERANCES, tolerance_classes=TOLERANCE_CLASSES, requirements=requirements,
    reference="original design, Table 1",
    variable_names=lambda config: tuple(config.free),
))


def __getattr__(name: str) -> Any:
    """The config model and the problem class, imported on first use (the spec names
    them)."""
    if name == "OpeningSpringConfig":
        return SPEC.config
    if name == "OpeningSpringProblem":
        return SPEC.problem
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
