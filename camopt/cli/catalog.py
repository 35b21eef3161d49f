"""``camopt validate``, ``camopt init`` and ``camopt solvers``: what a case file may say.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from camopt.cli.app import app, errors, load_case
from camopt.cli.console import escape, out, visible


@app.command()
def validate(case: Annotated[Path, typer.Argument(help="case file (TOML)")],
             set_: Annotated[list[str] | None, typer.Option("--set")] = None) -> None:
    """Check a case file without running it; warn (stderr, exit 0) of a run.target no
    design can reach, or one inherited from a file whose case table differs."""
    from typing import cast

    import numpy as np

    from camopt.engine.setup import FirstUseRng, build_solver, prepare
    from camopt.engine.targets import target_warnings

    with errors():
        config = load_case(case, set_)
        problem, solver_cls = prepare(config)
        # its own checks; a generator only if it draws
        build_solver(problem, solver_cls, config, cast("np.random.Generator", FirstUseRng(0)))
    for warning in target_warnings(config, problem):
        print(f"warning: {visible(warning)}", file=sys.stderr)
    out.print(f"ok: {escape(str(case))}: case '{config.case.kind}' ({problem.n_var} variables, "
              f"{problem.n_constr} constraints), solver '{solver_cls.name}'")


@app.command()
def init(kind: Annotated[str, typer.Argument(help="case kind")],
         out_path: Annotated[Path | None, typer.Option("--out", help="write here")] = None,
         force: Annotated[bool, typer.Option(help="overwrite --out")] = False) -> None:
    """Write a commented case-file template for a case kind."""
    from camopt.cases import get_case
    from camopt.config import template
    from camopt.solvers import get_solver

    with errors():
        spec = get_case(kind)
        text = template(spec.config, get_solver(spec.default_solver).Options.model_validate({}))
        if out_path is None:
            sys.stdout.write(text)
            return
        write_text(out_path, text, force)
    out.print(f"wrote {escape(str(out_path))}")


def write_text(path: Path, text: str, force: bool) -> None:
    """Write a new file (never over another's), or with ``force`` replace a regular file,
    through a temporary file beside it (:func:`camopt.archive.files.write_files`)."""
    from camopt import archive

    archive.write_files({path: text.encode()}, force)


LISTING = Path(__file__).with_name("solvers.json")
"""What ``camopt solvers`` prints for camopt's own solvers and cases, stored so that
listing them imports none of them (every case's model, pydantic, numpy): ``text``, and
the entry points it was rendered with (``entry_points``: group -> name -> module). Written
by :func:`write_listing` (``python -m camopt.cli.catalog``); tests/cli/test_catalog.py
checks it against the registries."""


@app.command(name="solvers")
def list_solvers() -> None:
    """List solvers with their options (TOML lines for a solver table, each with its
    meaning) and the case kinds each runs on."""
    with errors():
        text = solver_listing()
    sys.stdout.write(text)


def solver_listing() -> str:
    """The stored listing (:data:`LISTING`), or, when an installed distribution declares a
    case or solver entry point it was not rendered with (a plugin), the listing rendered
    from the registries (:func:`render_listing`: every case and solver imported)."""
    import json

    from camopt.core.plugins import entry_points

    stored = json.loads(LISTING.read_text(encoding="utf-8"))
    for group, known in stored["entry_points"].items():
        if any(known.get(ep.name) != ep.value for ep in entry_points(group)):
            return render_listing()
    return str(stored["text"])


def render_listing() -> str:
    """Every registered solver as a commented ``[solver]`` table: its summary, the case
    kinds it runs on (their Problem classes declare what it requires), its options."""
    from camopt.cases import cases
    from camopt.core.capabilities import capability_name
    from camopt.solvers import solvers

    blocks = []
    for name, cls in solvers().items():
        options = [line for k, v in cls.Options.model_fields.items() if k != "name"
                   for line in (f"# {v.description}" if v.description else "",
                                toml_line(k, v.get_default(call_default_factory=True))) if line]
        runs_on = ", ".join(k for k, spec in cases().items() if cls.supports(spec.problem))
        needs = ", ".join(capability_name(c) for c in cls.requires)
        # plain lines, never wrapped: each block is a valid [solver] table to copy
        blocks.append("\n".join([
            f"# {name}: {cls.summary}",
            f"# cases: {runs_on or '-'}" + (f"; needs: {needs}" if needs else ""),
            "[solver]", f'name = "{name}"', *options]) + "\n\n")
    return "".join(blocks)


def write_listing() -> None:
    """Render the listing and store it with the installed entry points (:data:`LISTING`)."""
    import json

    from camopt.core.plugins import entry_points

    groups = {group: {ep.name: ep.value for ep in entry_points(group)}
              for group in ("camopt.cases", "camopt.solvers")}
    LISTING.write_text(json.dumps({"entry_points": groups, "text": render_listing()},
                                  indent=1) + "\n", encoding="utf-8")


def toml_line(key: str, value: object) -> str:
    """``key = value`` as TOML (``true``, quoted strings, arrays); an unset (None) default as
    a TOML comment, since TOML has no null: copied into a case file it stays valid."""
    import tomli_w

    if value is None:
        return f"# {key} unset"
    if hasattr(value, "model_dump"):
        value = value.model_dump(mode="json", exclude_none=True)
    return tomli_w.dumps({key: value}).strip()


if __name__ == "__main__":
    write_listing()
