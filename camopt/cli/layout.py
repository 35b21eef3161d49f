"""One table layout for every command: columns when every word fits the console, else a
vertical ``name: value`` layout; a word (a header, a number, a name with underscores) is
never split across lines.

Cells are plain text (markup escaped here); rich wraps a column only at spaces, so a table
is drawn as columns when the longest word of each column, padded, fits the console's width.
"""

from __future__ import annotations

from collections.abc import Sequence

from rich.markup import escape
from rich.table import Table

from camopt.cli.app import out

BORDER = 3
"""Characters a column adds to its text: a rule and a space each side."""


def _longest_word(text: str) -> int:
    return max((len(w) for w in text.split()), default=0)


def fits(columns: Sequence[str], rows: Sequence[Sequence[str]], width: int) -> bool:
    """Whether the columns fit ``width`` with every column as wide as its longest word
    (header included; a cell of a right-justified number is one word)."""
    need = 1 + sum(BORDER + max(_longest_word(c), *(_longest_word(r[i]) for r in rows))
                   for i, c in enumerate(columns)) if rows else 0
    return need <= width


def print_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]],
                numeric: Sequence[bool] | None = None, styles: Sequence[str | None] = (),
                sections: Sequence[int] = ()) -> None:
    """Print ``rows`` of plain-text cells under ``columns``: as a table when it fits the
    console without splitting a word, else vertically (the first cell as a heading, then
    its ``column: value`` pairs, wrapped at spaces). ``numeric`` right-justifies columns;
    ``styles`` colours whole rows (``"red"``); ``sections`` are row indices a rule goes
    before."""
    numeric = list(numeric) if numeric is not None else [i > 0 for i in range(len(columns))]
    styles = list(styles) + [None] * (len(rows) - len(styles))
    if title:  # a line of its own: a table's title wraps at the table's width
        out.print(f"[italic]{escape(title)}[/]", highlight=False)
    if fits(columns, rows, out.width):
        table = Table()
        for c, num in zip(columns, numeric):
            table.add_column(escape(c), justify="right" if num else "left",
                             overflow="fold" if not num else "ellipsis", no_wrap=num)
        for i, row in enumerate(rows):
            if i in sections and i:
                table.add_section()
            table.add_row(*(escape(c) for c in row), style=styles[i])
        out.print(table)
        return
    for i, row in enumerate(rows):
        style = styles[i]
        head = escape(row[0]) if row else ""
        out.print(f"[bold]{head}[/]" if style is None else f"[bold {style}]{head}[/]",
                  highlight=False, soft_wrap=True)
        pairs = "; ".join(f"{escape(c)}: {escape(v)}" for c, v in zip(columns[1:], row[1:]))
        out.print(f"  {pairs}", highlight=False)  # wraps at spaces, never inside a word
