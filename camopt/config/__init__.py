"""Case files: pydantic models and the TOML loader. Nothing else in camopt reads TOML."""

from __future__ import annotations

from camopt.config.loader import LoadedConfig, load_config, parse_overrides, validate_data
from camopt.config.models import CaseConfig, RunSection, SolverOptions, template

__all__ = [
    "CaseConfig",
    "LoadedConfig",
    "RunSection",
    "SolverOptions",
    "load_config",
    "parse_overrides",
    "template",
    "validate_data",
]
