"""The registries' on-demand look-up (issue #36): a name is found without listing the
others, listing finds everything, and entry points are looked up by group and name."""

from __future__ import annotations

from typing import Any

import pytest

from camopt.core.plugins import OnDemand, entry_point, entry_points


def _registry() -> tuple[OnDemand[int], list[str]]:
    calls: list[str] = []
    every = {"a": 1, "b": 2}

    def find(name: str) -> int | None:
        calls.append(name)
        return every.get(name)

    def listing() -> dict[str, int]:
        calls.append("*")
        return every

    return OnDemand(find, listing), calls


def test_a_look_up_finds_one_name_without_listing() -> None:
    mapping, calls = _registry()
    assert "a" in mapping and mapping["a"] == 1 and mapping.get("b") == 2
    assert "z" not in mapping and mapping.get("z") is None
    with pytest.raises(KeyError):
        mapping["z"]
    assert 3 not in mapping  # type: ignore[comparison-overlap]  (not a name)
    assert "*" not in calls


def test_listing_finds_every_name() -> None:
    mapping, calls = _registry()
    assert sorted(mapping) == ["a", "b"] and len(mapping) == 2
    assert dict(mapping) == {"a": 1, "b": 2}
    assert "*" in calls


def test_entry_points_by_group_and_name() -> None:
    """pyproject.toml declares camopt's own solvers (the installed metadata holds them
    when camopt is installed; a source checkout has none, and then the look-up is None
    and the registries import every module)."""
    solvers = {ep.name: ep for ep in entry_points("camopt.solvers")}
    if not solvers:
        pytest.skip("camopt's entry points are not installed")
    found = entry_point("camopt.solvers", "cmaes")
    assert found is not None and found.value == solvers["cmaes"].value
    assert entry_point("camopt.solvers", "no such solver") is None
    assert entry_point("no such group", "cmaes") is None


def _entry_points(*specs: tuple[str, str, str]) -> Any:
    from importlib.metadata import EntryPoint, EntryPoints

    return EntryPoints(EntryPoint(name, value, group) for group, name, value in specs)


@pytest.fixture
def metadata(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """camopt's own entry points and every installed distribution's, as given here (not
    this machine's): camopt declares the case ``vcb``; a plugin declares ``escapement``
    and claims ``vcb`` too. The list records which of the two was read."""
    import camopt.core.plugins as plugins

    read: list[str] = []
    own = _entry_points(("camopt.cases", "vcb", "camopt.cases.vcb:VCB"))
    every = _entry_points(("camopt.cases", "vcb", "camopt.cases.vcb:VCB"),
                          ("camopt.cases", "vcb", "plugin.impostor:VCB"),
                          ("camopt.cases", "escapement", "plugin.escapement:SPEC"))

    def reading(name: str, found: Any) -> Any:
        return lambda: read.append(name) or found

    monkeypatch.setattr(plugins, "_own", reading("own", own))
    monkeypatch.setattr(plugins, "_installed", reading("installed", every))
    return read


def test_a_built_in_name_is_found_in_camopt_s_own_metadata_alone(metadata: list[str]) -> None:
    """Issue #36: a name camopt declares is looked up in camopt's own distribution, without
    reading every installed distribution; another distribution claiming the name does not
    replace camopt's (nor, as it did before, send the look-up to importing everything)."""
    found = entry_point("camopt.cases", "vcb")
    assert found is not None and found.value == "camopt.cases.vcb:VCB"
    assert metadata == ["own"]


def test_a_name_camopt_does_not_declare_is_looked_up_in_every_distribution(
        metadata: list[str]) -> None:
    found = entry_point("camopt.cases", "escapement")
    assert found is not None and found.value == "plugin.escapement:SPEC"
    assert entry_point("camopt.cases", "no such kind") is None
    assert metadata == ["own", "installed"] * 2
    assert [ep.value for ep in entry_points("camopt.cases")] == [  # listing: every one
        "camopt.cases.vcb:VCB", "plugin.impostor:VCB", "plugin.escapement:SPEC"]


def test_camopt_s_own_entry_points_are_its_distribution_s() -> None:
    """What :func:`camopt.core.plugins._own` reads is camopt's installed metadata: the
    built-in cases and solvers of pyproject.toml (a source checkout has none)."""
    from camopt.core.plugins import _own

    own = _own()
    if not list(own):
        pytest.skip("camopt's entry points are not installed")
    assert {ep.name for ep in own.select(group="camopt.solvers")} >= {"cmaes", "de_gr"}
    assert {ep.name for ep in own.select(group="camopt.cases")} >= {"vcb", "fast_switch"}
