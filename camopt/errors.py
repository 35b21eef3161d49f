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


def from_interrupt(exc: BaseException) -> bool:
    """Whether ``exc`` is, or came of, a KeyboardInterrupt (Ctrl-C, or SIGTERM as the CLI
    raises it): libraries turn one landing inside them into their own errors (h5py a
    SystemError in its callbacks, an extension module an ImportError from its
    initialisation), which must still read as an interruption, not a damaged archive or
    an internal error."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return True
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return False
