"""What the command line imports before a command runs (issue #22): ``--version`` and
``--help`` must not pay for numpy, scipy, h5py, pymoo, matplotlib or dask (their cost is
measured in bench/bench_startup.py; here only which modules are loaded). pydantic is not
on the list: typer itself imports it to convert a command's parameters."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("numpy", "scipy", "scipy.stats", "h5py", "pymoo", "matplotlib", "dask",
         "jinja2", "ezdxf", "camopt.engine.driver", "camopt.cases", "camopt.archive")

ROOT = Path(__file__).resolve().parents[2]
ARCHIVE = str(ROOT / "tests" / "data" / "archives" / "run_main_52e31ad.h5")

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
                          capture_output=True, text=True, check=True, cwd=ROOT)
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


# what a command that evaluates nothing must not load (issue #36): scipy's submodules
# (scipy.stats alone was ~1.4 s of CPU), pymoo, the plotting and report libraries, the
# compiler; and validate reads no archive, so no h5py
NEVER_FOR_CHECKS = ("scipy.stats", "scipy.optimize", "scipy.special", "scipy.linalg",
                    "scipy.integrate", "scipy.interpolate", "scipy.spatial", "pymoo",
                    "matplotlib", "jinja2", "ezdxf", "dask", "numba")


def test_validate_loads_no_solver_library() -> None:
    code, modules = loaded_after("validate", "configs/vcb_velocity.toml")
    assert code in (0, None)
    assert not modules & {*NEVER_FOR_CHECKS, "h5py"}, sorted(modules & {*NEVER_FOR_CHECKS,
                                                                         "h5py"})
    assert {"numpy", "pydantic", "camopt.cases"} <= modules  # the probe sees the case


@pytest.fixture(scope="module")
def current_archive(tmp_path_factory: pytest.TempPathFactory) -> str:
    """An archive this camopt wrote: it stores its expected yield (issue #34), so ``show``
    reads it and evaluates nothing (an older archive's is estimated at show time, which
    evaluates the design and so loads scipy)."""
    path = tmp_path_factory.mktemp("imports") / "fs.h5"
    subprocess.run([sys.executable, "-m", "camopt", "run",
                    str(ROOT / "configs" / "fast_switch.toml"), "--out", str(path), "--quiet"],
                   capture_output=True, text=True, check=True, cwd=ROOT)
    return str(path)


@pytest.mark.parametrize("command", ["show", "runs"])
def test_show_and_runs_load_no_solver_library(command: str, current_archive: str) -> None:
    target = current_archive if command == "show" else str(Path(ARCHIVE).parent)
    code, modules = loaded_after(command, target)
    assert code in (0, None)
    assert not modules & set(NEVER_FOR_CHECKS), sorted(modules & set(NEVER_FOR_CHECKS))
    assert "h5py" in modules  # the probe sees the archive being read
