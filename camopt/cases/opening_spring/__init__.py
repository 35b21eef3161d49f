"""40 kA VCB opening spring by the energy method, Ahn, Cho, Park & Kim."""

from __future__ import annotations

from camopt.cases.opening_spring.config import OpeningSpringConfig
from camopt.cases.opening_spring.paper import PAPER
from camopt.cases.opening_spring.problem import OpeningSpringProblem
from camopt.cases.opening_spring.requirements import requirements
from camopt.cases.registry import CaseSpec, register_case

TOLERANCES = {  # docs/assumptions.md, "Default tolerances"
    "k_n_per_mm": "±5%", "l0_mm": "±1",  # spring rate, free length
    "u_mm": "±0.05", "v_mm": "±0.05", "s_mm": "±0.05",  # pivot positions
}

SPEC = register_case(CaseSpec(
    kind="opening_spring", config=OpeningSpringConfig, problem=OpeningSpringProblem,
    default_solver="newton_pp",
    summary="opening spring of a 40 kA VCB for a specified opening motion (energy method)",
    paper_source="Ahn, Cho, Park & Kim, design of a spring-actuated linkage",
    figures="camopt.cases.opening_spring.figures:figures", paper=PAPER,
    tolerances=TOLERANCES, requirements=requirements, reference="original design, Table 1",
))
