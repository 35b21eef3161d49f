"""``camopt init`` and ``camopt solvers`` print TOML a user can copy; ``--version``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import tomllib
from typer.testing import CliRunner

from camopt import __version__
from camopt.cases import cases
from camopt.cli import app
from camopt.solvers import solvers
from tests.helpers import load

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

runner = CliRunner()


@pytest.mark.parametrize("kind", sorted(cases()))
def test_init_prints_valid_toml(kind):
    r = runner.invoke(app, ["init", kind])
    assert r.exit_code == 0, r.output
    assert tomllib.loads(r.stdout)["case"]["kind"] == kind


def test_solvers_prints_one_valid_solver_table_per_solver():
    r = runner.invoke(app, ["solvers"], env={"COLUMNS": "80"})
    assert r.exit_code == 0, r.output
    blocks = [b for b in r.stdout.split("\n\n") if b.strip()]
    names = [tomllib.loads(b)["solver"]["name"] for b in blocks]
    assert names == list(solvers())
    de = tomllib.loads(blocks[names.index("de_gr")])["solver"]
    assert de["population"] == 100 and "polish" not in de  # unset: a comment, not None


def test_stored_solver_listing_is_the_registries_listing():
    """``camopt solvers`` prints camopt/cli/solvers.json (it imports no case nor solver);
    it must be what the registries render now. After changing a solver's options or a
    case's capabilities: ``python -m camopt.cli.catalog`` writes it again."""
    import subprocess
    import sys

    from camopt.cli.catalog import LISTING

    stored = json.loads(LISTING.read_text(encoding="utf-8"))
    # a fresh interpreter: this one has the tests' own cases and solvers registered
    fresh = subprocess.run(
        [sys.executable, "-c", "import json; from camopt.cli.catalog import render_listing; "
         "from camopt.cases import cases; from camopt.solvers import solvers; "
         "print(json.dumps([render_listing(), sorted(solvers()), sorted(cases())]))"],
        capture_output=True, text=True, check=True, cwd=CONFIGS.parent)
    text, solver_names, kinds = json.loads(fresh.stdout)
    assert stored["text"] == text, "stale: run python -m camopt.cli.catalog"
    assert sorted(stored["entry_points"]["camopt.solvers"]) == solver_names
    assert sorted(stored["entry_points"]["camopt.cases"]) == kinds
    r = runner.invoke(app, ["solvers"])
    assert r.exit_code == 0 and r.stdout == stored["text"]


def test_a_plugin_solver_is_listed_from_the_registries(monkeypatch):
    """An entry point the stored listing was not rendered with (a plugin): the listing is
    rendered from the registries, which import it."""
    from importlib.metadata import EntryPoint

    from camopt.cli import catalog
    from camopt.core import plugins

    real = plugins.entry_points
    extra = EntryPoint("sphere_walk", "camopt.solvers.cmaes:CMAES", "camopt.solvers")

    def with_plugin(group):
        return [*real(group), *([extra] if group == "camopt.solvers" else [])]
    monkeypatch.setattr(plugins, "entry_points", with_plugin)
    monkeypatch.setattr(catalog, "render_listing", lambda: "rendered\n")
    assert catalog.solver_listing() == "rendered\n"


def test_version():
    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.stdout == f"camopt {__version__}\n"


def test_validate_warns_of_an_unreachable_target_and_still_passes(tmp_path):
    r = runner.invoke(app, ["validate", "configs/vcb.toml", "--set", "run.target=-1"])
    assert r.exit_code == 0, r.output
    assert r.stderr.startswith("warning: configs/vcb.toml: run.target: -1 is below 0")
    assert r.stdout.startswith("ok: configs/vcb.toml")


# the shipped case file each template reproduces (issue #22: `init` is the reference case)
REFERENCE = {"vcb": "vcb.toml", "vcb_identify": "vcb_identify.toml",
             "vcb_identify_dynamics": "vcb_identify_dynamics.toml", "emb_cam": "emb.toml",
             "fast_switch": "fast_switch_de.toml", "opening_spring": "opening_spring_pp3.toml"}


BUILT_IN = sorted(k for k, spec in cases().items() if spec.config.__module__.startswith("camopt."))


@pytest.mark.parametrize("kind", BUILT_IN)
def test_init_prints_the_shipped_reference_case(kind, tmp_path):
    assert kind in REFERENCE, f"name the shipped case file that `init {kind}` reproduces"
    r = runner.invoke(app, ["init", kind])
    assert r.exit_code == 0, r.output
    (tmp_path / "init.toml").write_text(r.stdout)
    shipped = load(CONFIGS / REFERENCE[kind]).case.model_dump(mode="json")
    assert load(tmp_path / "init.toml").case.model_dump(mode="json") == shipped


@pytest.mark.parametrize("command", [[], ["run"], ["show"]])
def test_dash_h_is_help(command):
    short, long = (runner.invoke(app, [*command, flag], env={"COLUMNS": "80"})
                   for flag in ("-h", "--help"))
    assert short.exit_code == long.exit_code == 0
    assert short.stdout == long.stdout and "Usage: " in short.stdout


def test_help_lists_commands_in_workflow_order_as_paragraphs():
    """Issue #34: init -> validate -> run -> show -> tolerance -> report -> export ...;
    each command's text wraps at the terminal's width, never at the docstring's lines
    (at 200 columns every command's help is one line)."""
    from camopt.cli.app import WORKFLOW

    r = runner.invoke(app, ["--help"], env={"COLUMNS": "200"})
    rows = [line.split() for line in r.stdout.split("Commands:")[1].splitlines()]
    listed = [row[0] for row in rows if row and row[0] in WORKFLOW]
    assert listed == list(WORKFLOW)
    import click
    import typer

    group = typer.main.get_command(app)
    ctx = click.Context(group)
    for name in WORKFLOW:
        text = group.get_command(ctx, name).help  # type: ignore[union-attr]
        assert text and "\n" not in text.replace("\n\n", ""), name
    assert "run.target no design can reach" in r.stdout  # was broken after "no"


def test_shell_completion_is_offered():
    r = runner.invoke(app, ["--help"], env={"COLUMNS": "80"})
    assert "--install-completion" in r.stdout and "--show-completion" in r.stdout


def test_runs_lists_each_archive_with_case_verdict_and_date(tmp_path):
    """Runs and sweeps newest first; a file that is not an archive is a row, not an error."""
    first = runner.invoke(app, ["run", str(CONFIGS / "fast_switch.toml"), "--quiet",
                                "--out", str(tmp_path / "a.h5")])
    assert first.exit_code == 0, first.output
    (tmp_path / "junk.h5").write_text("not hdf5")
    r = runner.invoke(app, ["runs", str(tmp_path), "--format", "json"])
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)
    assert [Path(row["path"]).name for row in rows] == ["a.h5", "junk.h5"]
    assert rows[0]["case"] == "fast_switch" and rows[0]["feasible"] is True
    assert rows[0]["verdict"] == invoke_verdict(tmp_path / "a.h5")
    assert rows[0]["created"].startswith("20") and rows[1]["verdict"].startswith("file: not")
    table = runner.invoke(app, ["runs", str(tmp_path)], env={"COLUMNS": "100"})
    assert table.exit_code == 0 and "fast_switch" in table.stdout
    # at 80 columns a long default name is never split: each archive heads its values
    long = tmp_path / "fast_switch_pareto-20261125T140812123456Z.h5"
    shutil.copy(tmp_path / "a.h5", long)
    narrow = runner.invoke(app, ["runs", str(tmp_path)], env={"COLUMNS": "80"})
    assert narrow.exit_code == 0
    lines = narrow.stdout.splitlines()
    assert max(len(line) for line in lines) <= 80
    assert long.name in lines and "a.h5" in lines
    assert any(line.startswith("  case: fast_switch; verdict: ") for line in lines)
    missing = runner.invoke(app, ["runs", str(tmp_path / "none")])
    assert missing.exit_code == 2 and missing.stderr.startswith("error: ")


def invoke_verdict(path: Path) -> str:
    """show's verdict of a run, what `camopt runs` lists."""
    return json.loads(runner.invoke(app, ["show", str(path), "--format", "json"]).stdout)[
        "verdict"]


def test_a_file_name_is_printed_as_it_is(tmp_path):
    """A path holding an emoji code or markup is printed as named, not as an emoji or a
    style (rich's emoji codes are off, markup is escaped)."""
    name = ":smile: [bold]x.toml"
    shutil.copy(CONFIGS / "fast_switch.toml", tmp_path / name)
    r = runner.invoke(app, ["validate", str(tmp_path / name)])
    assert r.exit_code == 0, r.output
    # wherever the console wraps the long temporary path (a worker's is longer)
    assert f"{name}:case'fast_switch'".replace(" ", "") in "".join(r.stdout.split()), r.stdout
