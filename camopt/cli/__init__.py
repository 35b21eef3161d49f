"""Command-line interface: thin typer commands, one module each, over one function each."""

from __future__ import annotations

from camopt.cli import (  # noqa: F401  (commands)
    catalog,
    compare,
    outputs,
    run,
    show,
    sweep,
    tolerance,
)
from camopt.cli.app import app


def main() -> None:
    """Console-script entry point."""
    app()


__all__ = ["app", "main"]
