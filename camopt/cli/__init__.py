"""Command-line interface: thin typer commands, one module each, over one function each.

The command modules are imported when the application's commands are first asked for
(:class:`camopt.cli.app.CommandsOnDemand`): ``camopt CMD`` imports CMD's module only."""

from __future__ import annotations

import gc
import os
import sys
import warnings

from camopt.cli.app import app, internal_error, load_commands
from camopt.cli.console import OutputError, checked_stdout, visible
from camopt.core import perf
from camopt.engine import interrupts
from camopt.errors import from_interrupt


def main() -> None:
    """Console-script entry point: BLAS on one thread before numpy loads
    (:func:`camopt.core.perf.one_blas_thread_on_load`), pydantic's plugin look-up off
    (:func:`camopt.core.perf.no_pydantic_plugins`); SIGTERM handled like Ctrl-C;
    whatever escapes a command (a closed pipe, a bug) is still one line, never a
    traceback."""
    perf.one_blas_thread_on_load()
    perf.no_pydantic_plugins()
    # a design that does not assemble is data (NaN), judged by the verdict: numpy's
    # 'invalid value' warnings, with source paths, are no message to a user
    warnings.simplefilter("ignore", RuntimeWarning)
    try:
        # from the handlers on, a signal while the command's modules load is exit 130 too
        try:
            interrupts.install()
            checked_stdout()
            unknown = unknown_command(sys.argv[1:])
            if unknown:
                print(unknown, file=sys.stderr)
                sys.exit(2)
            if not starts_only(sys.argv[1:]):
                gc.enable()  # off from camopt.__main__: a computing command collects cycles
            load_commands(sys.argv[1:])
            try:
                if sys.argv[1:] == ["solvers"]:
                    # nothing to parse: the stored listing, without typer's parameter
                    # conversion (it imports pydantic: 1.4x `import numpy, scipy`)
                    from camopt.cli.catalog import list_solvers

                    list_solvers()
                    sys.exit(0)  # as typer ends every command
                app(standalone_mode=True)
            finally:
                # the buffered rest goes out now, where a failure is one line (at exit,
                # Python would print it as an ignored exception, or not at all)
                sys.stdout.flush()
        except SystemExit as exc:
            if exc.code == 130 and interrupts.pending():
                # typer's own exit for a KeyboardInterrupt that left its parsing or a
                # command's imports, silent: camopt's one line, as for any interruption
                _say_interrupted()
            raise
        except OutputError as exc:  # printed outside a command's errors(): stdout failed
            print(f"error: {visible(exc)}", file=sys.stderr)
            sys.exit(2)
        except KeyboardInterrupt:
            _say_interrupted()
            sys.exit(130)
        except BrokenPipeError:  # `camopt show ... | head`: the reader left; not an error
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            sys.exit(0)
        except Exception as exc:
            if from_interrupt(exc):  # a library's own error for an interrupt inside it
                _say_interrupted()
                sys.exit(130)
            print(internal_error(exc), file=sys.stderr)
            sys.exit(2)
    finally:
        # the command is over, its output written or its error reported: a signal
        # landing while Python exits (which restores the default actions) would
        # kill a finished process by the signal
        interrupts.finished()


def _say_interrupted() -> None:
    interrupts.handled()
    print("error: interrupted", file=sys.stderr)


STARTS_ONLY = frozenset({"validate", "show", "runs", "compare", "init", "solvers"})
"""Commands that read a file or two and print (at most ``show`` of an older archive
estimates a yield on 300 draws, ``compare`` tests two runs): short-lived, they run with
the cyclic garbage collector as ``camopt.__main__`` left it (off); every other command,
which evaluates or draws figures for as long as it takes, turns it on first."""


def starts_only(args: list[str]) -> bool:
    """Whether the command line ``args`` is help, the version or a :data:`STARTS_ONLY`
    command (no command first: ``--help``, ``--version``, no arguments)."""
    return not args or args[0].startswith("-") or args[0] in STARTS_ONLY


SYNONYMS = {"verify": "validate", "check": "validate", "list": "runs", "optimise": "run",
            "optimize": "run", "summary": "show", "html": "report", "dxf": "export"}
"""Words a user may type for a command (the did-you-mean of a mistyped one)."""


def unknown_command(args: list[str]) -> str | None:
    """One ``error:`` line for a mistyped command (``camopt verfy``) with the nearest
    command names (difflib), or None when the first argument is a command or an option."""
    import difflib

    from camopt.cli.app import COMMANDS

    if not args or args[0].startswith("-") or args[0] in COMMANDS:
        return None
    words = {**{c: c for c in COMMANDS}, **SYNONYMS}
    near = list(dict.fromkeys(words[w] for w in difflib.get_close_matches(
        args[0], sorted(words), n=3, cutoff=0.5)))[:2]
    hint = (f"; did you mean {' or '.join(repr(n) for n in near)}?" if near
            else f"; commands: {', '.join(sorted(COMMANDS))}")
    return f"error: camopt: {args[0]}: unknown command{hint} (camopt --help)"


__all__ = ["app", "main"]
