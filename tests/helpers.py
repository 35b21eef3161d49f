"""Test helpers shared across modules."""

from __future__ import annotations

from pathlib import Path

from camopt.config import LoadedConfig, load_config
from camopt.solvers import solvers


def load(path: str | Path, *overrides: str) -> LoadedConfig:
    """Load a case file with every registered solver available."""
    return load_config(path, {n: c.Options for n, c in solvers().items()}, list(overrides))
