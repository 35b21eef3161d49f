"""``camopt run``: run a case file and write a run archive."""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any

import typer

from camopt.cli.app import app, errors, load_case
from camopt.cli.console import err, visible
from camopt.engine.interrupts import deferred
from camopt.errors import ArchiveError


@app.command()
def run(
    case: Annotated[Path, typer.Argument(help="case file (TOML)")],
    out_path: Annotated[Path | None, typer.Option("--out", help="archive path")] = None,
    seed: Annotated[int | None, typer.Option(min=0, help="root seed (sets run.seed)")] = None,
    repeats: Annotated[int | None, typer.Option(min=1, help="repeats (sets run.repeats)")]
    = None,
    set_: Annotated[list[str] | None, typer.Option("--set", help="override: section.key=value")]
    = None,
    force: Annotated[bool, typer.Option(help="overwrite an existing --out")] = False,
    quiet: Annotated[bool, typer.Option(help="no progress bar or summary; print the path")]
    = False,
    verbose: Annotated[bool, typer.Option(
        "--verbose", "-v", help="print the whole summary (as camopt show), not the short one")]
    = False,
    jobs: Annotated[int, typer.Option(min=1, max=256, help="worker processes for the "
                                      "repeats (or one repeat's starts); same results")] = 1,
) -> None:
    """Run a case file and write an HDF5 run archive."""
    from camopt import archive
    from camopt.cli.layout import print_show
    from camopt.core.perf import tune_allocator
    from camopt.core.runview import record_view
    from camopt.engine.driver import execute, prepare
    from camopt.engine.tolerance import expected_yield

    overrides = list(set_ or [])
    if seed is not None:  # recorded in the archive's config like any override
        overrides.append(f"run.seed={seed}")
    if repeats is not None:
        overrides.append(f"run.repeats={repeats}")
    with errors():
        config = load_case(case, overrides)
        prepare(config)
        path = out_path or default_out(config.run.name)
        with claim_out(path, force, inputs=(case,)):
            tune_allocator()
            with progress(quiet) as (callback, check):
                record = execute(config, callback=callback, jobs=jobs, check_progress=check)
            with deferred() as signals:  # a Ctrl-C now must not discard finished work
                if record.repeats and not record.failure:  # stored: show, report read it
                    record.expected_yield = expected_yield(record_view(record, str(path)))
                archive.write_run(record, path, force=force)
    if quiet:
        print(visible(path))  # plain print: a script reads exactly the path, never wrapped
    else:
        print_show(archive.load_run(path), rows=10, brief=not verbose)
    kept = f"{len(record.repeats)} finished of {config.run.repeats} repeats in {path}"
    if record.failure:
        print(visible(f"error: {case}: --jobs: {record.failure}; kept the {kept} (marked "
                      "interrupted)"), file=sys.stderr)
        raise typer.Exit(2)
    if record.interrupted:
        print(visible(f"error: interrupted; kept the {kept} (marked interrupted)"), file=sys.stderr)
        raise typer.Exit(130)
    if signals:
        print(visible(f"error: interrupted while writing; kept all {kept}"), file=sys.stderr)
        raise typer.Exit(130)


def default_out(name: str) -> Path:
    """``runs/<name>-<time>.h5``, creating ``runs/`` (an unwritable folder is bad input)."""
    from camopt import archive

    path = archive.default_path(name)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ArchiveError(f"{path.parent}: --out: cannot create the folder "
                           f"({exc.strerror})") from None
    return path


@contextlib.contextmanager
def claim_out(path: Path, force: bool, resuming: bool = False,
              inputs: tuple[Path, ...] = ()) -> Iterator[None]:
    """Hold ``path`` for writing (``archive.claim``: one writer per archive); report stale
    temporary files removed and, with ``--force``, what the new archive replaced (not when
    ``resuming`` the archive's own sweep). One of the command's ``inputs`` is never
    replaced, even with ``--force``."""
    from camopt import archive

    archive.check_not_input(path, inputs)
    replaced = archive.describe_file(path) if force and not resuming else None
    with archive.claim(path, force) as held:
        for stale in held.stale:
            print(f"note: removed {visible(stale)} (a temporary file left by a killed camopt)",
                  file=sys.stderr)
        yield
    if replaced:
        print(f"note: --force: replaced {visible(path)} ({replaced})", file=sys.stderr)


@contextlib.contextmanager
def progress(quiet: bool) -> Iterator[Any]:
    """Rich progress bars on stderr when it is a terminal: the search (repeats x
    iterations) and a robust run's final check (designs x draws, rows). Yields the two
    callbacks (None, None with ``--quiet`` or without a terminal); one live display."""
    if quiet or not err.is_terminal:
        yield None, None
        return
    from rich import progress as rp

    columns = (rp.TextColumn("{task.description}"), rp.BarColumn(), rp.MofNCompleteColumn(),
               rp.TextColumn("best {task.fields[best]}"), rp.TimeElapsedColumn())
    # the objective named: a robust run's is the normalised yield margin (<= 0 met), not
    # the case's quantity
    with rp.Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("solving", total=None, best="-")

        def callback(p: Any) -> None:
            total = p.repeats * (p.max_iterations or 1)
            done = p.repeat * (p.max_iterations or 1) + p.iteration
            bar.update(task, total=total, completed=done,
                       best=f"{p.objective_name} {p.best_objective:.6g}",
                       description=f"repeat {p.repeat + 1}/{p.repeats}")

        def check(done: int, total: int) -> None:
            bar.update(task, total=total, completed=done, best="-",
                       description="robust final check (samples)")

        yield callback, check


