"""The typer application, its consoles and what every command shares: the one place that
turns camopt's and pydantic's errors into ``error: ...`` and exit code 2.

The command modules import only the standard library, typer and rich at module level;
camopt's models, numpy, scipy, h5py and pydantic are imported inside the commands that use
them, so ``camopt --version`` and ``--help`` start in a fraction of a second
(tests/cli/test_imports.py, bench/bench_startup.py)."""

from __future__ import annotations

import contextlib
import enum
import importlib
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer
from typer.core import TyperGroup

from camopt.cli.console import visible
from camopt.engine import interrupts
from camopt.errors import CamoptError, from_interrupt

if TYPE_CHECKING:
    from camopt.config import LoadedConfig


def non_utf8_argument(args: Sequence[str]) -> str | None:
    """The first argument that is not valid UTF-8 (Python holds its bytes as surrogate
    escapes), shown with those bytes as ``\\xNN``; None when all are valid."""
    for arg in args:
        try:
            arg.encode("utf-8")
        except UnicodeEncodeError:
            return arg.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return None


WORKFLOW = ("init", "validate", "calibrate", "run", "show", "tolerance", "report", "export",
            "plot", "compare", "sweep", "runs", "dashboard", "solvers")
"""``camopt -h`` lists the commands in the order a first hour uses them (README)."""


class WorkflowGroup(TyperGroup):
    """The command group: commands in :data:`WORKFLOW` order (others after, by name), and
    help text as paragraphs, not the docstrings' source line breaks (a terminal of any
    width wraps them). It refuses, before any work, an argument that is not valid UTF-8
    (a path under a folder so named): archives, reports and exports store paths as UTF-8
    text (HDF5 attributes, HTML, JSON), and a run that did all its work and then could
    not record its own path would lose it; docs/reliability.md."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:  # typer's own click Context
        bad = non_utf8_argument(args)
        if bad is not None:
            print(f"error: {bad}: argument: not valid UTF-8 (camopt records paths as UTF-8 "
                  "text); rename the file or folder, or run from inside it with a "
                  "relative path", file=sys.stderr)
            raise SystemExit(2)  # typer's Exit escapes argument parsing as a bug
        return super().parse_args(ctx, args)

    # typer vendors its own click: its Context and Command types, not click's
    def list_commands(self, ctx: Any) -> list[str]:
        names = super().list_commands(ctx)
        rank = {name: i for i, name in enumerate(WORKFLOW)}
        return sorted(names, key=lambda n: (rank.get(n, len(WORKFLOW)), n))

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        command = super().get_command(ctx, cmd_name)
        if command is not None and command.help:
            command.help = unwrap(command.help)
            # the command list shows the first paragraph whole, wrapped (click would
            # cut it at 45 characters)
            command.short_help = command.short_help or command.help.split("\n\n")[0]
        return command


def unwrap(text: str) -> str:
    """``text`` with each paragraph's line breaks replaced by spaces."""
    import inspect

    return "\n\n".join(" ".join(p.split()) for p in inspect.cleandoc(text).split("\n\n"))


COMMANDS = {"init": "catalog", "validate": "catalog", "solvers": "catalog",
            "calibrate": "calibrate", "run": "run", "show": "show", "tolerance": "tolerance",
            "report": "outputs", "export": "outputs", "plot": "outputs",
            "dashboard": "outputs", "compare": "compare", "sweep": "sweep",
            "runs": "listing", "verify": "verify"}
"""Each command's module in :mod:`camopt.cli` (tests/cli/test_imports.py checks that every
command is here and defined where it says)."""


class CommandsOnDemand(typer.Typer):
    """The typer application whose command modules are imported when its commands are
    first asked for: all of them (``--help``, tests' ``CliRunner``), or only the module of
    the command a command line names (:func:`load_commands`, from ``camopt.cli.main``),
    so ``camopt validate`` builds and imports one module's commands, not all 14
    (start-up time)."""

    _chosen = False  # the command modules are imported, or being imported

    @property
    def registered_commands(self) -> list[Any]:
        if not self._chosen:
            load_commands()
        return self._commands

    @registered_commands.setter
    def registered_commands(self, value: list[Any]) -> None:
        self._commands = value


def load_commands(args: Sequence[str] | None = None) -> None:
    """Import the command modules: the one of the command ``args`` start with (a command
    line), else every one (no command first: ``--help``, ``--version``, an unknown name
    that typer lists the commands for, shell completion)."""
    app._chosen = True
    completing = any(k.startswith("_") and k.endswith("_COMPLETE") for k in os.environ)
    names = set(COMMANDS.values())
    if args and args[0] in COMMANDS and not completing:
        names = {COMMANDS[args[0]]}
    for name in sorted(names):
        importlib.import_module(f"camopt.cli.{name}")


# -h as --help on every command; typer's --install-completion / --show-completion
# help as click formats it (rich_markup_mode=None): typer's rich help imports rich's
# Markdown and markdown-it, ~50 % of `camopt --help`'s start-up (bench/bench_startup.py)
app = CommandsOnDemand(cls=WorkflowGroup, rich_markup_mode=None, no_args_is_help=True,
                  add_completion=True,
                  context_settings={"help_option_names": ["-h", "--help"]},
                  help="Batch optimiser for spring-actuated mechanisms.",
                  epilog="Examples: [bold]camopt run configs/CASE.toml[/] (the verdict and "
                  "next: end the output; --verbose for all of it) | [bold]camopt show "
                  "runs/NAME-*.h5[/] | [bold]camopt validate my_case.toml[/] | [bold]camopt "
                  "init KIND > my_case.toml[/] | [bold]camopt tolerance RUN.h5 --samples "
                  "2000[/] | [bold]camopt report RUN.h5[/] | [bold]camopt runs[/]")


def _print_version(value: bool) -> None:
    if value:
        from camopt import __version__

        print(f"camopt {__version__}")
        raise typer.Exit(0)


@app.callback()
def _options(version: Annotated[bool, typer.Option(
        "--version", is_eager=True, callback=_print_version,
        help="print camopt's version and exit")] = False) -> None:
    """Batch optimiser for spring-actuated mechanisms."""


class Format(str, enum.Enum):
    """Output of ``show`` and ``compare``."""

    table = "table"
    json = "json"


@contextlib.contextmanager
def errors() -> Iterator[None]:
    """Print camopt's and pydantic's errors as one line and exit with code 2; Ctrl-C (and
    SIGTERM, see ``main``) as one line and code 130, once temporary files are removed."""
    try:
        yield
    except CamoptError as exc:
        print(f"error: {visible(exc)}", file=sys.stderr)
        raise typer.Exit(2) from None
    except KeyboardInterrupt:
        _interrupted()
    except (typer.Exit, typer.Abort):
        raise
    except Exception as exc:
        if is_click_exception(exc):
            raise
        if from_interrupt(exc):  # a library's own error for an interrupt inside it
            _interrupted()
        if isinstance(exc, MemoryError):
            print("error: out of memory", file=sys.stderr)
            raise typer.Exit(2) from None
        if is_validation_error(exc):
            print(f"error: {visible(str(exc).splitlines()[0])}", file=sys.stderr)
            raise typer.Exit(2) from None
        # a bug: still one line, never a traceback (tests keep it unused)
        print(internal_error(exc), file=sys.stderr)
        raise typer.Exit(2) from None


def _interrupted() -> NoReturn:
    interrupts.handled()
    print("error: interrupted; no archive written", file=sys.stderr)
    raise typer.Exit(130) from None


def is_click_exception(exc: BaseException) -> bool:
    """``exc`` is one of click's own exits, aborts or usage errors, passed on to typer
    (click is not imported to ask: only code that imported it can raise them; typer
    vendors its own click, whose exceptions typer's are)."""
    click = sys.modules.get("click.exceptions")
    return click is not None and isinstance(
        exc, (click.Exit, click.ClickException, click.Abort))


def is_validation_error(exc: BaseException) -> bool:
    """``exc`` is pydantic's ValidationError (pydantic is not imported to ask: a command
    that raised one has imported it)."""
    pydantic = sys.modules.get("pydantic")
    return pydantic is not None and isinstance(exc, pydantic.ValidationError)


INTERNAL = "error: internal error"


def internal_error(exc: BaseException) -> str:
    """The one line for an exception camopt did not expect (a bug to report)."""
    first = (str(exc).splitlines() or [""])[0]
    return f"{INTERNAL}: {type(exc).__name__}: {visible(first)} (please report this)"


def load_case(case: Path, overrides: Sequence[str] | None = None) -> LoadedConfig:
    """A case file validated against every registered case and solver, with archive
    references (e.g. VCB step 2's ``cam_archive``) read."""
    from camopt import archive
    from camopt.engine.setup import load

    return archive.resolve_references(load(case, list(overrides or [])))


