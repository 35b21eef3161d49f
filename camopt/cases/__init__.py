"""Mechanisms: one package per case, each registering a :class:`CaseSpec`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from camopt.cases.registry import (
    CaseSpec,
    OverlayCurve,
    ProfileCircle,
    ProfileCurve,
    case_configs,
    cases,
    get_case,
    register_case,
    run_requirements,
)

if TYPE_CHECKING:
    from camopt.config.models import CaseConfig
    from camopt.core.problem import Problem


def build_problem(config: CaseConfig) -> Problem:
    """The Problem for a validated case config."""
    return get_case(config.kind).build(config)


__all__ = ["CaseSpec", "OverlayCurve", "ProfileCircle", "ProfileCurve", "build_problem",
           "case_configs", "cases", "get_case", "register_case", "run_requirements"]
