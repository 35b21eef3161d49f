"""``camopt validate``, ``camopt init`` and ``camopt solvers``: what a case file may say."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from camopt.capabilities import capability_name
from camopt.cases import cases, get_case
from camopt.cli.app import app, errors, load_case, out
from camopt.config import template
from camopt.driver import build_solver, prepare
from camopt.errors import CamoptError
from camopt.solvers import solvers


@app.command()
def validate(case: Annotated[Path, typer.Argument(help="case file (TOML)")],
             set_: Annotated[list[str] | None, typer.Option("--set")] = None) -> None:
    """Check a case file without running it."""
    with errors():
        config = load_case(case, set_)
        problem, solver_cls = prepare(config)
        build_solver(problem, solver_cls, config, np.random.default_rng(0))  # its own checks
    out.print(f"ok: {case}: case '{config.case.kind}' ({problem.n_var} variables, "
              f"{problem.n_constr} constraints), solver '{solver_cls.name}'")


@app.command()
def init(kind: Annotated[str, typer.Argument(help="case kind")],
         out_path: Annotated[Path | None, typer.Option("--out", help="write here")] = None,
         force: Annotated[bool, typer.Option(help="overwrite --out")] = False) -> None:
    """Write a commented case-file template for a case kind."""
    with errors():
        spec = get_case(kind)
        text = template(spec.config, solvers()[spec.default_solver].Options())
        if out_path is None:
            sys.stdout.write(text)
            return
        if out_path.exists() and not force:
            raise CamoptError(f"{out_path}: --out: exists; pass --force to overwrite")
        out_path.write_text(text)
    out.print(f"wrote {out_path}")


@app.command(name="solvers")
def list_solvers() -> None:
    """List solvers with their options and the case kinds each runs on."""
    table = Table(title="camopt solvers")
    for col in ("name", "what", "needs", "options", "cases"):
        table.add_column(col)
    for name, cls in solvers().items():
        options = "\n".join(f"{k} = {v.get_default(call_default_factory=True)!r}"
                            for k, v in cls.Options.model_fields.items() if k != "name")
        runs_on = ", ".join(k for k, spec in cases().items() if cls.supports(spec.problem))
        needs = ", ".join(capability_name(c) for c in cls.requires)
        table.add_row(name, cls.summary, needs or "-", options or "-", runs_on or "-")
    out.print(table)
