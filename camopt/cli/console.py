"""The consoles every command prints to (results on stdout, progress and errors on
stderr) and the one cell format of plain tables."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.markup import escape

out = Console()
err = Console(stderr=True)


def fmt(value: Any) -> str:
    """A table cell: floats to 6 significant digits, lists comma-joined, None as '-'."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(fmt(v) for v in value)
    return "-" if value is None else escape(str(value))  # labels may hold [markup]


def plain(value: Any) -> str:
    """:func:`fmt` without markup escaping (the layout escapes)."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(plain(v) for v in value)
    return "-" if value is None else str(value)

