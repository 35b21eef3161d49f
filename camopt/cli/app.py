"""The typer application, its consoles and what every command shares: the one place that
turns camopt's and pydantic's errors into ``error: ...`` and exit code 2."""

from __future__ import annotations

import contextlib
import enum
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import typer
from pydantic import ValidationError
from rich.console import Console
from rich.table import Table

from camopt import archive
from camopt.config import LoadedConfig
from camopt.driver import load
from camopt.errors import CamoptError

app = typer.Typer(rich_markup_mode="rich", no_args_is_help=True, add_completion=False,
                  help="Batch optimiser for spring-actuated mechanisms.")
out = Console()
err = Console(stderr=True)


class Format(str, enum.Enum):
    """Output of ``show`` and ``compare``."""

    table = "table"
    json = "json"


@contextlib.contextmanager
def errors() -> Iterator[None]:
    """Print camopt's and pydantic's errors as one line and exit with code 2."""
    try:
        yield
    except (CamoptError, ValidationError) as exc:
        message = str(exc).splitlines()[0] if isinstance(exc, ValidationError) else str(exc)
        print(f"error: {message}", file=sys.stderr)
        raise typer.Exit(2) from None


def load_case(case: Path, overrides: Sequence[str] | None = None) -> LoadedConfig:
    """A case file validated against every registered case and solver, with archive
    references (e.g. VCB step 2's ``cam_archive``) read."""
    return archive.resolve_references(load(case, list(overrides or [])))


def fmt(value: Any) -> str:
    """A table cell: floats to 6 significant digits, lists comma-joined, None as '-'."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(fmt(v) for v in value)
    return "-" if value is None else str(value)


def print_rows(title: str, rows: list[dict[str, Any]], columns: list[str],
               limit: int | None) -> None:
    """A rich table of the given columns (those present); every column is in the JSON."""
    columns = [c for c in columns if c in rows[0]]
    note = "all columns: --format json"
    if limit is not None and len(rows) > limit:
        note = (f"first {limit} of {len(rows)} rows; camopt show for all, "
                "--format json for all columns")
    table = Table(title=f"{title} ({note})")
    for col in columns:
        table.add_column(col, justify="right", overflow="fold")
    for row in rows[:limit]:
        table.add_row(*(fmt(row.get(c)) for c in columns))
    out.print(table)
