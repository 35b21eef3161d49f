"""``camopt dashboard``: one self-contained HTML page over a folder of archives, like the
run tables of Optuna's dashboard or MLflow's run comparison but with no server: the data
are in the page (JSON), the style sheet and the script too, so it opens from ``file://``
and can be mailed.

Each archive is a row: name (linked to its report, ``camopt report``'s default
``<archive>.html`` beside it, when that exists), case, solver, verdict (a run's best design
against its case's requirements; a sweep's cells done), expected yield (a robust run's
checked yield, or an ``expected_yield`` the archive stores; else "-"), objective, date
and seed. Columns sort on a click, a text box filters, and two ticked runs show only what
differs between them: the config as run and the results (objective, variables, metrics,
verdict and requirement values), flattened to ``section.key`` lines.

Jinja2, numpy and the reports are imported where used: listing archives starts without them.
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict, dataclass, field
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING, Any

from camopt.errors import CamoptError

if TYPE_CHECKING:  # annotations only: archives are read lazily
    from camopt.archive.listing import ArchiveRow

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


@dataclass(frozen=True)
class DashboardRow:
    """One archive as the page shows it; ``values`` are the flattened config and results
    the comparison reads (``config.case.rb_mm``, ``result.metrics.tau_max_mpa``)."""

    name: str
    archive: str
    case: str
    solver: str
    verdict: str
    expected_yield: float | None
    objective_name: str
    objective: float | None
    created: str
    seed: int | None
    report: str | None
    values: dict[str, str] = field(default_factory=dict)
    grade: str | None = None
    """``pass`` (green), ``pass at nominal`` (amber: below the yield target or at a limit),
    ``fail`` (red); None when not a judged run (:attr:`camopt.reporting.views.Verdict.grade`)."""
    yield_target: float | None = None
    headline: str = ""
    """The verdict in words with the expected yield beside a pass (the cell's tooltip)."""
    design: dict[str, float] = field(default_factory=dict)
    """The best design's variables (display units, finite ones): the parallel
    coordinates' axes."""

    @property
    def verdict_text(self) -> str:
        """The verdict cell: ``PASS at nominal`` or ``FAIL`` for a judged run, else the
        listing's words (a sweep's cells done, why a file cannot be read)."""
        return {"pass": "PASS at nominal", "pass at nominal": "PASS at nominal",
                "fail": "FAIL"}.get(self.grade or "", self.verdict)


def flatten(prefix: str, value: Any, out: dict[str, str]) -> dict[str, str]:
    """``{prefix.key.sub: text}`` of nested dicts; lists and scalars as compact text."""
    if isinstance(value, dict):
        for k, v in value.items():
            flatten(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out[prefix] = _text(value)
    return out


def _text(value: Any) -> str:
    from camopt.reporting.report import format_value

    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_text(v) for v in value) + "]"
    if isinstance(value, float):
        return format_value(value)
    return str(value)


def _finite(x: Any) -> float | None:
    return float(x) if isinstance(x, (int, float)) and math.isfinite(x) else None


def expected_yield(view: Any) -> float | None:
    """The run's expected yield: a robust run's yield on its final check's fresh draws,
    else the ``expected_yield`` the archive stores (its ``value``); None when it has
    neither (:func:`camopt.reporting.report.judged_yield`, what the verdict is graded
    on)."""
    from camopt.reporting.report import judged_yield

    judged = judged_yield(view)
    return _finite(None if judged is None else judged.value)


def run_row(path: Path, listed: ArchiveRow) -> DashboardRow:
    """A run archive's row (``listed``: its :func:`camopt.archive.listing.describe` row)."""
    from camopt import archive
    from camopt.reporting.report import verdict

    view = archive.load_run(path)
    judged = verdict(view)
    values: dict[str, str] = {}
    try:
        config = tomllib.loads(view.config_as_run or view.config_toml)
    except tomllib.TOMLDecodeError:
        config = {"case": view.case, "solver": view.solver, "run": view.run}
    flatten("config", config, values)
    flatten("result", {"objective": view.best.objective, "feasible": view.best.feasible,
                       "verdict": judged.verdict, "x": view.best.x,
                       "metrics": view.best.metrics}, values)
    for c in judged.checks:
        values[f"result.requirement.{c.requirement.name}"] = _text(c.value)
    return DashboardRow(
        name=path.name, archive="run", case=view.kind, solver=view.solver_name,
        verdict=judged.verdict or listed["verdict"], expected_yield=expected_yield(view),
        objective_name=view.objective_name, objective=_finite(view.best.objective),
        created=view.created[:16].replace("T", " "), seed=view.run.get("seed"),
        report=_report(path), values=values, grade=judged.grade,
        yield_target=judged.yield_target, headline=judged.headline,
        design={k: float(v) for k, v in view.best.x.items() if _finite(v) is not None})


def _report(path: Path) -> str | None:
    """The report beside the archive (``camopt report``'s default name), as a link
    relative to the folder, or None."""
    page = path.with_suffix(".html")
    return relative_href(page.name) if page.is_file() else None


def relative_href(name: str) -> str:
    """A file name as an ``href`` that can only mean that file beside the page: ``./``
    then the name percent-encoded (RFC 3986; ``/`` too). A name is user text: without
    the ``./``, ``javascript:alert(1);({}).html`` is a URL of the ``javascript:`` scheme
    (a script runs when the link is clicked), ``//host/x.html`` another host, and ``#``,
    ``?`` or ``%`` change what a browser fetches."""
    from urllib.parse import quote

    return "./" + quote(name, safe="")


def rows(folder: Path) -> list[DashboardRow]:
    """Every archive of ``folder`` (newest first, as ``camopt runs`` lists them); one
    that cannot be read is a row saying why."""
    from camopt.archive.listing import list_archives

    out = []
    for listed in list_archives(folder):
        path = Path(listed["path"])
        if listed["archive"] == "run" and not listed["verdict"].startswith(("file:",
                                                                            "damaged")):
            try:
                out.append(run_row(path, listed))
                continue
            except CamoptError as exc:
                listed["verdict"] = str(exc).split(": ")[-1]
        out.append(DashboardRow(
            name=path.name, archive=listed["archive"], case=listed["case"], solver="-",
            verdict=listed["verdict"], expected_yield=None, objective_name="",
            objective=None, created=str(listed["created"])[:16].replace("T", " "),
            seed=None, report=_report(path)))
    return out


VERDICT_COLOURS = {"pass": "#1b6e1b", "fail": "#b00020"}
"""Marker colours by verdict (the table's); any other verdict grey."""


@dataclass(frozen=True)
class Chart:
    """One inline SVG chart: its heading, the SVG markup (escaped here, drawn as is) and
    a note of what it leaves out."""

    title: str
    svg: str
    note: str = ""
    kind: str = "scatter"
    """``scatter`` or ``parallel`` (the page gives the latter the full width)."""


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About ``n`` round tick values covering lo..hi."""
    import numpy as np

    if not hi > lo:
        return [lo]
    step = 10 ** math.floor(math.log10((hi - lo) / n))
    for m in (1, 2, 2.5, 5, 10):
        if (hi - lo) / (m * step) <= n:
            step *= m
            break
    first = math.ceil(lo / step) * step
    return [float(v) for v in np.arange(first, hi + step * 1e-9, step)]


def _span(values: list[float]) -> tuple[float, float]:
    """The values' range, padded 5 % (a single value: +-1 or +-5 % of it)."""
    lo, hi = min(values), max(values)
    if hi == lo:
        pad = abs(lo) * 0.05 or 1.0
        return lo - pad, hi + pad
    pad = 0.05 * (hi - lo)
    return lo - pad, hi + pad


def _fmt(v: float) -> str:
    from camopt.reporting.report import format_value

    return str(format_value(v))


def scatter(case: str, found: list[DashboardRow]) -> Chart:
    """Objective against expected yield of one case's runs: a point per run with both,
    coloured by verdict, its name beside it and in its tooltip."""
    drawn = [r for r in found if r.objective is not None and r.expected_yield is not None]
    objectives = [float(r.objective) for r in drawn if r.objective is not None]
    lo, hi = _span(objectives) if objectives else (0.0, 1.0)
    labels = [_fmt(t) for t in _ticks(lo, hi)]
    # room for the longest tick label (11 px text: ~6.5 px a character) and the axis name
    width, height, right, top, bottom = 480, 300, 16, 14, 44
    left = 30 + int(6.5 * max(len(t) for t in labels))
    objective_name = next((r.objective_name for r in found if r.objective_name), "objective")
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" '
             f'role="img" class="chart scatter" data-case="{escape(case)}" '
             f'aria-label="{escape(case)}: {escape(objective_name)} against expected yield">']
    x0, x1 = left, width - right
    y0, y1 = height - bottom, top
    parts.append(f'<rect x="{x0}" y="{y1}" width="{x1 - x0}" height="{y0 - y1}" '
                 'fill="none" stroke="#999"/>')

    def px(y: float) -> float:  # yield 0..1 to the x pixel
        return x0 + y * (x1 - x0)

    def py(v: float) -> float:
        return y0 - (v - lo) / (hi - lo) * (y0 - y1)

    for t in (0.0, 0.25, 0.5, 0.75, 1.0):
        parts.append(f'<line x1="{px(t):.1f}" y1="{y0}" x2="{px(t):.1f}" y2="{y0 + 4}" '
                     'stroke="#999"/>'
                     f'<text x="{px(t):.1f}" y="{y0 + 16}" text-anchor="middle" '
                     f'font-size="11">{100 * t:.0f} %</text>')
    for t in _ticks(lo, hi):
        parts.append(f'<line x1="{x0 - 4}" y1="{py(t):.1f}" x2="{x0}" y2="{py(t):.1f}" '
                     'stroke="#999"/>'
                     f'<text x="{x0 - 6}" y="{py(t) + 4:.1f}" text-anchor="end" '
                     f'font-size="11">{escape(_fmt(t))}</text>')
    parts.append(f'<text x="{(x0 + x1) / 2}" y="{height - 6}" text-anchor="middle" '
                 'font-size="12">expected yield</text>')
    parts.append(f'<text x="12" y="{(y0 + y1) / 2}" text-anchor="middle" font-size="12" '
                 f'transform="rotate(-90 12 {(y0 + y1) / 2})">{escape(objective_name)}</text>')
    for r in drawn:
        assert r.objective is not None and r.expected_yield is not None
        cx, cy = px(r.expected_yield), py(r.objective)
        colour = VERDICT_COLOURS.get(r.verdict, "#777")
        tip = (f"{r.name}: {r.verdict}, yield {100 * r.expected_yield:.1f} %, "
               f"{r.objective_name} {_fmt(r.objective)}")
        anchor = "end" if cx > (x0 + x1) / 2 else "start"
        dx = -8 if anchor == "end" else 8
        parts.append(f'<g class="point" data-name="{escape(r.name)}"><circle cx="{cx:.1f}" '
                     f'cy="{cy:.1f}" r="5" fill="{colour}" fill-opacity="0.8">'
                     f'<title>{escape(tip)}</title></circle>'
                     f'<text x="{cx + dx:.1f}" y="{cy - 7:.1f}" text-anchor="{anchor}" '
                     f'font-size="10">{escape(r.name)}</text></g>')
    parts.append("</svg>")
    left_out = len(found) - len(drawn)
    note = (f"{left_out} run{'s' if left_out > 1 else ''} without an objective or an "
            "expected yield not drawn" if left_out else "")
    return Chart(f"{case}: {objective_name} against expected yield", "".join(parts), note)


def parallel(case: str, found: list[DashboardRow]) -> Chart:
    """Parallel coordinates of one case's runs: an axis per design variable, then the
    objective and the expected yield, each scaled to its range over these runs; a line
    per run, coloured by verdict (a value a run lacks breaks its line there)."""
    names = sorted({k for r in found for k in r.design})
    objective_name = next((r.objective_name for r in found if r.objective_name), "objective")
    axes: list[tuple[str, list[float | None]]] = [
        (n, [r.design.get(n) for r in found]) for n in names]
    axes.append((objective_name, [r.objective for r in found]))
    axes.append(("expected yield (0-1)", [r.expected_yield for r in found]))
    gap, left, top, bottom = 78, 48, 30, 70
    width = left * 2 + gap * (len(axes) - 1)
    height = 300
    y0, y1 = height - bottom, top
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             f'viewBox="0 0 {width} {height}" role="img" class="chart parallel" '
             f'data-case="{escape(case)}" aria-label="{escape(case)}: designs in parallel '
             'coordinates">']
    spans = []
    for i, (name, values) in enumerate(axes):
        x = left + gap * i
        known = [v for v in values if v is not None]
        lo, hi = (0.0, 1.0) if i == len(axes) - 1 or not known else _span(known)
        spans.append((lo, hi))
        parts.append(f'<line x1="{x}" y1="{y0}" x2="{x}" y2="{y1}" stroke="#999"/>'
                     f'<text x="{x}" y="{y1 - 8}" text-anchor="middle" font-size="10">'
                     f'{escape(_fmt(hi))}</text>'
                     f'<text x="{x}" y="{y0 + 14}" text-anchor="middle" font-size="10">'
                     f'{escape(_fmt(lo))}</text>'
                     f'<text x="{x}" y="{y0 + 26}" text-anchor="end" font-size="10" '
                     f'transform="rotate(-30 {x} {y0 + 26})">{escape(name)}</text>')
    for k, r in enumerate(found):
        points = []
        for i, ((_, values), (lo, hi)) in enumerate(zip(axes, spans)):
            v = values[k]
            points.append(None if v is None else
                          (left + gap * i, y0 - (v - lo) / (hi - lo) * (y0 - y1)))
        colour = VERDICT_COLOURS.get(r.verdict, "#777")
        runs_of = [[]]  # type: list[list[tuple[float, float]]]
        for p in points:
            if p is None:
                runs_of.append([])
            else:
                runs_of[-1].append(p)
        path = " ".join("M" + " L".join(f"{x:.1f},{y:.1f}" for x, y in seg)
                        for seg in runs_of if len(seg) > 1)
        dots = "".join(f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2.5" fill="{colour}"/>'
                       for seg in runs_of for x, y in seg)
        parts.append(f'<g class="line" data-name="{escape(r.name)}"><title>'
                     f'{escape(r.name)}: {escape(r.verdict)}</title>'
                     + (f'<path d="{path}" fill="none" stroke="{colour}" stroke-width="1.6" '
                        'stroke-opacity="0.75"/>' if path else "") + dots + "</g>")
    parts.append("</svg>")
    return Chart(f"{case}: designs in parallel coordinates", "".join(parts), kind="parallel")


def charts(found: list[DashboardRow]) -> list[Chart]:
    """Per case with readable runs: the objective against the expected yield and the
    designs in parallel coordinates (inline SVG: no script, no network)."""
    by_case: dict[str, list[DashboardRow]] = {}
    for r in found:
        if r.archive == "run" and r.objective_name:  # a run read whole
            by_case.setdefault(r.case, []).append(r)
    out = []
    for case, group in sorted(by_case.items()):
        out += [scatter(case, group), parallel(case, group)]
    return out


def render(folder: Path) -> str:
    """The dashboard page of ``folder``'s archives."""
    import jinja2

    found = rows(folder)
    env = jinja2.Environment(loader=jinja2.PackageLoader("camopt.reporting", "templates"),
                             autoescape=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True)
    from camopt.reporting.report import format_value

    env.filters["num"] = format_value
    return env.get_template("dashboard.html.j2").render(
        folder=str(folder), rows=found,
        data=[{**asdict(r), "verdict_text": r.verdict_text} for r in found],
        charts=charts(found))
