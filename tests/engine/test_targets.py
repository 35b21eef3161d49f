"""``run.target`` warnings (issue #22): a target no design can reach, or one inherited
through ``extends`` from a file whose ``[case]`` differs."""

from __future__ import annotations

from pathlib import Path

import pytest

from camopt.engine.driver import prepare
from camopt.engine.targets import target_warnings
from tests.helpers import load

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
SHIPPED = sorted(CONFIGS.glob("*.toml")) + sorted((CONFIGS / "reference").glob("*.toml"))


def warnings_of(path: Path, *overrides: str) -> list[str]:
    config = load(path, *overrides)
    return target_warnings(config, prepare(config)[0])  # as camopt validate: robust wrapped


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_every_shipped_target_means_something_for_its_config(path):
    assert warnings_of(path) == []


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


def test_a_target_inherited_by_a_file_with_another_case_is_named(tmp_path):
    base = (CONFIGS / "vcb.toml").read_text()
    write(tmp_path, "base.toml", base)
    child = write(tmp_path, "child.toml", 'extends = "base.toml"\n[case]\n'
                  "require_latch = true\nlatch_energy_min_j = 1.0\n")
    found = warnings_of(child)
    assert len(found) == 1
    assert "base.toml, whose [case] differs" in found[0]
    assert "latch_energy_min_j, require_latch" in found[0]
    # set in the file itself, or on the command line: the target is this config's own
    assert warnings_of(child, "run.target=2.0") == []
    write(tmp_path, "own.toml", 'extends = "base.toml"\n[case]\nrequire_latch = true\n'
          "[run]\ntarget = 2.0\n")
    assert warnings_of(tmp_path / "own.toml") == []


def test_a_file_changing_only_the_solver_keeps_its_base_target(tmp_path):
    write(tmp_path, "base.toml", (CONFIGS / "vcb.toml").read_text())
    child = write(tmp_path, "child.toml", 'extends = "base.toml"\n[solver]\n'
                  'name = "de_gr"\npopulation = 20\n')
    assert warnings_of(child) == []


def test_a_target_below_the_objective_floor_is_unreachable():
    found = warnings_of(CONFIGS / "vcb.toml", "run.target=-0.1")
    assert len(found) == 1 and "below 0, the least objective_j" in found[0]


def test_a_robust_target_is_judged_by_the_robust_objective():
    """A robust run keeps its case's floor for a statistic of the case's objective (a mean
    of values >= 0 is >= 0); a margin has none, so a negative margin target is fine."""
    robust = CONFIGS / "vcb_velocity_robust.toml"
    assert warnings_of(robust, "run.target=-0.02") == []
    found = warnings_of(robust, "robust.objective=mean", "robust.centre_generations=0",
                        "run.target=-0.1")
    assert len(found) == 1 and "below 0, the least objective_j" in found[0]
