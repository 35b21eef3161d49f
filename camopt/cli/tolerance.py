"""``camopt tolerance``: how a run's optimum fares when its parts are made to tolerance."""

from __future__ import annotations

import enum
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.markup import escape
from rich.table import Table

from camopt.cli.app import Format, app, errors, fmt, out

if TYPE_CHECKING:  # imported inside the command: the CLI starts without numpy
    from camopt.tolerance import Tolerance
from camopt.errors import CamoptError


class Dist(str, enum.Enum):
    """``--dist`` (the names of :class:`camopt.tolerance.Distribution`, which imports scipy:
    the command line lists them without it)."""

    uniform = "uniform"
    normal = "normal"


@app.command()
def tolerance(
    run_path: Annotated[Path, typer.Argument(metavar="ARCHIVE", help="run archive")],
    vary: Annotated[list[str] | None, typer.Option(
        "--vary", help="NAME=±X% (relative) or NAME=±X (own unit); NAME a design variable "
        "or case.FIELD; repeatable; default: the case's documented tolerances")] = None,
    samples: Annotated[int, typer.Option(
        min=1, max=1_000_000, help="samples, evaluated in row chunks (at most 10^6)")]
    = 2000,
    seed: Annotated[int, typer.Option(min=0, help="root seed of the draws")] = 0,
    dist: Annotated[Dist, typer.Option(
        "--dist", help="uniform on ±X, or normal with sigma = X/3")] = Dist.uniform,
    format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
    out_path: Annotated[Path | None, typer.Option(
        "--out", help="write the samples to this HDF5 file")] = None,
    plot: Annotated[Path | None, typer.Option(
        help="write histograms and a tornado chart (PNG) to this folder")] = None,
    tornado: Annotated[str | None, typer.Option(
        help="metric of the tornado chart (default the objective)")] = None,
    force: Annotated[bool, typer.Option(help="overwrite an existing --out")] = False,
) -> None:
    """Vary a run's optimum within tolerances: yield, percentiles, sensitivities."""
    from camopt import archive
    from camopt.perf import tune_allocator
    from camopt.report import jsonable
    from camopt.tolerance import Distribution, analyse, default_varies, parse_vary

    with errors():
        tune_allocator()  # chunk temporaries stay mapped (docs/design.md, Performance)
        run = archive.load_run(run_path)
        varies = ([parse_vary(str(run_path), v) for v in vary] if vary
                  else default_varies(run))
        if out_path is not None:
            archive.check_writable(out_path, force)
        result = analyse(run, varies, samples, seed, Distribution(dist.value))
        doc = jsonable(result.summary)
        if tornado is not None and tornado not in doc["metrics"]:
            raise CamoptError(f"{run_path}: --tornado: no metric '{tornado}'; the case "
                              f"reports {', '.join(doc['metrics'])}")
        if out_path is not None:
            _write(result, out_path, force)
        written = _figures(result, plot, tornado, run_path.stem) if plot else []
    if format is Format.json:
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
    else:
        print_tolerance(doc)
    for p in written:
        print(p)


def _write(result: Tolerance, path: Path, force: bool) -> None:
    from camopt.archive.samples import write_samples

    inputs = {v.name: result.inputs[:, j] for j, v in enumerate(result.varies)}
    write_samples(path, result.summary, inputs, result.metric_columns(result.samples),
                  result.samples.g, result.constraint_names, result.samples.feasible, force)


def _figures(result: Tolerance, folder: Path, metric: str | None, stem: str) -> list[Path]:
    from camopt import plots
    from camopt.tolerance_figures import figures

    return plots.save(figures(result, metric), folder, f"{stem}-tolerance")


def print_tolerance(doc: dict) -> None:
    """The analysis as rich tables: yield, then each metric's spread and its driver."""
    varied = ", ".join(f"{v['input']} ±{fmt(v['tolerance'])}{'%' if v['unit'] == '%' else ''}"
                       for v in doc["vary"])
    run = escape(str(doc["run"]))
    out.print(f"[bold]{run}[/]: {doc['samples']} samples ({doc['distribution']}, "
              f"seed {doc['seed']}) of {varied}")
    out.print(f"yield (feasible share): [bold]{doc['yield']:.1%}[/]"
              f"{'' if doc['nominal_feasible'] else ' (the nominal design is infeasible)'}")
    table = Table(title="metrics (driver: largest |Spearman rho|)")
    for col in ("metric", "nominal", "p05", "p50", "p95", "driver", "rho"):
        table.add_column(col, justify="left" if col in ("metric", "driver") else "right",
                         overflow="fold")
    for name, p in doc["metrics"].items():
        top = doc["sensitivity"][name][0]
        table.add_row(name, fmt(doc["nominal"][name]), fmt(p["p05"]), fmt(p["p50"]),
                      fmt(p["p95"]), top["input"] if top["spearman"] is not None else "-",
                      fmt(top["spearman"]))
    out.print(table)
    broken = {k: v for k, v in doc["violated_share"].items() if v}
    if broken:
        out.print("violated in: " + ", ".join(f"{k} {v:.1%}" for k, v in broken.items()))
