"""``camopt show``: a run archive's summary (the best design beside the reference design,
repeats, the solver's table), or a sweep archive's ranking."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from camopt.cli.app import Format, app, errors, out
from camopt.cli.layout import print_table

if TYPE_CHECKING:
    from camopt.runview import RunView


@app.command()
def show(run_paths: Annotated[list[Path], typer.Argument(
             metavar="RUN_OR_SWEEP...", help="run or sweep archives (a glob may match several)")],
         format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
         ) -> None:
    """Show archives: a run's best design beside the reference design, its repeats and
    table; a sweep's grid points ranked (as compare SWEEP). Several archives (a glob such
    as runs/NAME-*.h5) are each shown, in the order given (a glob's order: oldest
    first, as the names carry the time); with --format json, as a JSON array."""
    from camopt import archive, report
    from camopt.archive.sweeps import load_sweep
    from camopt.cli.compare import print_ranking

    with errors():  # every archive read before anything is printed
        loaded: list[tuple[str, Any]] = []
        for path in run_paths:
            if archive.archive_kind(path) == "sweep":
                loaded.append(("sweep", report.rank_sweep(*load_sweep(path))))
            else:
                loaded.append(("run", archive.load_run(path)))
    if format is Format.json:
        docs = [item if kind == "sweep" else report.show(item) for kind, item in loaded]
        sys.stdout.write(json.dumps(docs[0] if len(docs) == 1 else docs, indent=2) + "\n")
        return
    for i, (kind, item) in enumerate(loaded):
        if i:
            out.print()
        if kind == "sweep":
            print_ranking(item)
        else:
            print_show(item)


def cell(value: Any) -> str:
    """A table cell (:func:`camopt.report.format_value`), rich markup escaped."""
    from camopt import report

    return escape(report.format_value(value))


def print_show(view: RunView, rows: int | None = None) -> None:
    """The run summary: what ran, the best design beside the reference design (two
    columns, units in the names), the repeats (the first ``rows``) and the solver's table.
    Fits 80 columns: numbers are never wrapped, names fold when they must."""
    from camopt import report

    doc = report.show(view)
    out.print(escape(view.path), soft_wrap=True, highlight=False)
    reps = view.repeats
    n_run = view.run.get("repeats", len(reps))
    done = f"{len(reps)} of {n_run}" if view.interrupted else f"{len(reps)}"
    out.print(f"case [cyan]{escape(view.kind)}[/], solver [cyan]{escape(view.solver_name)}[/], "
              f"{done} repeats, seed {view.run.get('seed', '-')}", highlight=False)
    if view.interrupted:
        out.print("[bold red]interrupted[/]: the archive holds the finished repeats only")
    print_verdict(doc)
    if doc.get("pareto_summary"):
        print_pareto(doc["pareto_summary"])
    style = "green" if view.best.feasible else "bold red"
    out.print(f"run's constraints: [{style}]{escape(report.status(view))}[/]", highlight=False)
    print_best(report.summary(view))  # raw values: inf and NaN are shown
    robust = report.robust_summary(view)
    if robust is not None:
        out.print(robust_table(robust))
    _print_repeats(doc, rows)
    for r in doc["repeats"]:
        for note in r["notes"]:
            out.print(f"[bold]note[/] (repeat {r['spawn_key'][-1]}): {escape(note)}",
                      highlight=False)
    if doc["table"]:
        best = doc["best"]
        columns = ["label", *best["x"], view.objective_name, "feasible", "active", "violated"]
        print_fitted("solver's table", doc["table"], columns, rows)


def print_verdict(doc: dict[str, Any], title: str = "best design") -> None:
    """The overall verdict in words, the requirement | limit | value | margin | pass table
    of ``doc`` (``report.show``'s), and the reference design's verdict in one line."""
    from camopt import report

    style = "bold green" if doc["verdict"] == "pass" else "bold red"
    out.print(f"[{style}]{escape(doc['verdict_sentence'])}[/]", highlight=False)
    rows = report.verdict_rows(doc["requirements"])
    styles = ["red" if r["pass"] is False else None for r in doc["requirements"]]
    if rows:
        print_table(f"requirements of the {title}", report.VERDICT_COLUMNS, rows,
                    numeric=[False, True, True, True, True], styles=styles)
    ref = doc.get("reference")
    if ref:
        judged = {"pass": "[green]PASS[/]", "fail": "[red]FAIL[/]"}.get(ref["verdict"] or "",
                                                                      "not judged")
        words = ref["verdict_sentence"].removeprefix("PASS: ").removeprefix("FAIL: ")
        out.print(f"{escape(ref['label'])}: {judged}: {escape(words)}", highlight=False)


def print_pareto(doc: dict[str, Any]) -> None:
    """A Pareto run's front: objectives, extent and knee, and what the headline is."""
    from camopt import report

    print_table(f"Pareto front: {doc['front_size']} feasible of {doc['designs']} designs",
                report.PARETO_COLUMNS, report.pareto_rows(doc),
                numeric=[False, False, True, True, True])
    if doc["knee"]:
        knee = ", ".join(f"{k} {report.format_value(v)}" for k, v in doc["knee"].items())
        out.print(f"knee (nearest the ideal, objectives normalised): {escape(knee)}",
                  highlight=False)
    out.print(f"headline design below: {escape(doc['headline'])}", highlight=False)


def print_best(summary: dict[str, Any]) -> None:
    """The best design beside the reference design (``report.summary``)."""
    from camopt import report

    label = summary["reference_label"]
    columns = ["quantity", "optimum", *(["reference"] if label else [])]
    rows, sections, section = [], [], None
    for i, row in enumerate(summary["rows"]):
        if row["section"] != section:
            sections.append(i)
        section = row["section"]
        values = [row["optimum"], row["reference"]] if label else [row["optimum"]]
        name = f"objective: {row['name']}" if i == 0 else row["name"]
        rows.append([name, *(report.format_value(v) for v in values)])
    print_table("best design" + (f" beside the {label}" if label else ""), columns, rows,
                sections=sections)


def robust_table(summary: dict[str, Any]) -> Table:
    """A robust run's final check beside the best nominal design (``report.robust_summary``)."""
    table = Table(title=f"robust check ({summary['samples']} fresh draws for both; "
                  f"target {cell(summary['yield_target'])})", title_justify="left")
    table.add_column("", overflow="fold")
    for label in summary["labels"]:
        table.add_column(label, justify="right", no_wrap=True)
    for row in summary["rows"]:
        table.add_row(escape(row["name"]), *(cell(v) for v in row["values"]))
    return table


def _print_repeats(doc: dict[str, Any], rows: int | None) -> None:
    reps = doc["repeats"]
    stats = [r["objective"] for r in reps if r["feasible"] and r["objective"] is not None]
    line = f"repeats: {sum(r['feasible'] for r in reps)} of {len(reps)} feasible"
    if stats:
        line += (f"; objective best {cell(min(stats))}, median "
                 f"{cell(float(sorted(stats)[len(stats) // 2]))}, worst {cell(max(stats))}")
    out.print(line, highlight=False)
    if len(reps) <= 1:
        return
    shown = reps if rows is None else reps[:rows]
    title = "repeats (repeat k: child k of SeedSequence(run.seed))"
    if len(shown) < len(reps):
        title += f"; first {len(shown)} of {len(reps)}, camopt show for all"
    table = Table(title=title, title_justify="left")
    columns = ("objective", "feasible", "nfev", "converged_nit")
    for col in ("repeat", *columns, "wall_s"):
        table.add_column(col, justify="right", no_wrap=True)
    for r in shown:
        table.add_row(cell(r["spawn_key"][-1]), *(cell(r[c]) for c in columns),
                      f"{r['wall_s']:.2f}")
    out.print(table)


def print_fitted(title: str, rows: list[dict[str, Any]], columns: list[str],
                 limit: int | None) -> None:
    """A table of as many of ``columns`` as fit the console without wrapping a number
    (the rest are in ``--format json``); the first ``limit`` rows."""
    columns = [c for c in columns if c in rows[0]]
    shown_rows = rows if limit is None else rows[:limit]
    texts = {c: [cell(r.get(c)) for r in shown_rows] for c in columns}
    width, kept = 1, list[str]()
    for c in columns:
        w = max(len(c), *(len(t) for t in texts[c])) + 3  # padding and a rule
        if kept and width + w > out.width:
            break
        kept.append(c)
        width += w
    notes = []
    if len(kept) < len(columns):
        notes.append(f"{len(kept)} of {len(columns)} columns")
    if len(shown_rows) < len(rows):
        notes.append(f"first {len(shown_rows)} of {len(rows)} rows")
    note = ("; ".join(notes) + "; all: camopt show --format json") if notes else ""
    table = Table(title=escape(f"{title} ({note})" if note else title), title_justify="left")
    for c in kept:
        table.add_column(escape(c), justify="right", no_wrap=True)
    for i in range(len(shown_rows)):
        table.add_row(*(texts[c][i] for c in kept))
    out.print(table)
