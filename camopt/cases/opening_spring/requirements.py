"""What a VCB opening spring must meet: Ahn, Cho, Park & Kim state no acceptance limit
beyond the desired motion itself (Eq 7), which the design mode tracks as its objective,
and the run's constraints (spring in tension, stroke reachable). So the case declares no
requirement of its own; the verdict is the run's constraints (``camopt.reporting.report``)."""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

from camopt.core.requirements import Requirement


def requirements(case: Mapping[str, Any], names: Collection[str]) -> tuple[Requirement, ...]:
    """None: see the module's docstring."""
    return ()
