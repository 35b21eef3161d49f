"""``camopt runs``: the archives of a folder with their case, verdict and date."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from camopt.cli.app import Format, app, errors
from camopt.cli.console import out


@app.command(name="runs")
def list_runs(folder: Annotated[Path, typer.Argument(help="folder of archives")] = Path("runs"),
              format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
              ) -> None:
    """List the archives in a folder (default runs/), newest first: case, verdict (a run's
    best design against its case's requirements, pass or fail; a sweep's cells done),
    objective and date."""
    from camopt import archive
    from camopt.archive.listing import list_archives
    from camopt.errors import CamoptError
    from camopt.reporting.report import format_value, verdict

    with errors():
        rows = list_archives(folder)
        for row in rows:
            if row["archive"] != "run" or row["verdict"].startswith(("file:", "damaged")):
                continue
            try:  # the requirements' verdict (show's first line); feasibility when unreadable
                row["verdict"] = verdict(archive.load_run(row["path"]))["verdict"] or "-"
            except CamoptError:
                pass
    if format is Format.json:
        sys.stdout.write(json.dumps(rows, indent=2) + "\n")
        return
    if not rows:
        out.print(f"no archives in {escape(str(folder))}")
        return
    table = Table(title=escape(f"{folder}: {len(rows)} archives, newest first"),
                  title_justify="left")
    table.add_column("archive", overflow="fold")
    table.add_column("case", overflow="fold")
    table.add_column("verdict", overflow="fold")
    table.add_column("objective", justify="right", no_wrap=True)
    table.add_column("created (UTC)", no_wrap=True)
    for r in rows:
        kind = "" if r["archive"] == "run" else f" ({r['archive']})"
        table.add_row(escape(Path(r["path"]).name + kind), escape(r["case"]),
                      escape(r["verdict"]), escape(format_value(r["objective"])),
                      escape(r["created"][:16].replace("T", " ")))
    out.print(table)
