"""``camopt`` (``camopt.__main__.run``) starts with the cyclic garbage collector off, and
turns it on again before a command that computes: a run, a sweep or a tolerance analysis
must collect its cycles, a start-up command (``validate``, ``show``...) need not."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
import gc, json, sys
from camopt.__main__ import run
sys.argv = ["camopt", *json.loads(sys.argv[1])]
try:
    run()
except SystemExit as exc:
    code = exc.code
print("\\n" + json.dumps({"code": code, "collecting": gc.isenabled(),
                         "frozen": gc.get_freeze_count()}))
"""


def probe(*args: str) -> dict:
    """Exit code, whether the collector is on and how many objects are frozen out of it
    once ``camopt ARGS`` has run, in a fresh interpreter."""
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(list(args))],
                          capture_output=True, text=True, check=True, cwd=ROOT)
    result: dict = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def collecting_after(*args: str) -> tuple[int | None, bool]:
    """Exit code and whether the collector is on once ``camopt ARGS`` has run."""
    result = probe(*args)
    return result["code"], result["collecting"]


@pytest.mark.parametrize("args, collecting", [
    (("--version",), False),
    (("validate", "configs/fast_switch.toml"), False),
    (("solvers",), False),
    (("run", "--help"), True),  # a command that computes, even asked for its help
    (("tolerance", "--help"), True),
    (("report", "--help"), True),  # figures: matplotlib's objects hold cycles
])
def test_the_collector_is_on_for_commands_that_compute(args: tuple[str, ...],
                                                       collecting: bool) -> None:
    code, on = collecting_after(*args)
    assert code in (0, None)
    assert on is collecting, args


@pytest.mark.parametrize("args, frozen", [
    (("validate", "configs/fast_switch.toml"), True),
    (("--version",), True),
    (("run", "--help"), False),
])
def test_a_start_up_command_exits_without_the_collector_walking_its_objects(
        args: tuple[str, ...], frozen: bool) -> None:
    """A command that ran with the collector off leaves its objects frozen out of it when
    it returns (``camopt.__main__.exit_uncollected``: Python's collections at exit walk
    none of them); a command that computes, with the collector on, does not."""
    result = probe(*args)
    assert result["code"] in (0, None)
    assert (result["frozen"] > 0) is frozen, result


def test_python_m_camopt_runs_the_same_entry_point() -> None:
    """``python -m camopt`` and the console script both start through ``run``."""
    done = subprocess.run([sys.executable, "-m", "camopt", "--version"], capture_output=True,
                          text=True, check=True, cwd=ROOT)
    assert done.stdout.startswith("camopt ")
    script = (ROOT / "pyproject.toml").read_text()
    assert 'camopt = "camopt.__main__:run"' in script
