"""What the command line imports before a command runs (issue #22): ``--version`` and
``--help`` must not pay for numpy, scipy, h5py, pymoo, matplotlib or dask (their cost is
measured in bench/bench_startup.py; here only which modules are loaded). pydantic is not
on that list: typer itself imports it to convert a command's parameters (``run --help``
loads it); the bare ``--version`` and ``--help`` load neither it nor camopt's config.

A command that reads one case file or archive imports that case's package and that
solver's module only (issue #36: the registries look a name up through its entry point),
and BLAS is told to start on one thread before numpy loads."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("numpy", "scipy", "scipy.stats", "h5py", "pymoo", "matplotlib", "dask",
         "jinja2", "ezdxf", "numba", "camopt.engine.driver", "camopt.cases", "camopt.archive")

ROOT = Path(__file__).resolve().parents[2]
ARCHIVE = str(ROOT / "tests" / "data" / "archives" / "run_main_52e31ad.h5")

PROBE = """
import json, os, sys
from camopt.cli import main
sys.argv = ["camopt", *json.loads(sys.argv[1])]
try:
    main()
except SystemExit as exc:
    code = exc.code
print("\\n" + json.dumps({"code": code, "modules": sorted(sys.modules),
                         "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS")}))
"""


def probe(*args: str) -> dict:
    """What :data:`PROBE` reports once ``camopt ARGS`` has run, in a fresh interpreter
    (this test process has imported everything already) without OPENBLAS_NUM_THREADS."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(list(args))],
                          capture_output=True, text=True, check=True, cwd=ROOT, env=env)
    result: dict = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def loaded_after(*args: str) -> tuple[int, set[str]]:
    """Exit code and the modules loaded once ``camopt ARGS`` has run, in a fresh
    interpreter."""
    result = probe(*args)
    return result["code"], set(result["modules"])


@pytest.mark.parametrize("args", [("--version",), ("--help",), ("run", "--help"),
                                  ("solvers",)])
def test_startup_imports_no_heavy_library(args: tuple[str, ...]) -> None:
    code, modules = loaded_after(*args)
    assert code in (0, None)
    assert not modules & set(HEAVY), sorted(modules & set(HEAVY))


@pytest.mark.parametrize("args", [("--version",), ("--help",), ("solvers",)])
def test_version_and_help_load_no_pydantic_nor_config(args: tuple[str, ...]) -> None:
    code, modules = loaded_after(*args)
    assert code in (0, None)
    assert not modules & {"pydantic", "camopt.config"}, sorted(modules)


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


CASES = {"emb_cam", "fast_switch", "opening_spring", "vcb"}
"""camopt's case packages ..."""
SOLVERS = {"cmaes", "de_gr", "enumeration", "evaluate", "newton_pp", "nsga2", "pso",
           "simplex"}
"""... and solver modules."""


def _loaded(modules: set[str], wing: str) -> set[str]:
    """The sub-packages and modules of ``camopt.<wing>`` that are loaded."""
    prefix = f"camopt.{wing}."
    return {m[len(prefix):].split(".")[0] for m in modules if m.startswith(prefix)}


def test_validate_imports_its_case_and_solver_only() -> None:
    """configs/vcb_velocity.toml: the VCB package and CMA-ES, not the other cases'
    models nor the other solvers (issue #36: they were about a third of validate's
    start-up); BLAS was told one thread before numpy loaded (``camopt.cli.main``)."""
    result = probe("validate", "configs/vcb_velocity.toml")
    modules = set(result["modules"])
    assert result["code"] in (0, None)
    assert _loaded(modules, "cases") & CASES == {"vcb"}
    assert _loaded(modules, "solvers") & SOLVERS == {"cmaes"}
    assert result["blas_threads"] == "1"


def test_an_unknown_kind_imports_every_case_to_list_them() -> None:
    code, modules = loaded_after("init", "escapement")
    assert code == 2
    assert _loaded(modules, "cases") >= CASES


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
    assert "camopt.engine.driver" not in modules  # the registries validate, not the engine
    # nor build the case's Problem to check the archive's variable names (issue #48)
    models = {m for m in modules if m.startswith("camopt.cases.")
              and m.rsplit(".", 1)[-1] in ("problem", "model", "dynamics", "kernel")}
    assert not models and not modules & {"scipy", "numba"}, sorted(models)
    if command == "show":  # the archive's case only
        assert _loaded(modules, "cases") & CASES == {"fast_switch"}


def test_show_of_a_finished_archive_builds_no_config_model(current_archive: str) -> None:
    """``show`` checks the archive's variable names on its stored ``[case]`` as written
    (``CaseSpec.stored_names``): the case's config model, the config loader and models,
    the solver's options, the TOML reader, the views of compared runs and the Problem's
    classes are not imported (issue #48: start-up)."""
    code, modules = loaded_after("show", current_archive)
    assert code in (0, None)
    assert "camopt.cases.fast_switch" in modules  # the probe sees the case being read
    assert not modules & {"camopt.cases.fast_switch.config", "camopt.config.models",
                          "camopt.config.loader", "camopt.solvers", "tomllib",
                          "camopt.reporting.comparisons", "camopt.core.problem"}, sorted(
        m for m in modules if m.startswith(("camopt.config", "camopt.solvers", "camopt.cases")))


@pytest.fixture(scope="module")
def vcb_archive(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A small VCB run this camopt wrote (200 evaluations, one repeat: ~2 s): the case
    whose evaluation compiles with numba."""
    path = tmp_path_factory.mktemp("imports_vcb") / "vcb.h5"
    subprocess.run([sys.executable, "-m", "camopt", "run",
                    str(ROOT / "configs" / "vcb_velocity.toml"), "--out", str(path),
                    "--set", "solver.evaluations=200", "--set", "run.repeats=1", "--quiet"],
                   capture_output=True, text=True, check=True, cwd=ROOT)
    return str(path)


@pytest.mark.parametrize("command", ["show", "runs"])
def test_show_and_runs_of_a_vcb_archive_load_no_model_numba_nor_scipy(command: str,
                                                                      vcb_archive: str
                                                                      ) -> None:
    """The VCB archive's stored config is validated (its config module is loaded), its
    closing model, dynamics and compiled kernel are not, nor numba or scipy."""
    target = vcb_archive if command == "show" else str(Path(vcb_archive).parent)
    code, modules = loaded_after(command, target)
    assert code in (0, None)
    assert "camopt.cases.vcb.config" in modules  # the probe sees the case being read
    vcb = {m for m in modules if m.startswith("camopt.cases.vcb.")}
    # the case's config models (identify_config: the identifications' [case], registered
    # with the package), its paper values and requirements: data, no model
    assert vcb <= {"camopt.cases.vcb.config", "camopt.cases.vcb.identify_config",
                   "camopt.cases.vcb.paper", "camopt.cases.vcb.requirements"}, sorted(vcb)
    assert not {m.split(".")[0] for m in modules} & {"scipy", "numba", "llvmlite"}


def test_validate_imports_its_command_module_only_and_not_the_engine_s_loop() -> None:
    """``camopt validate`` imports ``camopt.cli.catalog`` (init, validate, solvers), not the
    other command modules; ``camopt.engine.setup``, not the driver's loop; not the VCB
    identification kinds nor their configs (``config_at``); and not threadpoolctl (BLAS
    was told one thread before numpy loaded); nor the reference cam's points and curve
    readers, which its case file does not name, nor pkgutil, which only listing a
    registry needs (issue #36); nor numpy.random, as CMA-ES draws nothing when it is
    built (``engine.setup.FirstUseRng``, issue #48)."""
    code, modules = loaded_after("validate", "configs/vcb_velocity.toml")
    assert code in (0, None)
    commands = _loaded(modules, "cli") - {"app", "console"}
    assert commands == {"catalog"}, commands
    assert "camopt.engine.setup" in modules
    assert not modules & {"camopt.engine.driver", "camopt.engine.robust",
                          "camopt.cases.vcb.identify", "camopt.cases.vcb.identify_config",
                          "threadpoolctl", "click",
                          "camopt.cases.vcb.cam_points", "camopt.cases.vcb.curves", "pkgutil",
                          "numpy.random"}


def test_every_command_is_where_commands_says() -> None:
    """:data:`camopt.cli.app.COMMANDS` names each command's module (what ``camopt CMD``
    imports): the application's commands are exactly its keys, each defined there."""
    from camopt.cli import app
    from camopt.cli.app import COMMANDS

    found = {info.name or info.callback.__name__: info.callback.__module__
             for info in app.registered_commands}
    assert found == {name: f"camopt.cli.{module}" for name, module in COMMANDS.items()}


def test_init_imports_its_case_s_config_not_its_model() -> None:
    """``camopt init vcb`` prints the config's template: the VCB package is imported, its
    problem, dynamics and identifications are not (the spec names its problem as
    ``"module:Class"``, imported when a problem is built: issue #36)."""
    code, modules = loaded_after("init", "vcb")
    assert code in (0, None)
    assert "camopt.cases.vcb.config" in modules
    assert not modules & {"camopt.cases.vcb.problem", "camopt.cases.vcb.dynamics",
                          "camopt.cases.vcb.identify"}


PLUGINS_PROBE = """
import json, sys
from camopt.cli import main
sys.argv = ["camopt", "validate", "configs/vcb_velocity.toml"]
try:
    main()
except SystemExit as exc:
    code = exc.code
from pydantic.plugin import _loader
print("\\n" + json.dumps({"code": code, "looked_up": _loader._plugins is not None}))
"""


@pytest.mark.parametrize("user", [None, "", "__all__"])
def test_validate_does_not_look_for_pydantic_plugins_unless_asked(user: str | None) -> None:
    """pydantic reads every installed distribution's entry points to find its plugins on
    the first model it validates (~0.017 s of ``validate``'s start-up): the command line
    turns that off (``perf.no_pydantic_plugins``), unless the user set
    PYDANTIC_DISABLE_PLUGINS (empty: every plugin, as pydantic's default)."""
    env = {k: v for k, v in os.environ.items() if k != "PYDANTIC_DISABLE_PLUGINS"}
    if user is not None:
        env["PYDANTIC_DISABLE_PLUGINS"] = user
    done = subprocess.run([sys.executable, "-c", PLUGINS_PROBE], capture_output=True,
                          text=True, check=True, cwd=ROOT, env=env)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["code"] in (0, None)
    assert result["looked_up"] is (user == "")
