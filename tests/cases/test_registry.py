"""The case registry: specs, entry points, and that nothing outside a case names it."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from camopt.cases import CaseSpec, cases, get_case, register_case
from camopt.cli import app
from camopt.errors import ConfigError
from camopt.solvers import solvers
from tests.conftest import ROOT, SPHERE, SphereConfig, SphereProblem

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

PACKAGE = ROOT / "camopt"
BUILT_IN = {k: s for k, s in cases().items() if s.problem.__module__.startswith("camopt.")}


def _own_folder(spec: CaseSpec) -> Path:
    return PACKAGE / Path(*spec.problem.__module__.split(".")[1:-1])


def test_every_built_in_case_is_a_package_with_its_own_config():
    assert set(BUILT_IN) >= {"fast_switch", "vcb", "vcb_identify", "opening_spring", "emb_cam"}
    for kind, spec in BUILT_IN.items():
        folder = _own_folder(spec)
        assert (folder / "__init__.py").is_file(), kind
        assert spec.config.__module__.startswith(spec.problem.__module__.rsplit(".", 1)[0])
        assert spec.default_solver in solvers(), kind


def test_no_file_outside_a_case_names_its_kind():
    """Outside its own package no module under camopt/ names a case kind (as a word in
    code, strings or comments): adding a mechanism touches one place."""
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, BUILT_IN)) + r")\b")
    own = {_own_folder(spec) for spec in BUILT_IN.values()}
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        if any(folder in path.parents for folder in own):
            continue
        for n, line in enumerate(path.read_text().splitlines(), 1):
            if pattern.search(line):
                offenders.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not offenders, "\n".join(offenders)


def test_pyproject_declares_every_built_in_case_as_an_entry_point():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    group = project["entry-points"]["camopt.cases"]
    assert set(group) == set(BUILT_IN)
    for kind, target in group.items():
        module, _, name = target.partition(":")
        obj = getattr(__import__(module, fromlist=[name]), name)
        assert obj is BUILT_IN[kind]


def test_a_kind_registered_twice_raises_and_unknown_kinds_list_the_known():
    impostor = CaseSpec(kind="sphere", config=SphereConfig, problem=SphereProblem,
                        default_solver="de_gr")
    with pytest.raises(ConfigError, match="registered twice"):
        register_case(impostor)
    assert register_case(SPHERE) is SPHERE  # the same spec again is no error
    with pytest.raises(ConfigError, match="known: emb_cam"):
        get_case("escapement")


def test_a_config_named_by_reference_is_imported_and_checked_when_first_read():
    """``config_at("module:Class")``: registered without importing it, imported on the
    first read of ``spec.config``, and checked then as a class given at registration is
    (its kind's default must be the spec's kind)."""
    from camopt.cases.registry import config_at

    spec = CaseSpec(kind="sphere_lazy", config=config_at("tests.conftest:SphereConfig"),
                    problem=SphereProblem, default_solver="de_gr")
    assert isinstance(spec.__dict__["_config"], str)  # nothing imported yet
    with pytest.raises(ConfigError, match="case 'sphere_lazy': its config model's kind"):
        _ = spec.config
    named = CaseSpec(kind="sphere", config=config_at("tests.conftest:SphereConfig"),
                     problem=SphereProblem, default_solver="de_gr")
    assert named.config is SphereConfig


def test_a_test_only_case_runs_through_the_cli(tmp_path):
    """The sphere case (registered in conftest with register_case, no monkeypatching)
    validates, gets a template, and runs through `camopt run` like a built-in case."""
    runner = CliRunner()
    case = tmp_path / "sphere.toml"
    r = runner.invoke(app, ["init", "sphere", "--out", str(case)])
    assert r.exit_code == 0, r.output
    assert runner.invoke(app, ["validate", str(case)]).exit_code == 0
    out = tmp_path / "s.h5"
    r = runner.invoke(app, ["run", str(case), "--out", str(out), "--quiet",
                            "--set", "solver.generations=20", "--set", "solver.population=10"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["show", str(out), "--format", "json"])
    assert r.exit_code == 0 and '"kind": "sphere"' in r.stdout


LOOK_UP = """
import json, sys
from importlib.metadata import EntryPoints
import camopt.core.plugins as plugins
if sys.argv[1] == "no metadata":  # a source checkout: no entry point is installed
    plugins._own = plugins._installed = lambda: EntryPoints(())
from camopt.cases import get_case
from camopt.solvers import get_solver
spec, solver = get_case("vcb"), get_solver("cmaes")
print(json.dumps({"spec": spec.problem.__module__, "solver": solver.__module__,
                  "modules": sorted(m for m in sys.modules if m.startswith("camopt."))}))
"""


@pytest.mark.parametrize("metadata", ["installed", "no metadata"])
def test_a_look_up_imports_its_entry_point_s_package_else_every_case(metadata: str) -> None:
    """Issue #36: with camopt's entry points installed, looking a kind (a solver) up
    imports that package (module) only; without them, every case and solver, as before.
    Either way the same spec and solver are found."""
    if metadata == "installed":
        from camopt.core.plugins import entry_point

        if entry_point("camopt.cases", "vcb") is None:
            pytest.skip("camopt's entry points are not installed")
    done = subprocess.run([sys.executable, "-c", LOOK_UP, metadata], capture_output=True,
                          text=True, check=True, cwd=ROOT)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["spec"] == "camopt.cases.vcb.problem"
    assert result["solver"] == "camopt.solvers.cmaes"
    others = {"camopt.cases.emb_cam", "camopt.cases.fast_switch", "camopt.solvers.de_gr",
              "camopt.solvers.pso"}
    loaded = others & set(result["modules"])
    assert loaded == (set() if metadata == "installed" else others), sorted(loaded)


SHIPPED = sorted(p.name for p in (Path(__file__).resolve().parents[2] / "configs").glob("*.toml"))


@pytest.mark.parametrize("name", SHIPPED)
def test_variable_names_without_the_model_are_the_problem_s(name: str) -> None:
    """``CaseSpec.variable_names`` (what ``show`` checks an archive's names with, building
    no model) gives the names the Problem has, for every shipped config, and for the
    VCB's optional variables switched on and off."""
    from camopt import archive
    from camopt.cases import build_problem, get_case
    from camopt.engine.setup import load

    configs = Path(__file__).resolve().parents[2] / "configs"
    config = archive.resolve_references(load(configs / name, []))
    spec = get_case(config.case.kind)
    assert spec.variable_names is not None, spec.kind
    assert spec.names_of(config.case) == tuple(build_problem(config.case).names)
    # as a run archive stores the [case] table (JSON of the validated config): the
    # names show accepts without validating it again are the same
    assert spec.stored_names(_as_stored(config.case)) == spec.names_of(config.case)
    if config.case.kind == "vcb" and config.case.step == "cam":
        bare = config.case.model_copy(update={"release_offset_bounds_deg": None,
                                              "velocity_setting_bounds_m_s": None})
        assert spec.names_of(bare) == tuple(build_problem(bare).names)
        assert len(spec.names_of(bare)) < len(spec.names_of(config.case)) or \
            config.case.release_offset_bounds_deg is None
        assert spec.stored_names(_as_stored(bare)) == spec.names_of(bare)


def _as_stored(case: Any) -> dict[str, Any]:
    """A validated ``[case]`` as a run archive stores it and reads it back (JSON)."""
    stored: dict[str, Any] = json.loads(json.dumps(case.model_dump(mode="json")))
    return stored


def test_stored_names_leave_a_table_that_cannot_answer_to_the_validated_config() -> None:
    """A stored ``[case]`` without a field its names depend on (an archive of another
    version), or with a value of another kind, gives None (the full check on the config
    validated decides), never a guess; a case without ``variable_names`` gives None."""
    vcb = get_case("vcb")
    stored = _as_stored(vcb.config())
    assert vcb.stored_names(stored) == vcb.names_of(vcb.config())
    assert vcb.stored_names({k: v for k, v in stored.items() if k != "step"}) is None
    emb = get_case("emb_cam")
    assert emb.stored_names({**_as_stored(emb.config()), "key_points": "7"}) is None
    assert CaseSpec(kind="bare", config=SphereConfig, problem=SphereProblem,
                    default_solver="de_gr").stored_names(stored) is None
