"""Case files: pydantic models and the TOML loader. Nothing else in camopt reads TOML.

The names below are loaded from their modules on first use (PEP 562), so a command that
reads only ``camopt.config.raw``'s types (``show`` of a run archive) does not build the
config models."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from camopt.config.loader import LoadedConfig, load_config, parse_overrides, validate_data
    from camopt.config.models import CaseConfig, RunSection, SolverOptions, template

_HOME = {
    **dict.fromkeys(("LoadedConfig", "load_config", "parse_overrides", "validate_data"),
                    "loader"),
    **dict.fromkeys(("CaseConfig", "RunSection", "SolverOptions", "template"), "models"),
}

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
assert sorted(__all__) == sorted(_HOME)


def __getattr__(name: str) -> Any:
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module 'camopt.config' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"camopt.config.{module}"), name)
    globals()[name] = value  # once: later lookups are plain attribute reads
    return value
