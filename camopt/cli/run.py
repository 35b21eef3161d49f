"""``camopt run``: run a case file and write a run archive.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import contextlib
import sys
import time
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
    from camopt.engine.driver import execute
    from camopt.engine.setup import prepare
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


PLAIN_EVERY_S = 60.0
"""Without a terminal (a pipe, a log file), one plain progress line this often."""


def progress_line(p: Any, elapsed: float) -> str:
    """``repeat 2/5: 43 % of the budget (evaluations), about 3 min left; best objective_j
    0.0123`` (or ``infeasible, worst: <constraint>``): the share done on the binding
    budget over all repeats, and a time left from the time so far."""
    frac = p.fraction
    if frac is None:
        return f"repeat {p.repeat + 1}/{p.repeats}: iteration {p.iteration}; {p.best_text}"
    done = (p.repeat + frac) / max(p.repeats, 1)
    left = elapsed * (1 - done) / done if done > 0 else None
    eta = "" if left is None else f", about {_duration(left)} left"
    return (f"repeat {p.repeat + 1}/{p.repeats}: {100 * done:.0f} % of the budget"
            f"{eta}; {p.best_text}")


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


@contextlib.contextmanager
def progress(quiet: bool) -> Iterator[Any]:
    """Progress on stderr, measured on the binding budget (iterations, evaluations or
    seconds: ``Progress.fraction``) over all repeats, with the time left and the best
    feasible value so far or ``infeasible, worst: <constraint>``: a rich bar when stderr is
    a terminal, else one plain line a minute (:data:`PLAIN_EVERY_S`). Yields the search's
    callback and a robust run's final-check callback (None, None with ``--quiet``)."""
    if quiet:
        yield None, None
        return
    start = time.monotonic()
    if not err.is_terminal:
        last = [start]

        def plain(p: Any) -> None:
            now = time.monotonic()
            if now - last[0] >= PLAIN_EVERY_S:
                last[0] = now
                print(f"camopt run: {progress_line(p, now - start)}", file=sys.stderr,
                      flush=True)

        yield plain, None
        return
    from rich import progress as rp

    columns = (rp.TextColumn("{task.description}"), rp.BarColumn(),
               rp.TaskProgressColumn(), rp.TextColumn("{task.fields[best]}"),
               rp.TimeElapsedColumn(), rp.TimeRemainingColumn())
    with rp.Progress(*columns, console=err, transient=True) as bar:
        task = bar.add_task("solving", total=None, best="")

        def callback(p: Any) -> None:
            frac = p.fraction
            done = None if frac is None else (p.repeat + frac) / max(p.repeats, 1)
            bar.update(task, total=None if done is None else 1000,
                       completed=0 if done is None else round(1000 * done),
                       best=p.best_text, description=f"repeat {p.repeat + 1}/{p.repeats}")

        def check(done: int, total: int) -> None:
            bar.update(task, total=total, completed=done, best="",
                       description="robust final check (samples)")

        yield callback, check
