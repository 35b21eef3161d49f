"""One table layout for every command: columns when every word fits the console, else a
vertical ``name: value`` layout; a word (a header, a number, a name with underscores) is
never split across lines.

Cells are plain text (markup escaped here); rich wraps a column only at spaces, so a table
is drawn as columns when the longest word of each column, padded, fits the console's width.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py).
"""

from __future__ import annotations

import shlex
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

from rich.cells import cell_len
from rich.table import Table

from camopt.cli.console import escape, fmt, out, plain, visible

if TYPE_CHECKING:
    from camopt.core.documents import FrontsCompared, ParetoSummary
    from camopt.core.runview import RunView
    from camopt.reporting.comparisons import Comparison, SweepRanking
    from camopt.reporting.views import (
        ReferenceVerdict,
        RobustSummary,
        RobustYield,
        ShowView,
        Summary,
        Verdict,
    )

BORDER = 3
"""Characters a column adds to its text: a rule and a space each side."""


def _longest_word(text: str) -> int:
    """The most terminal cells a word of ``text`` takes, as printed (:func:`visible`)."""
    return max((cell_len(w) for w in visible(text).split()), default=0)


def fits(columns: Sequence[str], rows: Sequence[Sequence[str]], width: int,
         numeric: Sequence[bool] = ()) -> bool:
    """Whether the columns fit ``width`` with every column as wide as its longest word
    (header included), or its longest cell for a ``numeric`` column (printed unwrapped)."""
    def need(i: int, c: str) -> int:
        whole = i < len(numeric) and numeric[i]
        cells = [cell_len(visible(r[i])) if whole else _longest_word(r[i]) for r in rows]
        return BORDER + max(_longest_word(c), *cells)

    total = 1 + sum(need(i, c) for i, c in enumerate(columns)) if rows else 0
    return total <= width


def print_table(title: str, columns: Sequence[str], rows: Sequence[Sequence[str]],
                numeric: Sequence[bool] | None = None, styles: Sequence[str | None] = (),
                sections: Sequence[int] = ()) -> None:
    """Print ``rows`` of plain-text cells under ``columns``: as a table when it fits the
    console without splitting a word, else vertically (the first cell as a heading, then
    its ``column: value`` pairs, wrapped at spaces). ``numeric`` right-justifies columns;
    ``styles`` colours whole rows (``"red"``); ``sections`` are row indices a rule goes
    before."""
    numeric = list(numeric) if numeric is not None else [i > 0 for i in range(len(columns))]
    styles = list(styles) + [None] * (len(rows) - len(styles))
    if title:  # a line of its own: a table's title wraps at the table's width
        out.print(f"[italic]{escape(title)}[/]", highlight=False)
    if fits(columns, rows, out.width, numeric):
        table = Table()
        for i, (c, num) in enumerate(zip(columns, numeric)):
            # a column of single words (names, kinds) is never folded inside one: rich
            # would otherwise shrink it with the wrapping ones ("fast_swi|tch")
            words = all(len(r[i].split()) <= 1 for r in rows)
            table.add_column(escape(c), justify="right" if num else "left",
                             overflow="fold" if not num else "ellipsis", no_wrap=num or words)
        for i, row in enumerate(rows):
            if i in sections and i:
                table.add_section()
            table.add_row(*(escape(c) for c in row), style=styles[i])
        out.print(table)
        return
    for i, row in enumerate(rows):
        style = styles[i]
        head = escape(row[0]) if row else ""
        out.print(f"[bold]{head}[/]" if style is None else f"[bold {style}]{head}[/]",
                  highlight=False, soft_wrap=True)
        pairs = "; ".join(f"{escape(c)}: {escape(v)}" for c, v in zip(columns[1:], row[1:]))
        out.print(f"  {pairs}", highlight=False)  # wraps at spaces, never inside a word


def print_rows(title: str, rows: Sequence[Mapping[str, object]], columns: list[str],
               limit: int | None) -> None:
    """The given columns (those present) through the word-safe layout
    (:func:`camopt.cli.layout.print_table`); every column is in the JSON."""
    columns = [c for c in columns if c in rows[0]]
    note = "all columns: --format json"
    if limit is not None and len(rows) > limit:
        note = (f"first {limit} of {len(rows)} rows; camopt show for all, "
                "--format json for all columns")
    cells = [[plain(row.get(c)) for c in columns] for row in rows[:limit]]
    print_table(f"{title} ({note})", columns, cells, numeric=[True] * len(columns))



def cell(value: Any) -> str:
    """A table cell (:func:`camopt.reporting.report.format_value`), rich markup escaped."""
    from camopt.reporting import report

    return escape(report.format_value(value))


def print_show(view: RunView, rows: int | None = None, brief: bool = False) -> None:
    """The run summary: what ran, the best design beside the reference design (two
    columns, units in the names), the repeats (the first ``rows``) and the solver's table,
    and the verdict again as the last lines with the next step (:func:`print_closing`).
    Fits 80 columns: numbers are never wrapped, names fold when they must. ``brief``
    (``run`` without ``--verbose``): the requirements not met or at their limit, the
    repeats in a line, the closing lines (:func:`print_brief`)."""
    from camopt.reporting import report

    doc = report.show(view)
    out.print(escape(view.path), soft_wrap=True, highlight=False)
    reps = view.repeats
    n_run = view.run.get("repeats", len(reps))
    done = f"{len(reps)} of {n_run}" if view.interrupted else f"{len(reps)}"
    out.print(f"case [cyan]{escape(view.kind)}[/], solver [cyan]{escape(view.solver_name)}[/], "
              f"{done} repeats, seed {view.run.get('seed', '-')}", highlight=False)
    if view.interrupted:
        out.print("[bold red]interrupted[/]: the archive holds the finished repeats only")
    if brief:
        print_brief(view, doc)
        return
    print_verdict(doc.verdict, robust_yield=doc.robust_yield,
                  expected_yield=doc.expected_yield, reference=doc.reference)
    if doc.pareto_summary:
        print_pareto(doc.pareto_summary)
    style = "green" if view.best.feasible else "bold red"
    out.print(f"run's constraints: [{style}]{escape(report.status(view))}[/]", highlight=False)
    print_best(report.summary(view))  # raw values: inf and NaN are shown
    forms = doc.findings.get("model_forms")
    if forms:  # an identification's forms (the parameters: --format json)
        print_fitted("model forms fitted on the same data", report.jsonable(forms),
                     ["name", "misfit", "max_residual_pct", "kept"], None)
    robust = report.robust_summary(view)
    if robust is not None:
        out.print(robust_table(robust))
    print_repeats(doc, rows)
    for r in doc.repeats:
        for note in r.notes:
            out.print(f"[bold]note[/] (repeat {r.spawn_key[-1]}): {escape(note)}",
                      highlight=False)
    if doc.table:
        columns = ["label", *doc.best.x, view.objective_name, "feasible", "active",
                   "violated"]
        print_fitted("solver's table", report.jsonable(doc.table), columns, rows)
    print_closing(doc.verdict.short, doc.verdict.style, doc.next, doc.robust_yield)


def print_brief(view: RunView, doc: ShowView) -> None:
    """``run``'s short summary: the requirements the best design fails or meets only at
    their limit (all of them: ``camopt show``), a Pareto run's front size, the run's
    constraints and the repeats in a line each, then the closing lines."""
    from camopt.reporting import report

    judged = doc.verdict
    keep = [i for i, c in enumerate(judged.checks) if c.passed is False or c.at_limit]
    rows = report.verdict_rows(judged.checks)
    styles = ["red" if judged.checks[i].passed is False else "yellow" for i in keep]
    if keep:
        print_table(f"requirements not met or at their limit ({len(keep)} of "
                    f"{len(rows)})", report.VERDICT_COLUMNS, [rows[i] for i in keep],
                    numeric=[False, True, True, False, True], styles=styles)
    if doc.pareto_summary:
        p = doc.pareto_summary
        out.print(escape(pareto_title(p)), highlight=False)
    style = "green" if view.best.feasible else "bold red"
    out.print(f"run's constraints: [{style}]{escape(report.status(view))}[/]", highlight=False)
    print_repeats(doc, 0)
    out.print(escape(f"details (design, metrics, repeats, reference): camopt show "
                     f"{shlex.quote(view.path)}"), highlight=False)
    print_closing(judged.short, judged.style, doc.next, doc.robust_yield)


def print_closing(headline: str, style: str, next_line: str,
                  robust_yield: RobustYield | None = None) -> None:
    """The last lines of ``run``, ``show`` (and any command ending in a verdict): a rule,
    the verdict in a line (its grade's colour), a robust run's yield against its target,
    and the ``next:`` step."""
    from camopt.reporting import report

    out.rule(style="dim")
    tone = f"bold {style}" if style else "bold"
    out.print(f"[{tone}]verdict: {escape(headline)}[/]", highlight=False)
    if robust_yield is not None:
        out.print(escape(report.robust_text(robust_yield)), highlight=False)
    out.print(f"[bold]{escape(next_line)}[/]", highlight=False)


def print_verdict(judged: Verdict, title: str = "best design", *,
                  robust_yield: RobustYield | None = None,
                  expected_yield: Mapping[str, Any] | None = None,
                  reference: ReferenceVerdict | None = None) -> None:
    """The answer first: a robust run's yield against its target, the overall verdict in
    words, the expected yield, then the requirement | limit | value | margin | pass table
    of ``judged``, and the reference design's verdict in one line."""
    from camopt.reporting import report

    if robust_yield is not None:
        met = robust_yield.meets_target
        style = "bold green" if met else "bold red" if met is False else "bold"
        out.print(f"[{style}]{escape(report.robust_text(robust_yield))}[/]",
                  highlight=False)
    style = f"bold {judged.style}" if judged.style else "bold"
    out.print(f"[{style}]{escape(judged.headline)}[/]", highlight=False)
    if expected_yield and judged.verdict != "pass":
        out.print(escape(report.yield_text(report.jsonable(expected_yield))),
                  highlight=False)
    rows = report.verdict_rows(judged.checks)
    styles = ["red" if c.passed is False else "yellow" if c.at_limit else None
              for c in judged.checks]
    if rows:
        print_table(f"requirements of the {title}", report.VERDICT_COLUMNS, rows,
                    numeric=[False, True, True, False, True], styles=styles)
    if reference is not None:
        words = {"pass": "[green]PASS[/]", "fail": "[red]FAIL[/]"}.get(
            reference.verdict or "", "not judged")
        said = reference.verdict_sentence.removeprefix("PASS: ").removeprefix("FAIL: ")
        out.print(f"{escape(reference.label)}: {words}: {escape(said)}", highlight=False)


def print_pareto(doc: ParetoSummary) -> None:
    """A Pareto run's front: objectives, extent and knee, and what the headline is."""
    from camopt.reporting import report

    print_table(pareto_title(doc),
                report.PARETO_COLUMNS, report.pareto_rows(doc),
                numeric=[False, False, True, True, True])
    if doc["knee"]:
        knee = ", ".join(f"{k} {report.format_value(v)}" for k, v in doc["knee"].items())
        out.print(f"knee (nearest the ideal, objectives normalised): {escape(knee)}",
                  highlight=False)
    out.print(f"headline design below: {escape(doc['headline'])}", highlight=False)


def pareto_title(doc: ParetoSummary) -> str:
    """``Pareto front: 12 feasible of 40 designs``, or what an empty front means beside
    the headline design's verdict."""
    if not doc["designs"]:
        return ("Pareto front: none stored (the run's table is empty); the verdict is the "
                "headline design's alone")
    if not doc["front_size"]:
        which = ("the final design is" if doc["designs"] == 1
                 else f"none of the {doc['designs']} final designs is")
        return (f"Pareto front: empty ({which} not feasible); the verdict is the headline "
                "design's (the best the search saw)")
    return f"Pareto front: {doc['front_size']} feasible of {doc['designs']} designs"


def print_best(summary: Summary) -> None:
    """The best design beside the reference design (``report.summary``)."""
    from camopt.reporting import report

    label = summary.reference_label
    columns = ["quantity", "optimum", *(["reference"] if label else [])]
    rows, sections, section = [], [], None
    for i, row in enumerate(summary.rows):
        if row.section != section:
            sections.append(i)
        section = row.section
        values = [row.optimum, row.reference] if label else [row.optimum]
        name = f"objective: {row.name}" if i == 0 else row.name
        rows.append([name, *(report.format_value(v) for v in values)])
    print_table("best design" + (f" beside the {label}" if label else ""), columns, rows,
                sections=sections)


def robust_table(summary: RobustSummary) -> Table:
    """A robust run's final check beside the best nominal design (``report.robust_summary``)."""
    table = Table(title=f"robust check ({summary.samples} fresh draws for both; "
                  f"target {cell(summary.yield_target)})", title_justify="left")
    table.add_column("", overflow="fold")
    for label in summary.labels:
        table.add_column(label, justify="right", no_wrap=True)
    for row in summary.rows:
        table.add_row(escape(row.name), *(cell(v) for v in row.values))
    return table


def print_repeats(doc: ShowView, rows: int | None) -> None:
    """The repeats' feasibility and objectives in one line, then (several repeats) a table
    of the first ``rows``."""
    reps = [r.to_json() for r in doc.repeats]  # as JSON: unbounded objectives as '-'
    stats = [r["objective"] for r in reps if r["feasible"] and r["objective"] is not None]
    line = f"repeats: {sum(r['feasible'] for r in reps)} of {len(reps)} feasible"
    if stats:
        line += (f"; objective best {cell(min(stats))}, median "
                 f"{cell(float(sorted(stats)[len(stats) // 2]))}, worst {cell(max(stats))}")
    out.print(line, highlight=False)
    if len(reps) <= 1 or rows == 0:
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
        table.add_row(cell(r["spawn_key"][-1]), cell(r["objective"]), cell(r["feasible"]),
                      cell(r["nfev"]), cell(r["converged_nit"]), f"{r['wall_s']:.2f}")
    out.print(table)


def print_fitted(title: str, rows: Sequence[Mapping[str, object]], columns: list[str],
                 limit: int | None) -> None:
    """A table of as many of ``columns`` as fit the console without wrapping a number
    (the rest are in ``--format json``); the first ``limit`` rows."""
    columns = [c for c in columns if c in rows[0]]
    shown_rows = rows if limit is None else rows[:limit]
    from camopt.reporting import report

    raw = {c: [report.format_value(r.get(c)) for r in shown_rows] for c in columns}
    texts = {c: [escape(t) for t in raw[c]] for c in columns}  # as cell() makes them
    width, kept, widths = 1, list[str](), list[int]()
    for c in columns:  # as printed: escape() shows a name as visible() does
        w = max(cell_len(visible(c)), *(cell_len(visible(t)) for t in raw[c]))
        if kept and width + w + BORDER > out.width:
            break
        kept.append(c)
        widths.append(w)
        width += w + BORDER
    notes = []
    if len(kept) < len(columns):
        notes.append(f"{len(kept)} of {len(columns)} columns")
    if len(shown_rows) < len(rows):
        notes.append(f"first {len(shown_rows)} of {len(rows)} rows")
    note = ("; ".join(notes) + "; all: camopt show --format json") if notes else ""
    table = Table(title=escape(f"{title} ({note})" if note else title), title_justify="left")
    for c, w in zip(kept, widths):  # its width given: rich need not measure every cell
        table.add_column(escape(c), justify="right", no_wrap=True, width=w)
    for i in range(len(shown_rows)):
        table.add_row(*(texts[c][i] for c in kept))
    out.print(table)



def print_verdicts(verdicts: Sequence[Verdict], names: Sequence[str]) -> None:
    """Each run's verdict in words, then requirement | limit | one value per run (3
    significant digits, with pass, FAIL or at limit)."""
    from camopt.core.requirements import value_text
    from camopt.reporting import report

    for name, judged in zip(names, verdicts):
        style = f"bold {judged.style}" if judged.style else "bold"
        out.print(f"{escape(name)}: [{style}]{escape(judged.headline)}[/]", highlight=False)
    rows: dict[str, list[str]] = {}
    for k, judged in enumerate(verdicts):
        for c, cells in zip(judged.checks, report.verdict_rows(judged.checks)):
            row = rows.setdefault(cells[0], [cells[0], cells[1], *("-" for _ in names)])
            value = c.value
            shown = (f"{value_text(c.requirement, value)} {c.requirement.unit}".strip()
                     if isinstance(value, float) and c.requirement.limit != "yes"
                     and value == value else cells[2])
            row[2 + k] = f"{shown} {cells[4]}"
    print_table("requirements", ["requirement", "limit", *names], list(rows.values()),
                numeric=[False, True, *(True for _ in names)])


NOISE = 1e-12  # camopt.reporting.report.NOISE: round-off, printed as 0
COMPARE_METRIC_RTOL = 1e-3
"""``compare``'s table lists a metric only where the runs differ by more than this share of
its magnitude (every metric is in ``--format json``)."""


def _differ(values: list[Any]) -> bool:
    nums = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if len(nums) != len(values):
        return any(v != values[0] for v in values)
    finite = [float(v) if abs(v) >= NOISE else 0.0 for v in nums
              if v == v and abs(v) != float("inf")]
    if len(finite) != len(nums):
        return any(repr(v) != repr(nums[0]) for v in nums)
    scale = max(abs(v) for v in finite)
    return max(finite) - min(finite) > COMPARE_METRIC_RTOL * scale


def compare_rows(doc: Comparison) -> list[list[str]]:
    """The compare table's rows: config differences, objective, feasibility, variables,
    the metrics that differ between the runs (:data:`COMPARE_METRIC_RTOL`; not those
    already shown: a variable repeated as a metric, ``feasible`` as 1, the reference
    design's ``initial_*``), and the repeats' median and successes; values as
    :func:`camopt.reporting.report.format_value` prints them."""
    from camopt.reporting import report

    def row(name: str, values: list[Any]) -> list[str]:
        return [name, *(report.format_value(v) for v in values)]

    rows = [row(k, v) for k, v in doc.config_differences.items()]
    rows += [row("objective", list(doc.objective)), row("feasible", list(doc.feasible))]
    rows += [row(k, v) for k, v in doc.x.items()]
    shown = {"feasible", "objective", *doc.x}
    same = 0
    for key, values in doc.metrics.items():
        if key in shown or key.startswith(report.REFERENCE_PREFIXES):
            continue
        if not _differ(values):
            same += 1
            continue
        rows.append(row(key, values))
    if same:
        rows.append([f"other metrics ({same})", *("same" for _ in doc.objective)])
    rows.append(row("repeats: median", [s.median for s in doc.statistics]))
    rows.append(["repeats: successes", *(f"{s.successes}/{s.runs}"
                                         for s in doc.statistics)])
    return rows


def print_hypervolume(hv: FrontsCompared, names: Sequence[str]) -> None:
    ref = ", ".join(f"{n} {fmt(v)}" for n, v in zip(hv["objectives"], hv["reference_point"] or []))
    out.print(f"hypervolume of the feasible fronts (normalised by their union; reference "
              f"point {ref or '-'}; larger is better):")
    for name, value, size in zip(names, hv["values"], hv["sizes"]):
        out.print(f"  {name}: {value:.4f} ({size} designs)")


def success_rate_text(s: Mapping[str, float]) -> str:
    return f"{s['rate']:.0%} [{s['ci_low']:.0%}, {s['ci_high']:.0%}]"


def print_ranking(doc: SweepRanking) -> None:
    """A sweep's verdict (each grid point's success rate against run.min_success_rate)
    and its grid points ranked (``report.rank_sweep``): a table, or ``name: value`` lines
    when a word would not fit."""
    from camopt.reporting import report

    print_verdict(doc.verdict, "sweep (run.min_success_rate)")

    rows = []
    for r in doc.ranking:
        vs = r.vs_best
        rows.append([str(r.rank), r.label, f"{r.row['successes']}/{r.row['runs']}",
                     *(report.format_value(report.jsonable(r.row[k]))
                       for k in ("best", "median", "median_nfev_to_target")),
                     f"{vs.p_value:.3g}" if vs else "-"])
    print_table(f"sweep {doc.sweep}: grid points ranked", ["rank", "grid point",
                "success", "best", "median", "nfev", "p"], rows,
                numeric=[True, False, True, True, True, True, True])
    out.print("success: successful/runs; nfev: median evaluations to the target; p: "
              "Mann-Whitney against rank 1; worst and more: --format json", highlight=False)
    for r in doc.ranking:
        if r.vs_best:
            out.print(escape(r.vs_best.verdict))

