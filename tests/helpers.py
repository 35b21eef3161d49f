"""Test helpers shared across modules."""

from __future__ import annotations

from pathlib import Path

from camopt.config import LoadedConfig
from camopt.engine.driver import load as load_case_file


def load(path: str | Path, *overrides: str) -> LoadedConfig:
    """Load a case file with every registered case and solver available."""
    return load_case_file(path, list(overrides))
