"""Error types. Only the CLI catches them; everything else builds a message and raises."""

from __future__ import annotations


class CamoptError(Exception):
    """Base of every error camopt raises on purpose."""


class ConfigError(CamoptError, ValueError):
    """A case file or override is wrong: ``<file>: <key or line>: <what is wrong>``."""

    def __init__(self, source: str, where: str, what: str) -> None:
        self.source, self.where, self.what = source, where, what
        super().__init__(f"{source}: {where}: {what}")


class SolverError(CamoptError, RuntimeError):
    """A solver cannot run on a case, or failed while running."""


class ArchiveError(CamoptError, OSError):
    """A run archive cannot be written or is not a camopt archive."""
