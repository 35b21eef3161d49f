"""Command-line interface: thin typer commands, one module each, over one function each.

The command modules are imported when the application's commands are first asked for
(:class:`camopt.cli.app.CommandsOnDemand`): ``camopt CMD`` imports CMD's module only."""

from __future__ import annotations

import os
import sys

from camopt.cli.app import app, internal_error, load_commands
from camopt.core import perf
from camopt.engine import interrupts


def main() -> None:
    """Console-script entry point: BLAS on one thread before numpy loads
    (:func:`camopt.core.perf.one_blas_thread_on_load`); SIGTERM handled like Ctrl-C;
    whatever escapes a command (a closed pipe, a bug) is still one line, never a
    traceback."""
    perf.one_blas_thread_on_load()
    interrupts.install()
    load_commands(sys.argv[1:])
    try:
        if sys.argv[1:] == ["solvers"]:
            # nothing to parse: the stored listing, without typer's parameter conversion
            # (it imports pydantic: 1.4x `import numpy, scipy` for any typer command)
            from camopt.cli.catalog import list_solvers

            list_solvers()
            sys.exit(0)  # as typer ends every command
        app(standalone_mode=True)
    except SystemExit:
        raise
    except KeyboardInterrupt:
        interrupts.handled()
        print("error: interrupted", file=sys.stderr)
        sys.exit(130)
    except BrokenPipeError:  # `camopt show ... | head`: the reader left; not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(0)
    except Exception as exc:
        print(internal_error(exc), file=sys.stderr)
        sys.exit(2)


__all__ = ["app", "main"]
