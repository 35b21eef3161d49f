"""What the command line imports before a command runs (issue #22): ``--version`` and
``--help`` must not pay for numpy, scipy, h5py, pymoo, matplotlib or dask (their cost is
measured in bench/bench_startup.py; here only which modules are loaded). pydantic is not
on the list: typer itself imports it to convert a command's parameters."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("numpy", "scipy", "scipy.stats", "h5py", "pymoo", "matplotlib", "dask",
         "jinja2", "ezdxf", "camopt.engine.driver", "camopt.cases", "camopt.archive")

PROBE = """
import json, sys
from camopt.cli import main
sys.argv = ["camopt", *json.loads(sys.argv[1])]
try:
    main()
except SystemExit as exc:
    code = exc.code
print("\\n" + json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def loaded_after(*args: str) -> tuple[int, set[str]]:
    """Exit code and the modules loaded once ``camopt ARGS`` has run, in a fresh
    interpreter (this test process has imported everything already)."""
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(list(args))],
                          capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result["code"], set(result["modules"])


@pytest.mark.parametrize("args", [("--version",), ("--help",), ("run", "--help")])
def test_startup_imports_no_heavy_library(args: tuple[str, ...]) -> None:
    code, modules = loaded_after(*args)
    assert code in (0, None)
    assert not modules & set(HEAVY), sorted(modules & set(HEAVY))


def test_probe_sees_a_command_that_imports_them() -> None:
    """The check can fail: a command that builds a case loads pydantic and numpy."""
    code, modules = loaded_after("init", "vcb")
    assert code in (0, None)
    assert {"pydantic", "numpy", "camopt.cases"} <= modules
