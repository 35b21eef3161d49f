"""``camopt show``: a run archive's best design, repeats and table."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from camopt import archive, report
from camopt.cli.app import Format, app, errors, fmt, out, print_rows
from camopt.runview import RunView


@app.command()
def show(run_path: Annotated[Path, typer.Argument(metavar="RUN", help="run archive")],
         format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
         ) -> None:
    """Show a run archive: best design, metrics, repeats, table."""
    with errors():
        view = archive.load_run(run_path)
    if format is Format.json:
        sys.stdout.write(json.dumps(report.show(view), indent=2) + "\n")
    else:
        print_show(view)


def print_show(view: RunView, rows: int | None = None) -> None:
    """The run summary as rich tables."""
    doc = report.show(view)
    best = doc["best"]
    out.print(f"[bold]{escape(view.path)}[/]  case [cyan]{escape(view.kind)}[/], "
              f"solver [cyan]{escape(view.solver_name)}[/]")
    head = Table(title="best design", show_header=False)
    head.add_row("objective", fmt(best["objective"]))
    head.add_row("feasible", fmt(best["feasible"]))
    head.add_row("active constraints", ", ".join(best.get("active", [])) or "none")
    if best.get("violated"):
        head.add_row("violated constraints", ", ".join(best["violated"]))
    for k, v in {**best["x"], **best["metrics"]}.items():
        head.add_row(k, fmt(v))
    out.print(head)
    # the 19-digit seeds are in --format json; the table names repeats by spawn key
    reps = Table(title="repeats (repeat k: child k of SeedSequence(run.seed))")
    columns = ("objective", "feasible", "nfev", "converged_nit")
    for col in ("repeat", *columns, "wall_s"):
        reps.add_column(col, justify="right")
    for r in doc["repeats"]:
        reps.add_row(fmt(r["spawn_key"]), *(fmt(r[c]) for c in columns), f"{r['wall_s']:.2f}")
    out.print(reps)
    for i, r in enumerate(doc["repeats"]):
        for note in r["notes"]:
            out.print(f"[bold]note[/] (repeat {i}): {escape(note)}")
    if doc["table"]:
        columns = ["label", *best["x"], view.objective_name, "feasible", "active", "violated"]
        print_rows("table", doc["table"], columns, rows)
