"""``camopt sweep``: grid points x seeds in one resumable sweep archive.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any

import typer

from camopt.cli.app import app, errors, is_validation_error, load_case
from camopt.cli.console import err, out, visible
from camopt.cli.layout import print_rows
from camopt.cli.run import claim_out, default_out
from camopt.errors import CamoptError


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
    from camopt.archive.sweeps import SweepWriter
    from camopt.core.perf import tune_allocator
    from camopt.core.stats import sweep_summary
    from camopt.engine import sweep as sweep_run

    with errors():
        if executor not in ("local", "dask"):
            raise CamoptError(f"--executor: {executor!r}: expected local or dask")
        if executor == "dask" and not scheduler:
            raise CamoptError("--scheduler: give the Dask scheduler's address with "
                              "--executor dask")
        if resume is not None:
            path = resume
        else:
            if case is None:
                raise CamoptError("sweep: CASE: give a case file (or --resume ARCHIVE)")
            config = load_case(case, set_ or [])
            if check and config.run.min_success_rate is None:
                raise CamoptError(f"{case}: run.min_success_rate: not set; --check needs it")
            path = out_path or default_out(f"{config.run.name}-sweep")
        with claim_out(path, force or resume is not None, resuming=resume is not None,
                       inputs=(case,) if case is not None else ()):
            spec, results = _sweep_setup(case, seeds, grid or [], set_ or [], resume)
            if check and spec.data["run"].get("min_success_rate") is None:
                raise CamoptError(f"{path}: run.min_success_rate: not set; --check needs it")
            tune_allocator()
            try:
                with _cell_progress(quiet) as progress:
                    replace = force or resume is not None
                    sweep_run.run_sweep(
                        spec, results,
                        lambda total: SweepWriter(path, spec, results, total, replace=replace),
                        jobs=jobs or os.cpu_count() or 1, executor=executor,
                        scheduler=scheduler, progress=progress)
            except sweep_run.SweepInterrupted as exc:
                print(visible(f"interrupted: {exc}; finish with: camopt sweep --resume {path}"),
                      file=sys.stderr)
                raise typer.Exit(130) from None
    rows = sweep_summary(spec, results.values())
    if not quiet:
        print_rows(f"sweep {path}", rows, list(rows[0]), None)
    else:
        print(visible(path))  # plain print: a script reads exactly the path
    if check:
        _check_success(spec, rows)


def _sweep_setup(case: Path | None, seeds: str, grid: list[str], overrides: list[str],
                 resume: Path | None) -> Any:
    """The sweep's spec and the cells already done (none for a new sweep); called with the
    archive claimed, so a resumed archive cannot change under it."""
    from camopt.archive.sweeps import load_sweep
    from camopt.config import sweep_spec as sweep_mod
    from camopt.engine.sweep import validate_spec

    if resume is not None:
        spec, results = load_sweep(resume)
        if case is not None:
            fresh = sweep_mod.SweepSpec(load_case(case, overrides).effective(), str(case), "",
                                        sweep_mod.parse_grid(grid), sweep_mod.parse_seeds(seeds))
            if fresh.to_json() != spec.to_json():
                raise CamoptError(f"{resume}: --resume: the case, grid or seeds differ from "
                                  "the sweep in the archive")
        return spec, results
    assert case is not None
    config = load_case(case, overrides)
    spec = sweep_mod.SweepSpec(config.effective(), str(case), config.text,
                               sweep_mod.parse_grid(grid), sweep_mod.parse_seeds(seeds))
    try:
        validate_spec(spec)
    except Exception as exc:
        if not is_validation_error(exc):
            raise
        raise CamoptError(f"{case}: --grid: {str(exc).splitlines()[0]}") from None
    return spec, {}


def _check_success(spec: Any, rows: list[dict[str, Any]]) -> None:
    floor = spec.data["run"].get("min_success_rate")
    if floor is None:
        print("error: --check: run.min_success_rate is not set in the case file",
              file=sys.stderr)
        raise typer.Exit(2)
    failing = [r for r in rows if not r["success_rate"] >= floor]
    for r in failing:
        print(f"check failed: grid point {visible(r['point'])} success rate "
              f"{r['success_rate']:.0%} < {floor:.0%}", file=sys.stderr)
    if failing:
        raise typer.Exit(1)
    out.print(f"check passed: every grid point succeeds in >= {floor:.0%} of runs")


@contextlib.contextmanager
def _cell_progress(quiet: bool) -> Iterator[Any]:
    if quiet or not err.is_terminal:
        yield None
        return
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("cells"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=err, transient=True) as bar:
        task = bar.add_task("cells", total=None)
        yield lambda done, total: bar.update(task, completed=done, total=total)
