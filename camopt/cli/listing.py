"""``camopt runs``: the archives of a folder with their case, verdict and date.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import escape, out
from camopt.cli.layout import print_table
from camopt.errors import CamoptError

if TYPE_CHECKING:  # annotations only: archives are read lazily
    from camopt.archive.listing import ArchiveRow


@app.command(name="runs")
def list_runs(folder: Annotated[Path, typer.Argument(help="folder of archives")] = Path("runs"),
              format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
              ) -> None:
    """List the archives in a folder (default runs/), newest first: case, verdict (a run's
    best design against its case's requirements: PASS at nominal, green at or above its
    yield target and amber below it, or FAIL; a sweep's cells done), expected yield,
    objective and date."""
    from camopt import archive
    from camopt.archive.listing import list_archives
    from camopt.core.requirements import GRADE_STYLES
    from camopt.reporting.report import format_value, judged_yield, verdict

    with errors():
        rows = list_archives(folder)
        for row in rows:
            if row["archive"] != "run" or row["verdict"].startswith(("file:", "damaged")):
                continue
            try:  # the requirements' verdict (show's first line); feasibility when unreadable
                view = archive.load_run(row["path"])
                judged = verdict(view)
                y = judged_yield(view)
                row.update({"verdict": judged.verdict or "-", "verdict_grade": judged.grade,
                            "expected_yield": None if y is None else y.value,
                            "yield_target": judged.yield_target})
            except CamoptError:
                pass
    if format is Format.json:
        sys.stdout.write(json.dumps(rows, indent=2) + "\n")
        return
    if not rows:
        out.print(f"no archives in {escape(str(folder))}")
        return
    words = {"pass": "PASS at nominal", "pass at nominal": "PASS at nominal", "fail": "FAIL"}
    cells = [[Path(r["path"]).name + ("" if r["archive"] == "run" else f" ({r['archive']})"),
              r["case"], words.get(r.get("verdict_grade") or "", r["verdict"]),
              yield_cell(r), format_value(r["objective"]),
              r["created"][:16].replace("T", " ")] for r in rows]
    styles = [GRADE_STYLES.get(r.get("verdict_grade") or "") for r in rows]
    # columns when every name fits, else one archive per heading (never a split name)
    print_table(f"{folder}: {len(rows)} archives, newest first (times UTC; green: passes "
                "at nominal with its yield at or above target, amber: below it)",
                ["archive", "case", "verdict", "yield", "objective", "created"], cells,
                numeric=[False, False, False, True, True, False], styles=styles)


def yield_cell(row: ArchiveRow) -> str:
    """``96.3 %``, ``1.3 % < 95 %`` below the yield target, ``-`` without an estimate."""
    value, target = row.get("expected_yield"), row.get("yield_target")
    if value is None:
        return "-"
    if target is not None and value < target:
        return f"{100 * value:.1f} % < {100 * target:g} %"
    return f"{100 * value:.1f} %"
