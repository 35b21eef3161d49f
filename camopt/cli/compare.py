"""``camopt compare``: runs side by side with a significance test, or a sweep's ranking."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from camopt.cli.app import Format, app, errors
from camopt.cli.console import out
from camopt.cli.layout import (
    compare_rows,
    print_hypervolume,
    print_ranking,
    print_table,
    print_verdicts,
    success_rate_text,
)
from camopt.errors import CamoptError


@app.command()
def compare(runs: Annotated[list[Path], typer.Argument(metavar="RUN...",
                                                       help="run archives, or one sweep")],
            format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
            ) -> None:
    """Compare runs (config differences, designs, statistics, a significance test for two)
    or rank the grid points of a sweep."""
    from camopt import archive
    from camopt.archive.sweeps import load_sweep
    from camopt.reporting import report

    with errors():
        if len(runs) == 1 and archive.archive_kind(runs[0]) == "sweep":
            doc = report.rank_sweep(*load_sweep(runs[0]))
            if format is Format.json:
                sys.stdout.write(json.dumps(doc, indent=2) + "\n")
            else:
                print_ranking(doc)
            return
        if len(runs) < 2:
            raise CamoptError("compare: RUN: give at least two run archives, or one sweep")
        doc = report.compare([archive.load_run(p) for p in runs], raw=True)
    if format is Format.json:
        sys.stdout.write(json.dumps(report.jsonable(doc), indent=2) + "\n")
        return
    names = [Path(p).name for p in doc["runs"]]
    print_verdicts(doc, names)
    print_table("compare", ["", *names], compare_rows(doc),
                numeric=[False, *(True for _ in names)])
    for same in doc["same_objective_different_designs"]:
        i, j = same["runs"]
        out.print(f"[bold]note[/]: {escape(names[i])} and {escape(names[j])} reach one "
                  f"objective ({report.format_value(same['objective'])}) with different "
                  f"designs (differing in {escape(', '.join(same['differ']))}): the "
                  "objective is flat there or has several optima", highlight=False)
    if "hypervolume" in doc:
        print_hypervolume(doc["hypervolume"], names)
    for test in doc["tests"]:
        a, b = escape(names[0]), escape(names[1])
        out.print(f"A = {a}, B = {b}: Mann-Whitney p = {test['p_value']:.3g}, "
                  f"P(A better) = {test['p_a_better']:.2f}; success A "
                  f"{success_rate_text(test['success_a'])}, "
                  f"B {success_rate_text(test['success_b'])}")
        out.print(f"[bold]{escape(test['verdict'])}[/]")


