"""Solver registry: ``@register_solver`` plus the ``camopt.solvers`` entry-point group.

Built-in solvers are found as cases are: every module of ``camopt.solvers`` is imported
and the classes decorated with ``@register_solver`` register themselves (no list to
keep). They are also declared as entry points in pyproject.toml like any plugin (a test
checks the two agree); listing the package makes a source checkout work without
installed metadata.
"""

from __future__ import annotations

import importlib
import pkgutil
from importlib.metadata import entry_points
from typing import TYPE_CHECKING

from camopt.errors import SolverError, did_you_mean

if TYPE_CHECKING:
    from camopt.solvers.base import Solver

ENTRY_POINT_GROUP = "camopt.solvers"
_REGISTRY: dict[str, type[Solver]] = {}
_loaded = False


def register_solver(cls: type[Solver]) -> type[Solver]:
    """Class decorator: register a solver under ``cls.name``; a different duplicate raises."""
    existing = _REGISTRY.get(cls.name)
    if existing is not None and existing.__qualname__ != cls.__qualname__:
        raise SolverError(f"solver name '{cls.name}' is registered twice")
    _REGISTRY[cls.name] = cls
    return cls


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    package = importlib.import_module("camopt.solvers")
    for module in pkgutil.iter_modules(package.__path__, "camopt.solvers."):
        importlib.import_module(module.name)  # solver modules register on import
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in _REGISTRY:
            continue
        try:
            register_solver(ep.load())
        except Exception as exc:  # a broken plugin must not break camopt
            raise SolverError(
                f"solver plugin '{ep.name}' ({ep.value}) failed to load: {exc}"
            ) from exc


def solvers() -> dict[str, type[Solver]]:
    """All registered solvers by name."""
    _load()
    return dict(sorted(_REGISTRY.items()))


def get_solver(name: str) -> type[Solver]:
    """The solver class named ``name``; an unknown name lists the known ones."""
    known = solvers()
    if name not in known:
        raise SolverError(f"unknown solver '{name}'{did_you_mean(name, known)}; known: "
                          f"{', '.join(known)}")
    return known[name]
