"""Holding Ctrl-C and SIGTERM back while finished work is being saved.

A run interrupted after its repeats have finished (or while its archive is being written)
still has everything to save; a signal arriving then must not discard it, and neither must
a second Ctrl-C pressed because the first seemed slow. Inside :func:`deferred` SIGINT and
SIGTERM are only noted; the caller finishes writing and then reports the interruption
(exit 130) with the archive kept."""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_pending = False
_installed = False  # the CLI's handlers are in place (not when camopt is a library)


def _interrupt(signum: int, frame: object) -> None:
    global _pending
    _pending = True  # kept in case the exception lands where Python ignores it
    raise KeyboardInterrupt


def install() -> None:
    """Ctrl-C and SIGTERM raise KeyboardInterrupt (SIGTERM unwinds like Ctrl-C, so
    temporary files are removed) and are remembered: Python ignores an exception raised
    inside a weakref callback or ``__del__``, and a signal landing there would be lost;
    :func:`check` raises it again at the next safe point."""
    global _installed
    for s in _SIGNALS:
        signal.signal(s, _interrupt)
    global _previous_hook
    if sys.unraisablehook is not _quiet_unraisable:
        _previous_hook, sys.unraisablehook = sys.unraisablehook, _quiet_unraisable
    _installed = True


_previous_hook: Callable[[Any], object] = sys.__unraisablehook__  # gets every other report


def _quiet_unraisable(unraisable: Any) -> None:
    """Python's report of an exception it could not raise (in a weakref callback,
    ``__del__``), without the one a signal raised there: that one is remembered
    (:func:`check` raises it again), and its traceback on stderr would be a second
    message beside camopt's one line."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        return
    _previous_hook(unraisable)


def check() -> None:
    """Raise KeyboardInterrupt if a signal arrived that no handler has dealt with (call
    between units of work: iterations, cells, chunks of rows)."""
    if _pending:
        raise KeyboardInterrupt


def pending() -> bool:
    """Whether a signal arrived that no handler has dealt with."""
    return _pending


def checked(progress: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
    """A row-chunk progress callback (``camopt.core.batch.RowsDone``) that first calls
    :func:`check`: a long evaluation in chunks (``camopt tolerance``) stops at the next
    chunk for a signal whose exception Python dropped (one landing in an import lock's
    callback)."""
    def told(done: int, total: int) -> None:
        check()
        if progress is not None:
            progress(done, total)

    return told


def handled() -> None:
    """The interruption has been dealt with (called where KeyboardInterrupt is caught).
    In the CLI, SIGINT and SIGTERM are ignored from here on: all the process still does is
    keep what it has (already inside :func:`deferred`) and report it. A second Ctrl-C
    pressed then used to land after the report, while Python was exiting (its own
    handlers already removed), and killed the process by SIGINT instead of exit 130.
    ``SIG_IGN`` is what outlives Python's shutdown; SIGKILL still ends a stuck exit."""
    global _pending
    _pending = False
    if _ignored():
        _forget_unhandled()


def _ignored() -> bool:
    """SIGINT and SIGTERM ignored from here on, in the CLI's main thread; whether so."""
    if not (_installed and threading.current_thread() is threading.main_thread()):
        return False
    for s in _SIGNALS:
        signal.signal(s, signal.SIG_IGN)
    return True


def _forget_unhandled() -> None:
    """Clear CPython's note of an unhandled KeyboardInterrupt. CPython 3.10 and 3.11 set it
    where a KeyboardInterrupt leaves code CPython runs itself (``PyRun_*``, module
    execution) and catching the exception higher up does not clear it: at exit the process
    then killed itself by SIGINT (exit -2 for a Python caller, 130 in a shell) after camopt
    had reported the interruption and chosen 130 (seen under strace; 8 of 60 SIGTERMs
    0.2-0.45 s into ``camopt tolerance``; which code set it was not traced). Where the
    symbol is not exported (a static build, CPython 3.12+'s runtime state) nothing is
    done."""
    try:
        import ctypes

        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0
    except (ImportError, AttributeError, ValueError, OSError):
        pass


def finished() -> None:
    """The command is over: its output is written or its error reported. SIGINT and
    SIGTERM are ignored from here on (as after :func:`handled`): Python's finalisation
    restores their default actions, and a signal landing then killed a process whose
    work was complete by the signal."""
    _ignored()


@contextlib.contextmanager
def deferred() -> Iterator[list[int]]:
    """SIGINT and SIGTERM noted, not raised, while the block runs; yields the list the
    signal numbers received are appended to (empty if none). Nests; a no-op outside the
    main thread (where Python cannot set handlers)."""
    got: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield got
        return

    def note(signum: int, frame: object) -> None:
        got.append(signum)

    old = {s: signal.signal(s, note) for s in _SIGNALS}
    try:
        yield got
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)
