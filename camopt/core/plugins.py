"""What the case and solver registries share: finding one entry by name without importing
every other (start-up time).

A registry's entries register themselves when their module is imported, and the
registries used to import every module before the first look-up: ``camopt validate`` of a
VCB case imported the EMB, fast-switch and opening-spring cases and every solver, about
half of its start-up. The entry points of a group (pyproject.toml declares every built-in
case and solver there, and tests check they agree with the packages) map each name to the
module that defines it, so a look-up by name imports that module only; a name without
exactly one entry point (an unknown name, a source checkout without installed metadata,
two other distributions claiming one name) falls back to importing everything, as before,
so what is found and every error are unchanged. Listing a registry imports everything.

Where a name is looked up: first in camopt's own distribution
(:data:`DISTRIBUTION`, its one ``entry_points.txt``), then, for a name camopt does not
declare, in every installed distribution's entry points (reading them opens each
distribution's metadata, 84 in camopt's development environment: a look-up of a built-in
name no longer pays for it). A built-in name is camopt's: when another distribution
declares an entry point under a name camopt declares too (a built-in case kind,
``cmaes``), a look-up by that name imports camopt's module without reading the other
distribution, so a plugin cannot replace a built-in case or solver by claiming its
name. The other entry point is read only when the registry is listed (an unknown name's
error, ``camopt solvers``), as before: the case registry then reports the kind as
registered twice, and the solver registry keeps its built-in solver."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

T = TypeVar("T")

DISTRIBUTION = "camopt"
"""camopt's distribution name (pyproject.toml ``[project] name``), whose own entry points
are read first (:func:`entry_point`)."""


@functools.cache
def _own() -> Any:
    """camopt's own entry points, read once per process from its distribution's metadata
    (one file); none when camopt is not installed (a source checkout)."""
    from importlib.metadata import EntryPoints, PackageNotFoundError, distribution

    try:
        return distribution(DISTRIBUTION).entry_points
    except PackageNotFoundError:
        return EntryPoints(())


@functools.cache
def _installed() -> Any:
    """Every installed entry point, read once per process (each reading opens every
    installed distribution's metadata, and a command looks up a case and a solver)."""
    from importlib.metadata import entry_points

    return entry_points()  # .select() works on what every Python >= 3.10 returns


def entry_points(group: str) -> list[EntryPoint]:
    """The installed entry points of ``group``."""
    return list(_installed().select(group=group))


def entry_point(group: str, name: str) -> EntryPoint | None:
    """The entry point called ``name`` in ``group``: camopt's own when camopt declares the
    name (every other distribution unread: a built-in name is camopt's), else the one
    installed entry point so called; None when there is none, or more than one (only
    importing them all tells which registers what)."""
    own = list(_own().select(group=group, name=name))
    if len(own) == 1:
        return own[0]
    found = list(_installed().select(group=group, name=name))
    return found[0] if len(found) == 1 else None


def look_up(registry: Mapping[str, T], name: str, group: str, loaded: bool,
            load_one: Callable[[EntryPoint], None], load_all: Callable[[], None]) -> T | None:
    """``registry[name]`` (None: unknown), importing first what its one entry point of
    ``group`` names (``load_one``) when it is not registered yet, else everything
    (``load_all``); nothing when the registry is ``loaded`` already."""
    if name not in registry and not loaded:
        ep = entry_point(group, name)
        if ep is not None:
            load_one(ep)
        if name not in registry:
            load_all()
    return registry.get(name)


class OnDemand(Mapping[str, T]):
    """A registry as a read-only mapping for the config loader: looking a name up
    (``in``, ``[]``, ``get``) imports only what defines it (``find``, None when the name is
    unknown); listing the names (iteration, ``len``) imports everything (``every``)."""

    def __init__(self, find: Callable[[str], T | None],
                 every: Callable[[], Mapping[str, T]]) -> None:
        self._find = find
        self._every = every

    def __getitem__(self, name: str) -> T:
        found = self._find(name) if isinstance(name, str) else None
        if found is None:
            raise KeyError(name)
        return found

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and self._find(name) is not None

    def __iter__(self) -> Iterator[str]:
        return iter(self._every())

    def __len__(self) -> int:
        return len(self._every())
