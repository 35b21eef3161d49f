"""``camopt report``: one self-contained HTML page per archive (Jinja2 template
``templates/report.html.j2``). Every figure is an inline SVG data URI and the style sheet is
in the page, so it opens without network access and can be handed over as one file.

Jinja2, the archives' readers and the figures (matplotlib) are imported where a report is
rendered."""

from __future__ import annotations

import base64
import io
import platform
from collections.abc import Mapping
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

from camopt import archive
from camopt.archive.sweeps import load_sweep
from camopt.core.documents import ParetoSummary, Row, RunStatisticsDoc, ToleranceDoc
from camopt.core.record import Repeat
from camopt.core.runview import RunView
from camopt.reporting import report
from camopt.reporting.comparisons import RankedPoint
from camopt.reporting.views import (
    ReferenceVerdict,
    RobustSummary,
    RobustYield,
    SummaryRow,
    Verdict,
)

if TYPE_CHECKING:  # annotations only: matplotlib is imported where a figure is drawn
    from matplotlib.figure import Figure

LIBRARIES = ("camopt", "numpy", "scipy", "h5py", "matplotlib", "pymoo", "pydantic", "Jinja2",
             "ezdxf")


class FigureDoc(TypedDict):
    """A figure on the page: its name, its title (one line) and its SVG data URI."""

    name: str
    title: str
    uri: str


class VerdictContext(TypedDict):
    """The verdict a page leads with (:func:`verdict_context`)."""

    verdict: str | None
    verdict_sentence: str
    verdict_class: str
    at_limit: list[str]
    robust_yield: str
    robust_met: bool | None
    expected_yield: str
    next_step: str
    verdict_columns: tuple[str, ...]
    verdict_rows: list[tuple[list[str], str]]


class RunContext(VerdictContext):
    """What ``report.html.j2`` shows of a run archive (:func:`run_context`)."""

    reference: ReferenceVerdict | None
    pareto: ParetoSummary | None
    pareto_rows: list[list[str]]
    pareto_columns: tuple[str, ...]
    kind: str
    title: str
    path: str
    case_kind: str
    case_summary: str
    paper_source: str
    solver: str
    created: str
    seed: int | None
    seed_entropy: str
    repeats_planned: int | None
    interrupted: bool
    status: str
    feasible: bool
    active: list[str]
    violated: list[str]
    objective_name: str
    reference_label: str
    rows: tuple[SummaryRow, ...]
    robust: RobustSummary | None
    statistics: RunStatisticsDoc
    target: float | None
    repeats: list[Repeat]
    table: list[Row]
    table_rows: int
    table_columns: list[str]
    notes: list[tuple[int, str]]
    figures: list[FigureDoc]
    config_toml: str
    versions: dict[str, str]
    environment: dict[str, str]


class SweepContext(VerdictContext):
    """What ``report.html.j2`` shows of a sweep archive (:func:`sweep_context`)."""

    reference: None
    kind: str
    title: str
    path: str
    source: str
    grid: list[tuple[str, list[Any]]]
    seeds: list[int]
    cells: int
    ranking: tuple[RankedPoint, ...]
    figures: list[FigureDoc]
    config_toml: str
    environment: dict[str, str]


class ToleranceContext(TypedDict):
    """What ``tolerance.html.j2`` shows of a tolerance archive."""

    title: str
    s: ToleranceDoc
    created: str
    figures: list[FigureDoc]


class CalibrationContext(TypedDict):
    """What ``calibration.html.j2`` shows of a calibration archive (``s``: the
    ``calibrate --format json`` document, whose entries the case extends)."""

    title: str
    s: Mapping[str, object]
    created: str
    case_kind: str
    config_toml: str
    figures: list[FigureDoc]


def number(value: Any) -> str:
    """A value as the report prints it (:func:`camopt.reporting.report.format_value`)."""
    return report.format_value(value)


def svg_uri(fig: Any) -> str:
    """A matplotlib figure as an ``data:image/svg+xml;base64,...`` URI (text as paths, so
    no font is needed to view it); the figure is closed."""
    from camopt.core.plotting import close

    buf = io.BytesIO()
    fig.savefig(buf, format="svg")
    close(fig)
    return "data:image/svg+xml;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _figures(figures: Mapping[str, Figure]) -> list[FigureDoc]:
    out: list[FigureDoc] = []
    for name, fig in figures.items():
        title = fig.axes[0].get_title() if fig.axes else name
        suptitle = getattr(fig, "_suptitle", None)  # get_suptitle() is matplotlib >= 3.8
        if not title and suptitle is not None:  # stacked axes: the figure's title
            title = suptitle.get_text()
        title = " ".join(title.split())  # a wrapped title is one line of text here
        out.append({"name": name, "title": title or name, "uri": svg_uri(fig)})
    return out


def _environment() -> dict[str, str]:
    found = {"python": platform.python_version()}
    for lib in LIBRARIES:
        try:
            found[lib] = version(lib)
        except PackageNotFoundError:
            found[lib] = "not installed"
    return found


def run_context(view: RunView) -> RunContext:
    """What the template shows of a run archive."""
    from camopt.cases import get_case
    from camopt.reporting import plots

    spec = get_case(view.kind)
    summary = report.summary(view)
    stats = report.repeat_statistics(view).as_dict()
    doc = report.show(view)
    return {
        **verdict_context(doc.verdict, doc.robust_yield, doc.expected_yield, doc.next),
        "reference": doc.reference, "pareto": doc.pareto_summary,
        "pareto_rows": report.pareto_rows(doc.pareto_summary)
        if doc.pareto_summary else [], "pareto_columns": report.PARETO_COLUMNS,
        "kind": "run", "title": f"{view.kind} / {view.solver_name}: {Path(view.path).name}",
        "path": view.path, "case_kind": view.kind, "case_summary": spec.summary,
        "paper_source": spec.paper_source, "solver": view.solver_name,
        "created": view.created, "seed": view.run.get("seed"),
        "seed_entropy": view.seed_entropy, "repeats_planned": view.run.get("repeats"),
        "interrupted": view.interrupted, "status": report.status(view),
        "feasible": view.best.feasible, "active": view.best.active,
        "violated": view.best.violated, "objective_name": view.objective_name,
        "reference_label": summary.reference_label, "rows": summary.rows,
        "robust": report.robust_summary(view),
        "statistics": stats, "target": view.run.get("target"),
        "repeats": view.repeats, "table": view.table[:50], "table_rows": len(view.table),
        "table_columns": ["label", *view.best.x, view.objective_name, "feasible"],
        "notes": [(r.index, n) for r in view.repeats for n in r.notes],
        "figures": _figures(plots.run_figures(view)),
        "config_toml": view.config_as_run or view.config_toml,
        "versions": view.versions, "environment": _environment(),
    }


def verdict_context(judged: Verdict, robust: RobustYield | None = None,
                    expected: Mapping[str, Any] | None = None, next_step: str = ""
                    ) -> VerdictContext:
    """The verdict the page leads with: a robust run's yield against its target, the
    sentence, pass/fail, the expected yield, the table's cells with each row's class
    (``bad``: fails, ``at-limit``: passes at its limit, else '') and the next step
    (``judged``: a run's or a sweep's verdict)."""
    classes = ["bad" if c.passed is False else "at-limit" if c.at_limit else ""
               for c in judged.checks]
    return {"verdict": judged.verdict, "verdict_sentence": judged.headline,
            "verdict_class": {"pass": "ok", "pass at nominal": "limit", "fail": "bad"}.get(
                judged.grade or "", ""),
            "at_limit": judged.at_limit,
            "robust_yield": report.robust_text(robust) if robust else "",
            "robust_met": robust.meets_target if robust else None,
            "expected_yield": report.yield_text(expected) if expected else "",
            "next_step": next_step,
            "verdict_columns": report.VERDICT_COLUMNS,
            "verdict_rows": list(zip(report.verdict_rows(judged.checks), classes))}


def sweep_context(path: Path) -> SweepContext:
    """What the template shows of a sweep archive (read through ``load_sweep`` only)."""
    from camopt.reporting import plots

    spec, results = load_sweep(path)
    ranking = report.rank_sweep(spec, results)
    return {
        **verdict_context(ranking.verdict), "reference": None,
        "kind": "sweep", "title": f"sweep: {path.name}", "path": str(path),
        "source": spec.source, "grid": spec.grid, "seeds": list(spec.seeds),
        "cells": len(results), "ranking": ranking.ranking,
        "figures": _figures(plots.sweep_figures(spec, results)),
        "config_toml": spec.text, "environment": _environment(),
    }


def render(path: Path) -> str:
    """The HTML page of a run, sweep, tolerance or calibration archive."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("camopt.reporting", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True)
    env.filters["num"] = number
    kind = archive.archive_kind(path)
    if kind == "tolerance":
        return env.get_template("tolerance.html.j2").render(**tolerance_context(path))
    if kind == "calibration":
        return env.get_template("calibration.html.j2").render(**calibration_context(path))
    context: SweepContext | RunContext
    if kind == "sweep":
        context = sweep_context(path)
    else:
        context = run_context(archive.load_run(path))
    return env.get_template("report.html.j2").render(**context)


def tolerance_context(path: Path) -> ToleranceContext:
    """What the page shows of a tolerance archive: its summary (``s``, as ``tolerance
    --format json`` printed it) and its figures drawn from the stored samples."""
    from camopt.archive.samples import load_samples
    from camopt.reporting.tolerance_figures import figures

    samples = load_samples(path)
    return {"title": path.name, "s": report.jsonable(samples.summary),
            "created": samples.created, "figures": _figures(figures(samples))}


def calibration_context(path: Path) -> CalibrationContext:
    """What the page shows of a calibration archive: its summary (``s``, as ``calibrate
    --format json`` printed it: per form the RMS misfit, kept, parameters with intervals,
    each curve's analyser quantities measured and fitted, the predictions) and the fits'
    figures drawn from the stored curves."""
    from camopt.archive.calibrations import load_calibration
    from camopt.reporting.calibration_figures import figures, rms_of

    view = load_calibration(path)
    return {"title": path.name, "s": report.jsonable(view.summary), "created": view.created,
            "case_kind": view.case_kind, "config_toml": view.config_toml,
            "figures": _figures(figures(view.curves, rms_of(view.summary)))}
