"""``camopt init`` and ``camopt solvers`` print TOML a user can copy; ``--version``."""

from __future__ import annotations

import pytest
import tomllib
from typer.testing import CliRunner

from camopt import __version__
from camopt.cases import cases
from camopt.cli import app
from camopt.solvers import solvers

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


def test_version():
    r = runner.invoke(app, ["--version"])
    assert r.exit_code == 0 and r.stdout == f"camopt {__version__}\n"


def test_validate_warns_of_an_unreachable_target_and_still_passes(tmp_path):
    r = runner.invoke(app, ["validate", "configs/vcb.toml", "--set", "run.target=-1"])
    assert r.exit_code == 0, r.output
    assert r.stderr.startswith("warning: configs/vcb.toml: run.target: -1 is below 0")
    assert r.stdout.startswith("ok: configs/vcb.toml")
