"""Command-line interface: thin typer commands, each calling one function."""

from __future__ import annotations

import contextlib
import json
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from pydantic import ValidationError
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from camopt import archive, report
from camopt import sweep as sweep_mod
from camopt.cases import DEFAULT_SOLVER, case_class
from camopt.config import CASE_CONFIGS, load_config, template
from camopt.driver import build_solver, execute, prepare
from camopt.errors import CamoptError
from camopt.solvers import solvers

app = typer.Typer(rich_markup_mode="rich", no_args_is_help=True, add_completion=False,
                  help="Batch optimiser for spring-actuated mechanisms.")
out = Console()
err = Console(stderr=True)


@contextlib.contextmanager
def _errors() -> Iterator[None]:
    """Print camopt's and pydantic's errors as one line and exit with code 2."""
    try:
        yield
    except (CamoptError, ValidationError) as exc:
        message = str(exc).splitlines()[0] if isinstance(exc, ValidationError) else str(exc)
        print(f"error: {message}", file=sys.stderr)
        raise typer.Exit(2) from None


def _solver_options() -> dict[str, Any]:
    return {name: cls.Options for name, cls in solvers().items()}


def _load(case: Path, overrides: list[str] | None = None) -> Any:
    return archive.resolve_references(load_config(case, _solver_options(), overrides or []))


@app.command()
def run(
    case: Annotated[Path, typer.Argument(help="case file (TOML)")],
    out_path: Annotated[Path | None, typer.Option("--out", help="archive path")] = None,
    seed: Annotated[int | None, typer.Option(min=0, help="root seed (overrides run.seed)")]
    = None,
    repeats: Annotated[int | None, typer.Option(min=1, help="repeats (overrides run.repeats)")]
    = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="override: section.key=value")]
    = None,
    force: Annotated[bool, typer.Option(help="overwrite an existing --out")] = False,
    quiet: Annotated[bool, typer.Option(help="no progress bar or summary; print the path")]
    = False,
) -> None:
    """Run a case file and write an HDF5 run archive."""
    with _errors():
        config = _load(case, set_)
        prepare(config)
        path = out_path or archive.default_path(config.run.name)
        if out_path is None:
            path.parent.mkdir(parents=True, exist_ok=True)
        archive.check_writable(path, force)
        with _progress(quiet) as callback:
            record = execute(config, seed=seed, repeats=repeats, callback=callback)
        archive.write_run(record, path, force=force)
    if quiet:
        out.print(str(path))
        return
    _print_show(archive.load_run(path), rows=10)


@contextlib.contextmanager
def _progress(quiet: bool) -> Iterator[Any]:
    """A rich progress bar over repeats x iterations when stderr is a terminal."""
    if quiet or not err.is_terminal:
        yield None
        return
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("best {task.fields[best]}"), TimeElapsedColumn())
    with Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("solving", total=None, best="-")

        def callback(p: Any) -> None:
            total = p.repeats * (p.max_iterations or 1)
            done = p.repeat * (p.max_iterations or 1) + p.iteration
            bar.update(task, total=total, completed=done, best=f"{p.best_objective:.6g}",
                       description=f"repeat {p.repeat + 1}/{p.repeats}")

        yield callback


@app.command()
def validate(case: Annotated[Path, typer.Argument(help="case file (TOML)")],
             set_: Annotated[list[str] | None, typer.Option("--set")] = None) -> None:
    """Check a case file without running it."""
    with _errors():
        config = _load(case, set_)
        problem, solver_cls = prepare(config)
        build_solver(problem, solver_cls, config, np.random.default_rng(0))  # its own checks
    out.print(f"ok: {case}: case '{config.case.kind}' ({problem.n_var} variables, "
              f"{problem.n_constr} constraints), solver '{solver_cls.name}'")


@app.command()
def init(kind: Annotated[str, typer.Argument(help="case kind")],
         out_path: Annotated[Path | None, typer.Option("--out", help="write here")] = None,
         force: Annotated[bool, typer.Option(help="overwrite --out")] = False) -> None:
    """Write a commented case-file template for a case kind."""
    with _errors():
        if kind not in CASE_CONFIGS:
            raise CamoptError(f"init: kind: unknown case kind {kind!r}; known: "
                              f"{', '.join(sorted(CASE_CONFIGS))}")
        text = template(kind, solvers()[DEFAULT_SOLVER[kind]].Options())
        if out_path is None:
            sys.stdout.write(text)
            return
        if out_path.exists() and not force:
            raise CamoptError(f"{out_path}: --out: exists; pass --force to overwrite")
        out_path.write_text(text)
    out.print(f"wrote {out_path}")


@app.command(name="solvers")
def list_solvers() -> None:
    """List solvers with their options and the case kinds each runs on."""
    table = Table(title="camopt solvers")
    for col in ("name", "what", "options", "cases"):
        table.add_column(col)
    for name, cls in solvers().items():
        options = "\n".join(f"{k} = {v.get_default(call_default_factory=True)!r}"
                            for k, v in cls.Options.model_fields.items() if k != "name")
        cases = ", ".join(k for k in sorted(CASE_CONFIGS) if cls.supports(case_class(k)))
        table.add_row(name, cls.summary, options or "-", cases or "-")
    out.print(table)


Format = Annotated[str, typer.Option("--format", help="table or json")]


def _check_format(fmt: str) -> None:
    if fmt not in ("table", "json"):
        raise CamoptError(f"--format: {fmt!r}: expected table or json")


@app.command()
def show(run_path: Annotated[Path, typer.Argument(metavar="RUN", help="run archive")],
         fmt: Format = "table") -> None:
    """Show a run archive: best design, metrics, repeats, table."""
    with _errors():
        _check_format(fmt)
        run_data = archive.load_run(run_path)
    if fmt == "json":
        sys.stdout.write(json.dumps(report.show(run_data), indent=2) + "\n")
    else:
        _print_show(run_data)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(_fmt(v) for v in value)
    return "-" if value is None else str(value)


def _print_show(run_data: dict[str, Any], rows: int | None = None) -> None:
    doc, path = report.show(run_data), run_data["extra"]["path"]
    best = doc["best"]
    out.print(f"[bold]{path}[/]  case [cyan]{doc['case']['kind']}[/], "
              f"solver [cyan]{doc['solver']['name']}[/]")
    head = Table(title="best design", show_header=False)
    head.add_row("objective", _fmt(best["objective"]))
    head.add_row("feasible", _fmt(best["feasible"]))
    head.add_row("active constraints", ", ".join(best.get("active", [])) or "none")
    for k, v in {**best["x"], **best["metrics"]}.items():
        head.add_row(k, _fmt(v))
    out.print(head)
    # the 19-digit seeds are in --format json; the table names repeats by spawn key
    reps = Table(title="repeats (repeat k: child k of SeedSequence(run.seed))")
    columns = ("objective", "feasible", "nfev", "converged_nit")
    for col in ("repeat", *columns, "wall_s"):
        reps.add_column(col, justify="right")
    for r in doc["repeats"]:
        reps.add_row(_fmt(r["spawn_key"]), *(_fmt(r[c]) for c in columns),
                     f"{r['wall_s']:.2f}")
    out.print(reps)
    for i, r in enumerate(doc["repeats"]):
        for note in r["notes"]:
            out.print(f"[bold]note[/] (repeat {i}): {note}")
    if doc["table"]:
        columns = ["label", *best["x"], run_data["extra"]["objective_name"], "feasible",
                   "active", "violated"]
        _print_rows("table", doc["table"], columns, rows)


def _print_rows(title: str, rows: list[dict[str, Any]], columns: list[str],
                limit: int | None) -> None:
    """A rich table of the given columns (those present); every column is in the JSON."""
    columns = [c for c in columns if c in rows[0]]
    note = "all columns: --format json"
    if limit is not None and len(rows) > limit:
        note = (f"first {limit} of {len(rows)} rows; camopt show for all, "
                "--format json for all columns")
    table = Table(title=f"{title} ({note})")
    for col in columns:
        table.add_column(col, justify="right", overflow="fold")
    for row in rows[:limit]:
        table.add_row(*(_fmt(row.get(c)) for c in columns))
    out.print(table)


@app.command()
def compare(runs: Annotated[list[Path], typer.Argument(metavar="RUN...",
                                                       help="run archives, or one sweep")],
            fmt: Format = "table") -> None:
    """Compare runs (config differences, designs, statistics, a significance test for two)
    or rank the grid points of a sweep."""
    with _errors():
        _check_format(fmt)
        if len(runs) == 1 and archive.archive_kind(runs[0]) == "sweep":
            spec, results = sweep_mod.load_sweep(runs[0])
            doc = report.rank_sweep(spec, results)
            if fmt == "json":
                sys.stdout.write(json.dumps(doc, indent=2) + "\n")
            else:
                _print_ranking(doc)
            return
        if len(runs) < 2:
            raise CamoptError("compare: RUN: give at least two run archives, or one sweep")
        doc = report.compare([archive.load_run(p) for p in runs])
    if fmt == "json":
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return
    names = [Path(p).name for p in doc["runs"]]
    table = Table(title="compare")
    table.add_column("")
    for n in names:
        table.add_column(n, justify="right", overflow="fold")
    for key, values in doc["config_differences"].items():
        table.add_row(f"[dim]{key}[/]", *(_fmt(v) for v in values))
    table.add_row("[bold]objective[/]", *(_fmt(v) for v in doc["objective"]))
    table.add_row("feasible", *(_fmt(v) for v in doc["feasible"]))
    for section in ("x", "metrics"):
        for key, values in doc[section].items():
            table.add_row(key, *(_fmt(v) for v in values))
    for stat in ("repeats", "best", "median", "worst", "feasible_fraction"):
        table.add_row(f"repeats: {stat}", *(_fmt(s[stat]) for s in doc["statistics"]))
    out.print(table)
    for test in doc["tests"]:
        out.print(f"A = {names[0]}, B = {names[1]}: Mann-Whitney p = {test['p_value']:.3g}, "
                  f"P(A better) = {test['p_a_better']:.2f}; success A "
                  f"{_rate(test['success_a'])}, B {_rate(test['success_b'])}")
        out.print(f"[bold]{test['verdict']}[/]")


def _rate(s: dict[str, float]) -> str:
    return f"{s['rate']:.0%} [{s['ci_low']:.0%}, {s['ci_high']:.0%}]"


def _print_ranking(doc: dict[str, Any]) -> None:
    table = Table(title=f"sweep {doc['sweep']}: grid points ranked")
    for col in ("rank", "point", "runs", "success", "best", "median", "worst",
                "nfev to target", "vs best"):
        table.add_column(col, justify="right" if col != "point" else "left")
    for r in doc["ranking"]:
        vs = r.get("vs_best")
        table.add_row(str(r["rank"]), r["label"], str(r["runs"]),
                      _fmt(r["success_rate"]), _fmt(r["best"]), _fmt(r["median"]),
                      _fmt(r["worst"]), _fmt(r["median_nfev_to_target"]),
                      f"p = {vs['p_value']:.3g}" if vs else "-")
    out.print(table)
    for r in doc["ranking"]:
        if r.get("vs_best"):
            out.print(r["vs_best"]["verdict"])


@app.command()
def sweep(
    case: Annotated[Path | None, typer.Argument(help="case file (TOML)")] = None,
    seeds: Annotated[str, typer.Option(help="seed indices START:STOP")] = "0:5",
    grid: Annotated[list[str] | None, typer.Option(
        "--grid", help="key=v1,v2,... (repeatable; Cartesian product)")] = None,
    jobs: Annotated[int | None, typer.Option(min=1, help="local workers (default: cores)")]
    = None,
    out_path: Annotated[Path | None, typer.Option("--out", help="sweep archive path")] = None,
    resume: Annotated[Path | None, typer.Option(help="finish an interrupted sweep")] = None,
    executor: Annotated[str, typer.Option(help="local or dask")] = "local",
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address")] = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="section.key=value")] = None,
    check: Annotated[bool, typer.Option(help="exit 1 below run.min_success_rate")] = False,
    force: Annotated[bool, typer.Option(help="overwrite an existing --out")] = False,
    quiet: Annotated[bool, typer.Option(help="no progress bar")] = False,
) -> None:
    """Run every grid point x seed; one sweep archive with a summary per grid point."""
    with _errors():
        if executor not in ("local", "dask"):
            raise CamoptError(f"--executor: {executor!r}: expected local or dask")
        spec, results, path = _sweep_setup(case, seeds, grid or [], set_ or [], out_path,
                                           resume, force)
        try:
            with _cell_progress(quiet) as progress:
                sweep_mod.run_sweep(spec, path, results, jobs=jobs or os.cpu_count() or 1,
                                    executor=executor, scheduler=scheduler,
                                    progress=progress)
        except sweep_mod.SweepInterrupted as exc:
            print(f"interrupted: {exc}; finish with: camopt sweep --resume {path}",
                  file=sys.stderr)
            raise typer.Exit(130) from None
    rows = sweep_mod.summary(spec, results.values())
    if not quiet:
        _print_rows(f"sweep {path}", rows, list(rows[0]), None)
    else:
        out.print(str(path))
    if check:
        _check_success(spec, rows)


def _sweep_setup(case: Path | None, seeds: str, grid: list[str], overrides: list[str],
                 out_path: Path | None, resume: Path | None, force: bool) -> Any:
    if resume is not None:
        spec, results = sweep_mod.load_sweep(resume)
        if case is not None:
            fresh = sweep_mod.SweepSpec(_load(case, overrides).effective(), str(case), "",
                                        sweep_mod.parse_grid(grid), sweep_mod.parse_seeds(seeds))
            if fresh.to_json() != spec.to_json():
                raise CamoptError(f"{resume}: --resume: the case, grid or seeds differ from "
                                  "the sweep in the archive")
        return spec, results, resume
    if case is None:
        raise CamoptError("sweep: CASE: give a case file (or --resume ARCHIVE)")
    config = _load(case, overrides)
    spec = sweep_mod.SweepSpec(config.effective(), str(case), config.text,
                               sweep_mod.parse_grid(grid), sweep_mod.parse_seeds(seeds))
    try:
        spec.validate()
    except ValidationError as exc:
        raise CamoptError(f"{case}: --grid: {str(exc).splitlines()[0]}") from None
    path = out_path or archive.default_path(f"{config.run.name}-sweep")
    if out_path is None:
        path.parent.mkdir(parents=True, exist_ok=True)
    archive.check_writable(path, force)
    return spec, {}, path


def _check_success(spec: Any, rows: list[dict[str, Any]]) -> None:
    floor = spec.data["run"].get("min_success_rate")
    if floor is None:
        print("error: --check: run.min_success_rate is not set in the case file",
              file=sys.stderr)
        raise typer.Exit(2)
    failing = [r for r in rows if not r["success_rate"] >= floor]
    for r in failing:
        print(f"check failed: grid point {r['point']} success rate {r['success_rate']:.0%} "
              f"< {floor:.0%}", file=sys.stderr)
    if failing:
        raise typer.Exit(1)
    out.print(f"check passed: every grid point succeeds in >= {floor:.0%} of runs")


@contextlib.contextmanager
def _cell_progress(quiet: bool) -> Iterator[Any]:
    if quiet or not err.is_terminal:
        yield None
        return
    with Progress(TextColumn("cells"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=err, transient=True) as bar:
        task = bar.add_task("cells", total=None)
        yield lambda done, total: bar.update(task, completed=done, total=total)


@app.command()
def plot(path: Annotated[Path, typer.Argument(metavar="RUN_OR_SWEEP", help="archive")],
         out_dir: Annotated[Path | None, typer.Option("--out", help="folder for the PNGs")]
         = None) -> None:
    """Write PNG figures: convergence and the case's curves."""
    from camopt import plots

    with _errors():
        folder = out_dir or path.parent / f"{path.stem}-plots"
        if archive.archive_kind(path) == "sweep":
            figures = plots.sweep_figures(*sweep_mod.load_sweep(path))
        else:
            figures = plots.run_figures(archive.load_run(path))
        written = plots.save(figures, folder, path.stem)
    for p in written:
        out.print(str(p))


@app.command()
def export(run_path: Annotated[Path, typer.Argument(metavar="RUN", help="run archive")],
           fmt: Format = "csv",
           out_dir: Annotated[Path | None, typer.Option("--out", help="output folder")] = None
           ) -> None:
    """Export the summary and analysis curves (csv or json) and cam profile point files."""
    from camopt.export import export_run

    with _errors():
        if fmt not in ("csv", "json"):
            raise CamoptError(f"--format: {fmt!r}: expected csv or json")
        run_data = archive.load_run(run_path)
        written = export_run(run_data, out_dir or run_path.parent, run_path.stem, fmt)
    for p in written:
        out.print(str(p))


def main() -> None:
    """Console-script entry point."""
    app()
