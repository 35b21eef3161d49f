"""Command-line interface: thin typer commands, one module each, over one function each."""

from __future__ import annotations

from camopt.cli import catalog, compare, outputs, run, show, sweep  # noqa: F401  (commands)
from camopt.cli.app import app


def main() -> None:
    """Console-script entry point."""
    app()


__all__ = ["app", "main"]
