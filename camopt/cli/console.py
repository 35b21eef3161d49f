"""The consoles every command prints to (results on stdout, progress and errors on
stderr) and the one cell format of plain tables."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

from rich.console import Console
from rich.markup import escape

# no emoji codes: rich would print a path such as ':smile:.toml' as an emoji (what
# camopt prints is file names, quantities and markup it escapes, never an emoji)
out = Console(emoji=False)
err = Console(stderr=True, emoji=False)


@contextlib.contextmanager
def rows_bar(label: str, quiet: bool) -> Iterator[Callable[[int, int], None] | None]:
    """A rich progress bar on stderr over rows evaluated (``camopt.core.batch.RowsDone``:
    rows done, rows in all), or None with ``--quiet`` or when stderr is not a terminal
    (a pipe or a log file gets no bar)."""
    if quiet or not err.is_terminal:
        yield None
        return
    from rich import progress as rp

    with rp.Progress(rp.TextColumn(escape(label)), rp.BarColumn(), rp.MofNCompleteColumn(),
                  rp.TimeElapsedColumn(), rp.TimeRemainingColumn(), console=err,
                  transient=True) as bar:
        task = bar.add_task(label, total=None)

        def rows_done(done: int, total: int) -> None:
            bar.update(task, total=total, completed=done)

        yield rows_done


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

