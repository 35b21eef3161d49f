"""Case files: pydantic models and the TOML loader. Nothing else in camopt reads TOML.

The names below are loaded from their modules on first use (PEP 562), so a command that
reads only ``camopt.config.raw``'s types (``show`` of a run archive) does not build the
config models."""

from __future__ import annotations

from typing import TYPE_CHECKING

from camopt.lazy import lazy_names

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


__getattr__ = lazy_names(globals(), _HOME)
