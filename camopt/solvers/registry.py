"""Solver registry: ``@register_solver`` plus the ``camopt.solvers`` entry-point group.

Built-in solvers are found as cases are: every module of ``camopt.solvers`` is imported
and the classes decorated with ``@register_solver`` register themselves (no list to
keep). They are also declared as entry points in pyproject.toml like any plugin (a test
checks the two agree); listing the package makes a source checkout work without
installed metadata.

A look-up by name (:func:`get_solver`, :func:`solver_options`) imports only the module the
name's entry point names, not every solver; listing (:func:`solvers`) imports them all
(:mod:`camopt.core.plugins`).
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from camopt.core.plugins import OnDemand, entry_points, look_up
from camopt.errors import SolverError, did_you_mean

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

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


def _load_entry_point(ep: EntryPoint) -> None:
    try:
        register_solver(ep.load())
    except Exception as exc:  # a broken plugin must not break camopt
        raise SolverError(
            f"solver plugin '{ep.name}' ({ep.value}) failed to load: {exc}"
        ) from exc


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    import pkgutil  # listing only: a look-up by name imports one module

    package = importlib.import_module("camopt.solvers")
    for module in pkgutil.iter_modules(package.__path__, "camopt.solvers."):
        importlib.import_module(module.name)  # solver modules register on import
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in _REGISTRY:
            continue
        _load_entry_point(ep)


def _find(name: str) -> type[Solver] | None:
    """The solver ``name`` (None: unknown), importing the module its one entry point
    names when it is not registered yet, else every solver (:func:`_load`)."""
    return look_up(_REGISTRY, name, ENTRY_POINT_GROUP, _loaded, _load_entry_point, _load)


def solvers() -> dict[str, type[Solver]]:
    """All registered solvers by name (every solver module imported)."""
    _load()
    return dict(sorted(_REGISTRY.items()))


def get_solver(name: str) -> type[Solver]:
    """The solver class named ``name`` (only its module imported); an unknown name lists
    the known ones."""
    cls = _find(name)
    if cls is None:
        known = solvers()
        raise SolverError(f"unknown solver '{name}'{did_you_mean(name, known)}; known: "
                          f"{', '.join(known)}")
    return cls


def solver_options() -> Mapping[str, Any]:
    """Solver names to their Options models (what the loader validates ``[solver]``
    with); a name looked up imports its solver only, listing them imports every solver."""
    def options(name: str) -> Any:
        cls = _find(name)
        return None if cls is None else cls.Options

    return OnDemand(options, lambda: {name: cls.Options for name, cls in solvers().items()})
