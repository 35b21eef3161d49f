"""``camopt show``: a run archive's summary (the best design beside the reference design,
repeats, the solver's table), or a sweep archive's ranking.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import out, visible
from camopt.cli.layout import print_ranking, print_show

if TYPE_CHECKING:
    from camopt.archive.calibrations import CalibrationView


def calibration_doc(view: CalibrationView) -> dict[str, object]:
    """``show --format json`` of a calibration archive: ``calibrate --format json``'s
    document with the archive's kind, path, case kind and time."""
    return {"archive_kind": "calibration", "path": view.path, "case_kind": view.case_kind,
            "created": view.created, **view.summary}


def calibration_lines(view: CalibrationView) -> list[str]:
    """``show`` of a calibration archive: a heading, then the report as calibrate printed
    it."""
    return [f"calibration archive {view.path} ({view.case_kind} case, written "
            f"{view.created})", "", *view.lines]


@app.command()
def show(run_paths: Annotated[list[Path], typer.Argument(
             metavar="RUN_OR_SWEEP...", help="run or sweep archives (a glob may match several)")],
         format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
         ) -> None:
    """Show archives: a run's best design beside the reference design, its repeats and
    table; a sweep's grid points ranked (as compare SWEEP); a tolerance archive's yield
    and spreads (as ``camopt tolerance`` printed them); a calibration archive's report (as
    ``camopt calibrate`` printed it: per model form the RMS misfit, kept or not, the
    parameters with their intervals, each curve's analyser quantities measured beside
    fitted, the predictions). Several archives (a glob such
    as runs/NAME-*.h5) are each shown, in the order given (a glob's order: oldest
    first, as the names carry the time); with --format json, as a JSON array."""
    from camopt import archive
    from camopt.errors import ArchiveError
    from camopt.reporting import report
    from camopt.reporting.report import jsonable

    with errors():  # every archive read before anything is printed
        loaded: list[tuple[str, Any]] = []
        for path in run_paths:
            try:  # most archives are runs: opened (and checked) once
                loaded.append(("run", archive.load_run(path)))
                continue
            except ArchiveError:
                kind = archive.archive_kind(path)  # its own error for what no kind reads
                if kind == "run":
                    raise
            if kind == "sweep":
                from camopt.archive.sweeps import load_sweep

                loaded.append(("sweep", report.rank_sweep(*load_sweep(path))))
            elif kind == "tolerance":
                from camopt.archive.samples import load_samples

                loaded.append(("tolerance", jsonable(load_samples(path).summary)))
            elif kind == "calibration":
                from camopt.archive.calibrations import load_calibration

                loaded.append(("calibration", load_calibration(path)))
    if format is Format.json:
        docs = [report.show(item).to_json() if kind == "run" else calibration_doc(item)
                if kind == "calibration" else jsonable(item) for kind, item in loaded]
        sys.stdout.write(json.dumps(docs[0] if len(docs) == 1 else docs, indent=2) + "\n")
        return
    for i, (kind, item) in enumerate(loaded):
        if i:
            out.print()
        if kind == "sweep":
            print_ranking(item)
        elif kind == "tolerance":
            from camopt.cli.tolerance import print_tolerance

            print_tolerance(item)
        elif kind == "calibration":
            sys.stdout.write("\n".join(map(visible, calibration_lines(item))) + "\n")
        else:
            print_show(item)


