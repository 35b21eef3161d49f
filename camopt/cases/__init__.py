"""One module per mechanism; each builds a Problem from its config."""

from __future__ import annotations

from collections.abc import Callable

from camopt.config.models import CaseConfig
from camopt.problem import Problem


def _fast_switch(config: CaseConfig) -> Problem:
    from camopt.cases.fast_switch import FastSwitchProblem

    return FastSwitchProblem(config)  # type: ignore[arg-type]


def _vcb(config: CaseConfig) -> Problem:
    from camopt.cases.vcb import VcbProblem

    return VcbProblem(config)  # type: ignore[arg-type]


def _vcb_identify(config: CaseConfig) -> Problem:
    from camopt.cases.vcb_identify import VcbIdentification

    return VcbIdentification(config)  # type: ignore[arg-type]


def _opening_spring(config: CaseConfig) -> Problem:
    from camopt.cases.opening_spring import OpeningSpringProblem

    return OpeningSpringProblem(config)  # type: ignore[arg-type]


def _emb_cam(config: CaseConfig) -> Problem:
    from camopt.cases.emb_cam import EmbCamProblem

    return EmbCamProblem(config)  # type: ignore[arg-type]


CASE_BUILDERS: dict[str, Callable[[CaseConfig], Problem]] = {
    "emb_cam": _emb_cam,
    "opening_spring": _opening_spring,
    "fast_switch": _fast_switch,
    "vcb": _vcb,
    "vcb_identify": _vcb_identify,
}
CASE_CLASSES: dict[str, str] = {
    "emb_cam": "camopt.cases.emb_cam:EmbCamProblem",
    "opening_spring": "camopt.cases.opening_spring:OpeningSpringProblem",
    "fast_switch": "camopt.cases.fast_switch:FastSwitchProblem",
    "vcb": "camopt.cases.vcb:VcbProblem",
    "vcb_identify": "camopt.cases.vcb_identify:VcbIdentification",
}


def build_problem(config: CaseConfig) -> Problem:
    """The Problem for a validated case config."""
    return CASE_BUILDERS[config.kind](config)


def case_class(kind: str) -> type[Problem]:
    """The Problem class of a case kind (to ask which capabilities it offers)."""
    import importlib

    module, _, name = CASE_CLASSES[kind].partition(":")
    return getattr(importlib.import_module(module), name)

DEFAULT_SOLVER: dict[str, str] = {"fast_switch": "enumeration", "vcb": "de_gr",
                                 "opening_spring": "newton_pp",
                                 "emb_cam": "pso",
                                 "vcb_identify": "de_gr"}
"""The solver a new case file of each kind starts with (the paper's method)."""
