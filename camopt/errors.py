"""Error types. Only the CLI catches them; everything else builds a message and raises.

difflib is imported where a suggestion is made (every command imports this module)."""

from __future__ import annotations

from collections.abc import Iterable


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


def did_you_mean(word: str, known: Iterable[str]) -> str:
    """``" (did you mean 'l1_mm'?)"`` for the known name closest to a mistyped ``word``
    (difflib's ratio at least 0.6, or the same name in another case: ``L1_mm``), else
    ''. A unit typed wrong (``l1_m`` for ``l1_mm``) is one such near name."""
    import difflib

    names = list(known)
    match = difflib.get_close_matches(word, names, n=1, cutoff=0.6)
    if not match:
        match = [n for n in names if n.lower() == word.lower()][:1]
    return f" (did you mean {match[0]!r}?)" if match else ""
