"""What the case and solver registries share: finding one entry by name without importing
every other (issue #36).

A registry's entries register themselves when their module is imported, and the
registries used to import every module before the first look-up: ``camopt validate`` of a
VCB case imported the EMB, fast-switch and opening-spring cases and every solver, about
half of its start-up. The entry points of a group (pyproject.toml declares every built-in
case and solver there, and tests check they agree with the packages) map each name to the
module that defines it, so a look-up by name imports that module only; a name without
exactly one entry point (an unknown name, a source checkout without installed metadata,
two distributions claiming one name) falls back to importing everything, as before, so
what is found and every error are unchanged. Listing a registry imports everything."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from importlib.metadata import EntryPoint

T = TypeVar("T")


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
    """The one entry point called ``name`` in ``group``; None when there is none, or more
    than one (only importing them all tells which registers what)."""
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
