"""``camopt tolerance``: how a run's optimum fares when its parts are made to tolerance.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import contextlib
import enum
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import escape, fmt, out, rows_bar, visible
from camopt.cli.layout import print_table
from camopt.errors import CamoptError

if TYPE_CHECKING:  # imported inside the command: the CLI starts without numpy
    from camopt.core.runview import RunView
    from camopt.engine.tolerance import Distribution, Tolerance


class Dist(str, enum.Enum):
    """``--dist`` (the names of :class:`camopt.engine.tolerance.Distribution`, which imports scipy:
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
    seed: Annotated[int, typer.Option(min=0, max=2**128 - 1, help="root seed of the draws "
                                      "(0 to 2^128 - 1, as run.seed)")] = 0,
    dist: Annotated[Dist, typer.Option(
        "--dist", help="uniform on ±X, or normal with sigma = X/3")] = Dist.uniform,
    format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
    out_path: Annotated[Path | None, typer.Option(
        "--out", help="write the samples to this HDF5 file")] = None,
    plot: Annotated[Path | None, typer.Option(
        help="write histograms and a tornado chart (PNG) to this folder")] = None,
    tornado: Annotated[str | None, typer.Option(
        help="metric of the tornado chart (default the quantity of the requirement that "
        "limits the yield)")] = None,
    force: Annotated[bool, typer.Option(
        help="overwrite an existing --out and --plot's PNGs")] = False,
    tolerance_class: Annotated[str | None, typer.Option(
        "--class", help="the case's tolerance class (docs/tolerance.md; default the run's "
        "case.tolerance_class, else the case's default class)")] = None,
    allocate: Annotated[bool, typer.Option(
        "--allocate", help="the yield in every tolerance class of the case, the cheapest "
        "that reaches --target, and what tightening each input buys")] = False,
    target: Annotated[float | None, typer.Option(
        help="yield target of --allocate, a share > 0 and <= 1 (default the run's "
        "robust.yield_target, else 0.95)")] = None,
    quiet: Annotated[bool, typer.Option(
        help="no progress bar (there is none when stderr is not a terminal)")] = False,
) -> None:
    """Vary a run's optimum within tolerances: yield, percentiles, sensitivities."""
    from camopt import archive
    from camopt.cases import get_case
    from camopt.core.perf import tune_allocator
    from camopt.engine.tolerance import Distribution, analyse, default_varies, parse_vary
    from camopt.reporting.report import jsonable

    with errors():
        tune_allocator()  # chunk temporaries stay mapped (docs/design.md, Performance)
        run = archive.load_run(run_path)
        if allocate:
            if vary or out_path is not None or plot is not None or tolerance_class:
                raise CamoptError(f"{run_path}: --allocate: takes the case's classes; "
                                  "--vary, --class, --out and --plot are for one analysis")
            _allocate(run, target, samples, seed, Distribution(dist.value), format)
            return
        if vary and tolerance_class:
            raise CamoptError(f"{run_path}: --class: give --class or --vary, not both")
        varies = ([parse_vary(str(run_path), v) for v in vary] if vary
                  else default_varies(run, tolerance_class))
        used_class = None if vary else (tolerance_class or run.case.get("tolerance_class")
                                        or get_case(run.kind).default_tolerance_class)
        if out_path is not None:
            archive.check_writable(out_path, force)
            archive.check_not_input(out_path, [run_path])
        with contextlib.ExitStack() as stack:
            if plot is not None:  # a file, FIFO or unwritable folder: one line, before any
                # work; the folder, if made here, is removed again should the rest fail
                stack.enter_context(archive.output_folder(plot, "--plot"))
            with rows_bar("tolerance samples", quiet) as rows_done:
                result = analyse(run, varies, samples, seed, Distribution(dist.value),
                                 used_class, rows_done)
            doc = jsonable(result.summary)
            if tornado is not None and tornado not in doc["metrics"]:
                raise CamoptError(f"{run_path}: --tornado: no metric '{tornado}'; the case "
                                  f"reports {', '.join(doc['metrics'])}")
            if out_path is not None:
                _write(result, out_path, force)
            written = _figures(result, plot, tornado, run_path.stem, force) if plot else []
    if format is Format.json:  # stdout holds only the JSON; the figures' paths on stderr
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        for p in written:
            print(visible(p), file=sys.stderr)
        return
    print_tolerance(doc)
    for p in written:
        print(visible(p))


def _allocate(run: RunView, target: float | None, samples: int, seed: int,
              distribution: Distribution, format: Format) -> None:
    """``--allocate``: the classes' yields on common draws, the cheapest that reaches the
    target, and the gain of tightening each input alone."""
    from camopt.engine.allocation import allocate

    if target is None:
        target = float(run.robust.get("yield_target", 0.95))
    result = allocate(run, target, samples, seed, distribution)
    if format is Format.json:
        sys.stdout.write(json.dumps(result.to_json(), indent=2) + "\n")
        return
    out.print(f"[bold]{escape(result.run)}[/]: {result.samples} samples (seed "
              f"{result.seed}, the same draws in every class); target {result.target:.1%}, "
              "reached where the lower end of the yield's 95 % interval is at or above it",
              highlight=False)
    rows = [[c.name, f"{c.relative_cost:g}", f"{c.yield_:.1%}",
             f"[{c.low:.1%}, {c.high:.1%}]", "yes" if c.reaches_target else "no"]
            for c in result.classes]
    print_table("tolerance classes, cheapest first (cost relative to the case's default; "
                "docs/tolerance.md)", ["class", "cost", "yield", "95 % interval", "reaches"],
                rows, numeric=[False, True, True, True, False])
    chosen = result.chosen or "none of the case's classes"
    out.print(f"cheapest class that reaches the target: [bold]{escape(chosen)}[/]",
              highlight=False)
    if result.tightenings:
        rows = [[t.input, f"{t.tolerance_from} -> {t.tolerance_to}", f"{t.yield_:.1%}",
                 f"{t.gain:+.1%}"] for t in result.tightenings]
        print_table(f"tightening one input of class {result.classes[0].name} alone",
                    ["input", "tolerance", "yield", "gain"], rows,
                    numeric=[False, False, True, True])


def _write(result: Tolerance, path: Path, force: bool) -> None:
    from camopt.archive.samples import write_samples

    inputs = {v.name: result.inputs[:, j] for j, v in enumerate(result.varies)}
    write_samples(path, result.summary, inputs, result.metric_columns(result.samples),
                  result.samples.g, result.constraint_names, result.samples.feasible, force)


def _figures(result: Tolerance, folder: Path, metric: str | None, stem: str,
             force: bool) -> list[Path]:
    from camopt.reporting import plots
    from camopt.reporting.tolerance_figures import figures

    return plots.save(figures(result, metric), folder, f"{stem}-tolerance", force,
                      key="--plot")


def print_tolerance(doc: dict) -> None:
    """The analysis as rich tables: yield, then each metric's spread and its driver."""
    from camopt.reporting import report

    varied = ", ".join(f"{v['input']} ±{fmt(v['tolerance'])}{'%' if v['unit'] == '%' else ''}"
                       for v in doc["vary"])
    run = escape(str(doc["run"]))
    out.print(f"[bold]{run}[/]: {doc['samples']} samples ({doc['distribution']}, "
              f"seed {doc['seed']}) of {varied}")
    cls = f", tolerance class {doc['tolerance_class']}" if doc.get("tolerance_class") else ""
    out.print(f"yield (feasible share): [bold]{doc['yield']:.1%}[/] [{doc['yield_low']:.1%}, "
              f"{doc['yield_high']:.1%}] (95 % interval{cls})"
              f"{'' if doc['nominal_feasible'] else ' (the nominal design is infeasible)'}")
    if doc.get("per_form"):
        print_table("yield per model form (each sample judged under one kept form of the "
                    "case, in turn; the yield above is over both)",
                    ["form", "samples", "yield", "95 % interval"],
                    [[r["form"], str(r["samples"]), f"{r['yield']:.1%}",
                      f"[{r['yield_low']:.1%}, {r['yield_high']:.1%}]"]
                     for r in doc["per_form"]], numeric=[False, True, True, True])
    if doc["requirements"]:
        rows = [[r["name"], r["limit"], f"{r['yield']:.1%}", report.format_value(
                 r["margin_p5"]) + (f" {r['unit']}" if r["unit"] and r["margin_p5"]
                                   is not None else ""),
                 "pass" if r["nominal_pass"] else "FAIL"] for r in doc["requirements"]]
        print_table("yield per requirement (margin p05: 5 % of samples are closer to the "
                    "limit)", ["requirement", "limit", "yield", "margin p05", "nominal"],
                    rows, numeric=[False, True, True, True, True])
        if doc["limiting"]:
            out.print(f"limits the yield: [bold]{escape(doc['limiting'])}[/] (the tornado's "
                      "default)", highlight=False)
    for adjustment in doc.get("adjustments", ()):
        out.print(escape(report.adjustment_text(adjustment)), highlight=False)
    rows = []
    for name, p in doc["metrics"].items():
        top = doc["sensitivity"][name][0]
        rows.append([name, *(report.format_value(v) for v in (
            doc["nominal"][name], p["p05"], p["p50"], p["p95"])),
            top["input"] if top["spearman"] is not None else "-",
            report.format_value(top["spearman"])])
    print_table(f"metrics, raw (objective over {doc['objective_over']}; driver: largest "
                "|Spearman rho|)", ["metric", "nominal", "p05", "p50", "p95", "driver", "rho"],
                rows, numeric=[False, True, True, True, True, False, True])
    broken = {k: v for k, v in doc["violated_share"].items() if v}
    if broken:
        out.print("violated in: " + ", ".join(f"{k} {v:.1%}" for k, v in broken.items()))
