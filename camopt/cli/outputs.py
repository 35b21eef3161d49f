"""``camopt plot`` and ``camopt export``: figures and files from an archive.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import contextlib
import enum
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated

import typer

from camopt.cli.app import app, errors
from camopt.cli.console import visible
from camopt.errors import ArchiveError


@contextlib.contextmanager
def writing(folder: Path) -> Iterator[None]:
    """An unwritable or full output folder is one error line naming it."""
    try:
        yield
    except ArchiveError:
        raise
    except OSError as exc:
        where = exc.filename or folder
        raise ArchiveError(f"{folder}: --out: cannot write {where} "
                           f"({exc.strerror or exc})") from None


class ExportFormat(str, enum.Enum):
    """Formats of ``camopt export``."""

    csv = "csv"
    json = "json"
    dxf = "dxf"


@app.command()
def plot(paths: Annotated[list[Path], typer.Argument(
             metavar="RUN_OR_SWEEP [RUN...]",
             help="archive; two or more runs of one case: drawn on the same axes")],
         out_dir: Annotated[Path | None, typer.Option("--out", help="folder for the PNGs")]
         = None,
         force: Annotated[bool, typer.Option(help="replace existing PNGs of these names")]
         = False) -> None:
    """Write PNG figures: convergence and the case's curves; given several runs, their
    cam profiles and travel and velocity curves overlaid (``A-vs-B-<figure>.png``)."""
    from camopt import archive
    from camopt.archive.sweeps import load_sweep
    from camopt.reporting import plots

    with errors():
        path = paths[0]
        stem = "-vs-".join(p.stem for p in paths)
        folder = out_dir or path.parent / f"{stem}-plots"
        if len(paths) > 1:
            runs = [archive.load_run(p) for p in paths]
            labels = [p.stem if [q.stem for q in paths].count(p.stem) == 1 else str(p)
                      for p in paths]
            figures = plots.overlay_figures(runs, labels)
        elif archive.archive_kind(path) == "sweep":
            figures = plots.sweep_figures(*load_sweep(path))
        elif archive.archive_kind(path) == "tolerance":
            from camopt.archive.samples import load_samples
            from camopt.reporting.tolerance_figures import figures as tolerance_figures

            figures = tolerance_figures(load_samples(path))
        elif archive.archive_kind(path) == "calibration":
            from camopt.archive.calibrations import load_calibration
            from camopt.reporting.calibration_figures import figures as fit_figures
            from camopt.reporting.calibration_figures import rms_of

            view = load_calibration(path)
            figures = fit_figures(view.curves, rms_of(view.summary))
        else:
            figures = plots.run_figures(archive.load_run(path))
        with writing(folder):
            written = plots.save(figures, folder, stem, force, tuple(paths))
    for p in written:
        print(visible(p))


@app.command()
def export(run_path: Annotated[Path, typer.Argument(metavar="RUN", help="run archive")],
           format: Annotated[ExportFormat, typer.Option("--format", help="file format")]
           = ExportFormat.csv,
           out_dir: Annotated[Path | None, typer.Option("--out", help="output folder")] = None,
           force: Annotated[bool, typer.Option(help="replace existing files of these names")]
           = False,
           step_deg: Annotated[float, typer.Option(
               "--step-deg", help="angle step of the dxf's CNC points table (deg, 0.01 to "
               "30)")] = 1.0,
           chord_error_mm: Annotated[float | None, typer.Option(
               "--chord-error-mm", help="largest distance of the dxf's outline from the "
               "exact profile (mm, 0.0005 to 0.05 and below the case's profile tolerance; "
               "default 0.005); sets the polyline's point spacing")] = None,
           ) -> None:
    """Export the summary and analysis curves (csv or json) or, for the workshop, the cam
    as a DXF drawing in mm (dxf: the closed full-turn outline where the case has one, within
    --chord-error-mm of the exact profile, base circle, roller and its path, pivots, datum,
    rotation arrow and sense, a title block and notes) with its curves' point files
    (x,y,z in mm) and a CNC points table (polar and Cartesian, mm, every --step-deg).
    The formats write distinct files, so all can go into one folder.

    A design that fails its requirements at nominal is exported with a one-line warning
    on stderr; its drawing's title block and notes say NOT FOR RELEASE and list the failed
    requirements: exported for review, never unmarked (docs/design.md, "A drawing a CAM
    programmer can release")."""
    from camopt import archive
    from camopt.reporting.export import export_run, failed_warning

    with errors():
        view = archive.load_run(run_path)
        folder = out_dir or run_path.parent
        with writing(folder):
            written = export_run(view, folder, run_path.stem, format.value, force,
                                 (run_path,), step_deg, chord_error_mm)
        warning = failed_warning(view, format.value)
    if warning:
        print(f"warning: {visible(warning)}", file=sys.stderr)
    for p in written:
        print(visible(p))


@app.command()
def dashboard(folder: Annotated[Path, typer.Argument(help="folder of archives")] = Path("runs"),
              out: Annotated[Path | None, typer.Option(
                  "--out", help="HTML file to write (default: FOLDER/index.html)")] = None,
              force: Annotated[bool, typer.Option(help="overwrite --out")] = False) -> None:
    """Write one self-contained HTML page over a folder's archives (no server, opens from
    file://): case, verdict, expected yield, objective, date and seed of each; sort,
    filter, tick two runs to see only what differs; links to the reports beside them."""
    from camopt import archive
    from camopt.cli.catalog import write_text
    from camopt.reporting.dashboard import render

    with errors():
        target = out or folder / "index.html"
        archive.check_writable(target, force)
        write_text(target, render(folder), force)
    print(visible(target))


@app.command()
def report(path: Annotated[Path, typer.Argument(metavar="RUN_OR_SWEEP", help="archive")],
           out: Annotated[Path | None, typer.Option(
               "--out", help="HTML file to write (default: the archive's name with .html)")]
           = None,
           force: Annotated[bool, typer.Option(help="overwrite --out")] = False) -> None:
    """Write one self-contained HTML report (figures inline, no network needed to view it):
    the case and solver, the best design beside the reference design, constraints, metrics,
    figures, repeat statistics, notes, versions and seeds; for a sweep, its ranking; for a
    calibration, per model form the fits, residuals, parameters and analyser quantities."""
    from camopt import archive
    from camopt.cli.catalog import write_text
    from camopt.reporting.html_report import render

    with errors():
        target = out or path.with_suffix(".html")
        archive.check_writable(target, force)
        archive.check_not_input(target, [path])
        write_text(target, render(path), force)
    print(visible(target))
