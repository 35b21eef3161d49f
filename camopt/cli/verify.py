"""``camopt verify``: a VCB run's closing checked against a planar multibody model.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import enum
import importlib
import json
import math
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from camopt.cli.app import Format, app, errors
from camopt.cli.console import fmt, out
from camopt.cli.layout import print_table
from camopt.errors import CamoptError


class Design(str, enum.Enum):
    """``--design``: the run's best design or the case's reference (the vendor's)."""

    best = "best"
    reference = "reference"


class Sets(str, enum.Enum):
    """``--sets``: every parameter set of the run's band or the identified one alone."""

    all = "all"
    identified = "identified"


@app.command()
def verify(
    run_path: Annotated[Path, typer.Argument(metavar="ARCHIVE", help="VCB run archive")],
    design: Annotated[Design, typer.Option(
        "--design", help="the run's best design or the case's reference design")]
    = Design.best,
    format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
    sets: Annotated[Sets, typer.Option(
        "--sets", help="every parameter set of the run's band (each kept model form's, "
        "the links' own masses) or the identified one alone (a simulation each, ~4 s)")]
    = Sets.all,
    restitution: Annotated[float, typer.Option(
        min=0.0, max=0.99, help="the cam-roller pick-up's restitution coefficient in the "
        "multibody model (camopt's is 0, plastic)")] = 0.0,
    coupler_kg: Annotated[float, typer.Option(
        "--coupler-kg", min=0.0, max=50.0, help="the coupler DL's own mass in the multibody model "
        "(kg, a uniform bar; camopt's is none)")] = 0.0,
    contact_restitution: Annotated[float, typer.Option(
        "--contact-restitution", min=0.0, max=0.99, help="the moving contacts' restitution "
        "on the fixed ones in the multibody model (their bounce; camopt's is 0)")] = 0.0,
) -> None:
    r"""Check a VCB run's closing against a planar multibody model (needs the extra:
    pip install 'camopt\[multibody]')."""
    from camopt import archive
    from camopt.engine.tolerance import problem_of
    from camopt.reporting.views import jsonable

    with errors():
        run = archive.load_run(run_path)
        problem = problem_of(run)
        # a case with a multibody model has a ``verify`` module beside its problem
        package = type(problem).__module__.rpartition(".")[0]
        try:
            case = importlib.import_module(f"{package}.verify")
        except ModuleNotFoundError:
            raise CamoptError(f"{run_path}: verify: a '{run.kind}' run has no multibody "
                              "model (the VCB closing has)") from None
        result = case.verify(run, problem, design.value, restitution=restitution,
                             coupler_kg=coupler_kg, every=sets is Sets.all,
                             contact_restitution=contact_restitution)
    doc = {"archive": str(run_path), **jsonable(result.as_dict())}
    if format is Format.json:
        sys.stdout.write(json.dumps(doc, indent=2) + "\n")
        return

    def difference(q: Any) -> str:
        finite = math.isfinite(q.relative_difference)
        return f"{q.relative_difference:+.2%}" if q.camopt and finite else "-"

    rows = []
    for q in result.quantities:
        within = "-" if q.within is None else ("yes" if q.within else "NO")
        limit = "-" if q.limit is None else f"±{q.limit:.0%}"
        rows.append([f"{q.name} ({q.unit})", fmt(q.camopt), fmt(q.multibody),
                     difference(q), limit, within])
    engine = result.engine
    pickup = ("plastic pick-up" if not restitution
              else f"pick-up restitution {restitution:g}")
    if contact_restitution:
        pickup += f", contact restitution {contact_restitution:g}"
    coupler = f", coupler {coupler_kg:g} kg" if coupler_kg else ""
    print_table(f"{run_path.name}: {design.value} design, identified set, camopt against "
                f"{engine['name']} {engine['version']} (step {engine['step_s']:g} s, "
                f"{pickup}{coupler})",
                ["quantity", "camopt", "multibody", "difference", "limit", "within"], rows)
    if len(result.sets) > 1:
        judged = [q.name for q in result.quantities if q.limit is not None]
        print_table(f"every parameter set of the band ({len(result.sets)}): multibody "
                    "against camopt", ["form", "set", *judged, "within"],
                    [[check.form, str(check.index),
                      *(difference(q) for q in check.quantities if q.limit is not None),
                      "yes" if check.agree else "NO"] for check in result.sets])
    out.print("agree: the lumped closing is confirmed within the limits" if result.agree
              else "DISAGREE: a difference is outside its limit", highlight=False)
