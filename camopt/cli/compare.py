"""``camopt compare``: runs side by side with a significance test, or a sweep's ranking."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape

from camopt.cli.app import Format, app, errors, fmt, out
from camopt.cli.layout import print_table
from camopt.errors import CamoptError


@app.command()
def compare(runs: Annotated[list[Path], typer.Argument(metavar="RUN...",
                                                       help="run archives, or one sweep")],
            format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
            ) -> None:
    """Compare runs (config differences, designs, statistics, a significance test for two)
    or rank the grid points of a sweep."""
    from camopt import archive, report
    from camopt.archive.sweeps import load_sweep

    with errors():
        if len(runs) == 1 and archive.archive_kind(runs[0]) == "sweep":
            doc = report.rank_sweep(*load_sweep(runs[0]))
            if format is Format.json:
                sys.stdout.write(json.dumps(doc, indent=2) + "\n")
            else:
                print_ranking(doc)
            return
        if len(runs) < 2:
            raise CamoptError("compare: RUN: give at least two run archives, or one sweep")
        doc = report.compare([archive.load_run(p) for p in runs], raw=True)
    if format is Format.json:
        sys.stdout.write(json.dumps(report.jsonable(doc), indent=2) + "\n")
        return
    names = [Path(p).name for p in doc["runs"]]
    _print_verdicts(doc, names)
    print_table("compare", ["", *names], _rows(doc),
                numeric=[False, *(True for _ in names)])
    for same in doc["same_objective_different_designs"]:
        i, j = same["runs"]
        out.print(f"[bold]note[/]: {escape(names[i])} and {escape(names[j])} reach one "
                  f"objective ({report.format_value(same['objective'])}) with different "
                  f"designs (differing in {escape(', '.join(same['differ']))}): the "
                  "objective is flat there or has several optima", highlight=False)
    if "hypervolume" in doc:
        _print_hypervolume(doc["hypervolume"], names)
    for test in doc["tests"]:
        a, b = escape(names[0]), escape(names[1])
        out.print(f"A = {a}, B = {b}: Mann-Whitney p = {test['p_value']:.3g}, "
                  f"P(A better) = {test['p_a_better']:.2f}; success A "
                  f"{_rate(test['success_a'])}, B {_rate(test['success_b'])}")
        out.print(f"[bold]{escape(test['verdict'])}[/]")


def _print_verdicts(doc: dict[str, Any], names: list[str]) -> None:
    """Each run's verdict in words, then requirement | limit | one value per run (with
    pass or FAIL)."""
    from camopt import report

    for name, judged, words in zip(names, doc["verdict"], doc["verdict_sentence"]):
        style = "green" if judged == "pass" else "bold red"
        out.print(f"{escape(name)}: [{style}]{escape(words)}[/]", highlight=False)
    rows: dict[str, list[str]] = {}
    for k, reqs in enumerate(doc["requirements"]):
        for cells in report.verdict_rows(reqs):
            row = rows.setdefault(cells[0], [cells[0], cells[1], *("-" for _ in names)])
            row[2 + k] = f"{cells[2]} {cells[4]}"
    print_table("requirements", ["requirement", "limit", *names], list(rows.values()),
                numeric=[False, True, *(True for _ in names)])


def _rows(doc: dict[str, Any]) -> list[list[str]]:
    """The compare table's rows: config differences, objective, feasibility, variables,
    metrics (without those already shown: a variable repeated as a metric, ``feasible``
    as 1, the reference design's ``initial_*`` when equal in every run) and repeat
    statistics; values as :func:`camopt.report.format_value` prints them."""
    from camopt import report

    def row(name: str, values: list[Any]) -> list[str]:
        return [name, *(report.format_value(v) for v in values)]

    rows = [row(k, v) for k, v in doc["config_differences"].items()]
    rows += [row("objective", doc["objective"]), row("feasible", doc["feasible"])]
    rows += [row(k, v) for k, v in doc["x"].items()]
    shown = {"feasible", "objective", *doc["x"]}
    for key, values in doc["metrics"].items():
        same = all(v == values[0] for v in values)
        if key in shown or (key.startswith(report.REFERENCE_PREFIXES) and same):
            continue
        rows.append(row(key, values))
    for stat in ("runs", "best", "median", "worst", "feasible_fraction", "success_rate"):
        rows.append(row(f"repeats: {stat}", [s[stat] for s in doc["statistics"]]))
    return rows


def _print_hypervolume(hv: dict[str, Any], names: list[str]) -> None:
    ref = ", ".join(f"{n} {fmt(v)}" for n, v in zip(hv["objectives"], hv["reference_point"] or []))
    out.print(f"hypervolume of the feasible fronts (normalised by their union; reference "
              f"point {ref or '-'}; larger is better):")
    for name, value, size in zip(names, hv["values"], hv["sizes"]):
        out.print(f"  {name}: {value:.4f} ({size} designs)")


def _rate(s: dict[str, float]) -> str:
    return f"{s['rate']:.0%} [{s['ci_low']:.0%}, {s['ci_high']:.0%}]"


def print_ranking(doc: dict[str, Any]) -> None:
    """A sweep's verdict (each grid point's success rate against run.min_success_rate)
    and its grid points ranked (``report.rank_sweep``): a table, or ``name: value`` lines
    when a word would not fit."""
    from camopt import report
    from camopt.cli.show import print_verdict

    print_verdict(doc, "sweep (run.min_success_rate)")

    rows = []
    for r in doc["ranking"]:
        vs = r.get("vs_best")
        rows.append([str(r["rank"]), r["label"], f"{r['successes']}/{r['runs']}",
                     *(report.format_value(r[k]) for k in ("best", "median",
                                                            "median_nfev_to_target")),
                     f"{vs['p_value']:.3g}" if vs else "-"])
    print_table(f"sweep {doc['sweep']}: grid points ranked", ["rank", "grid point",
                "success", "best", "median", "nfev", "p"], rows,
                numeric=[True, False, True, True, True, True, True])
    out.print("success: successful/runs; nfev: median evaluations to the target; p: "
              "Mann-Whitney against rank 1; worst and more: --format json", highlight=False)
    for r in doc["ranking"]:
        if r.get("vs_best"):
            out.print(escape(r["vs_best"]["verdict"]))
