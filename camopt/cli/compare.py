"""``camopt compare``: runs side by side with a significance test, or a sweep's ranking.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Annotated

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import escape, out
from camopt.cli.layout import (
    compare_rows,
    print_hypervolume,
    print_ranking,
    print_table,
    print_verdicts,
    success_rate_text,
)
from camopt.errors import CamoptError, ConfigError


@app.command()
def compare(runs: Annotated[list[Path], typer.Argument(metavar="RUN...",
                                                       help="run archives, or one sweep")],
            format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
            equivalence: Annotated[float | None, typer.Option(
                min=0, help="practical-equivalence threshold in the objective's unit, a "
                "finite number >= 0 (default: the case's, else 0.1% of the larger "
                "median)")] = None,
            ) -> None:
    """Compare runs (config differences, designs, statistics, a significance test for two)
    or rank the grid points of a sweep."""
    from camopt import archive
    from camopt.config.models import unit_of
    from camopt.reporting import report

    with errors():
        if equivalence is not None and not math.isfinite(equivalence):
            raise ConfigError("--equivalence", str(equivalence), "a finite threshold >= 0 "
                              "in the objective's unit")
        if len(runs) == 1 and archive.archive_kind(runs[0]) == "sweep":
            from camopt.archive.sweeps import load_sweep

            doc = report.rank_sweep(*load_sweep(runs[0]))
            if format is Format.json:
                sys.stdout.write(json.dumps(doc.to_json(), indent=2) + "\n")
            else:
                print_ranking(doc)
            return
        if len(runs) < 2:
            raise CamoptError("compare: RUN: give at least two run archives, or one sweep")
        comparison = report.compare([archive.load_run(p) for p in runs],
                                    equivalence=equivalence)
    if format is Format.json:
        sys.stdout.write(json.dumps(comparison.to_json(), indent=2) + "\n")
        return
    labels = comparison.labels
    for label, path in zip(labels, comparison.runs):
        out.print(f"[bold]{label}[/] = {escape(str(path))}", highlight=False, soft_wrap=True)
    print_verdicts(comparison.verdicts, labels)
    print_table("compare", ["", *labels], compare_rows(comparison),
                numeric=[False, *(True for _ in labels)])
    for same in comparison.same_objective_different_designs:
        i, j = same.runs
        out.print(f"[bold]note[/]: {labels[i]} and {labels[j]} reach one objective "
                  f"({report.format_value(same.objective)}) with different designs "
                  f"(differing in {escape(', '.join(same.differ))}): the objective is "
                  "flat there or has several optima", highlight=False)
    if comparison.hypervolume:
        print_hypervolume(comparison.hypervolume, labels)
    for test in comparison.tests:
        unit = unit_of(comparison.objective_name)
        effect = ("-" if test.effect is None else f"{test.effect:.3g} {unit}".strip())
        threshold = ("-" if test.threshold is None
                     else f"{test.threshold:.3g} {unit}".strip())
        out.print(f"medians B - A = {effect} (equivalence threshold {threshold}); "
                  f"Mann-Whitney p = {test.p_value:.3g}, P(A better) = "
                  f"{test.p_a_better:.2f}", highlight=False)
        out.print(f"success A {success_rate_text(test.success_a)}, B "
                  f"{success_rate_text(test.success_b)}: Fisher exact p = "
                  f"{test.success_p_value:.3g}", highlight=False)
        out.print(f"[bold]{escape(test.verdict)}[/]", highlight=False)
