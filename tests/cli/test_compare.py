"""``camopt compare``: config differences name the seed; different kinds are refused."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()
PP3 = str(CONFIGS / "opening_spring_pp3.toml")


def run(tmp_path, name, case, *args):
    out = tmp_path / name
    r = runner.invoke(app, ["run", case, "--out", str(out), "--quiet", *args])
    assert r.exit_code == 0, r.output
    return str(out)


def test_seed_from_the_command_line_is_a_config_difference(tmp_path):
    a = run(tmp_path, "s7.h5", PP3, "--seed", "7")
    b = run(tmp_path, "s8.h5", PP3, "--seed", "8")
    r = runner.invoke(app, ["compare", a, b, "--format", "json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["config_differences"] == {"run.seed": [7, 8]}
    r = runner.invoke(app, ["compare", a, b], env={"COLUMNS": "80"})
    assert "run.seed" in r.stdout


def test_runs_of_different_kinds_are_refused(tmp_path):
    a = run(tmp_path, "os.h5", PP3)
    b = run(tmp_path, "fs.h5", str(CONFIGS / "fast_switch.toml"))
    r = runner.invoke(app, ["compare", a, b])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {b}: case_kind: 'fast_switch', but {a} has "
                        "'opening_spring': runs of different kinds are not comparable\n")
