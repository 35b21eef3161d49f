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
"""

from __future__ import annotations

import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from camopt.errors import CamoptError

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
    """The run's expected yield: an ``expected_yield`` the archive stores, else a robust
    run's yield on its final check's fresh draws; None when it has neither."""
    stored = getattr(view, "expected_yield", None)
    if isinstance(stored, (int, float)):
        return float(stored)
    check = (view.robust_check or {}).get("robust") or {}
    return _finite(check.get("yield"))


def run_row(path: Path, listed: dict[str, Any]) -> DashboardRow:
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
        report=_report(path), values=values)


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
        folder=str(folder), rows=found, data=[asdict(r) for r in found])
