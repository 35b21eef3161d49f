"""``camopt runs``: the archives of a folder with their case, verdict and date."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import escape, out
from camopt.cli.layout import print_table


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
                row["verdict"] = verdict(archive.load_run(row["path"])).verdict or "-"
            except CamoptError:
                pass
    if format is Format.json:
        sys.stdout.write(json.dumps(rows, indent=2) + "\n")
        return
    if not rows:
        out.print(f"no archives in {escape(str(folder))}")
        return
    cells = [[Path(r["path"]).name + ("" if r["archive"] == "run" else f" ({r['archive']})"),
              r["case"], r["verdict"], format_value(r["objective"]),
              r["created"][:16].replace("T", " ")] for r in rows]
    # columns when every name fits, else one archive per heading (never a split name)
    print_table(f"{folder}: {len(rows)} archives, newest first (times UTC)",
                ["archive", "case", "verdict", "objective", "created"], cells,
                numeric=[False, False, False, True, False])
