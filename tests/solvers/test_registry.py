"""Solvers are discovered like cases: every module of camopt.solvers, plus entry points."""

from __future__ import annotations

import importlib
import pkgutil
import sys

import camopt.solvers
from camopt.solvers import solvers
from tests.conftest import ROOT

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def built_in() -> dict[str, type]:
    """Every solver class defined in camopt.solvers' own modules, by name."""
    found = {}
    for module in pkgutil.iter_modules(camopt.solvers.__path__, "camopt.solvers."):
        for obj in vars(importlib.import_module(module.name)).values():
            if (isinstance(obj, type) and issubclass(obj, camopt.solvers.Solver)
                    and obj.__module__ == module.name and "name" in vars(obj)):
                found[obj.name] = obj
    return found


def test_every_built_in_solver_is_registered_without_a_list():
    registered = solvers()
    for name, cls in built_in().items():
        assert registered[name] is cls
    assert {"de_gr", "pso", "cmaes", "simplex", "nsga2", "newton_pp", "enumeration",
            "evaluate"} <= set(built_in())


def test_pyproject_declares_every_built_in_solver_as_an_entry_point():
    """The entry points (what another distribution's solvers use) and the package agree."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    group = project["entry-points"]["camopt.solvers"]
    assert set(group) == set(built_in())
    for name, target in group.items():
        module, _, attr = target.partition(":")
        assert getattr(importlib.import_module(module), attr) is built_in()[name]


def test_each_solver_declares_a_valid_test_budget():
    for cls in solvers().values():
        cls.Options.model_validate({"name": cls.name, **cls.test_options})
