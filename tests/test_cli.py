"""The command line through typer's CliRunner: run, show, compare, and every bad input."""

from __future__ import annotations

import json
import os

import pytest
from typer.testing import CliRunner

from camopt.cases import cases
from camopt.cli import app
from tests.conftest import CONFIGS

runner = CliRunner()
FAST = str(CONFIGS / "fast_switch.toml")
DE = str(CONFIGS / "fast_switch_de.toml")
SMALL_DE = ["--set", "solver.generations=10", "--set", "solver.population=10",
            "--set", "solver.polish.maxiter=5"]  # small runs: the polish is no subject


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("runs")
    a, b = d / "a.h5", d / "b.h5"
    assert invoke("run", FAST, "--out", a, "--quiet").exit_code == 0
    r = invoke("run", DE, "--out", b, "--quiet", "--repeats", "3", *SMALL_DE)
    assert r.exit_code == 0, r.output
    return a, b


def test_run_prints_summary_and_writes_archive(tmp_path):
    out = tmp_path / "fs.h5"
    r = invoke("run", FAST, "--out", out)
    assert r.exit_code == 0, r.output
    assert out.is_file() and "verdict: " in r.stdout and "camopt show" in r.stdout
    r = invoke("run", FAST, "--out", out, "--force", "--verbose")  # the whole summary
    assert "best design" in r.stdout and "closure_time_ms" in r.stdout


def test_default_archive_path_is_runs_name_timestamp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = invoke("run", FAST, "--quiet")
    assert r.exit_code == 0, r.output
    (path,) = (tmp_path / "runs").iterdir()
    assert path.name.startswith("fast_switch-") and path.suffix == ".h5"
    assert r.stdout.strip() == os.path.join("runs", path.name)


def test_show_json_has_exactly_the_documented_keys(two_runs):
    r = invoke("show", two_runs[0], "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert list(doc) == ["verdict", "verdict_sentence", "requirements", "at_limit",
                         "expected_yield", "next", "case", "solver", "best", "repeats",
                         "table", "reference", "verdict_grade", "verdict_headline",
                         "yield_target"]
    assert doc["verdict"] == "pass"  # Eq 92's optimum meets R1-R21 and its ratings
    assert doc["reference"]["label"] == "reference: paper's optimum, Eq 92"
    assert doc["reference"]["values"]["coils"] == 7
    assert set(doc["best"]) == {"objective", "feasible", "x", "metrics", "active", "violated"}
    assert isinstance(doc["best"]["active"], list)
    for key in ("closure_time_ms", "closure_time_exact_ms", "coils"):
        assert key in doc["best"]["metrics"]
    assert {"seed", "objective", "feasible", "nfev", "wall_s"} <= set(doc["repeats"][0])
    row = doc["table"][4]
    for key in ("coils", "s0_mm", "sud_mm", "sf_mm", "k_n_per_m", "r3_mm", "r2_mm",
                "closure_time_ms", "feasible", "active"):
        assert key in row
    assert row["coils"] == 7 and isinstance(row["active"], list)


def test_show_table(two_runs):
    r = invoke("show", two_runs[1])
    assert r.exit_code == 0 and "repeats" in r.stdout and "de_gr" in r.stdout


def test_compare_two_runs(two_runs):
    r = invoke("compare", *two_runs, "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["config_differences"]["solver.name"] == ["enumeration", "de_gr"]
    assert doc["statistics"][1]["runs"] == 3
    assert set(doc["statistics"][0]) == {"runs", "best", "median", "worst",
                                         "feasible_fraction", "successes", "success_rate"}
    assert len(doc["metrics"]["closure_time_ms"]) == 2
    r = invoke("compare", *two_runs)
    # the table shows the successes; feasible_fraction and the rest are in the JSON
    assert r.exit_code == 0 and "repeats: successes" in r.stdout


def test_validate_init_solvers(tmp_path):
    assert invoke("validate", FAST).exit_code == 0
    tpl = tmp_path / "t.toml"
    assert invoke("init", "fast_switch", "--out", tpl).exit_code == 0
    assert "# L, total length of link 2" in tpl.read_text()
    r = invoke("validate", tpl)
    assert r.exit_code == 0, r.output
    r = invoke("solvers")
    assert r.exit_code == 0 and "de_gr" in r.stdout and "fast_switch" in r.stdout


@pytest.mark.parametrize("kind", sorted(cases()))
def test_init_template_validates_for_every_kind(tmp_path, kind):
    path = tmp_path / f"{kind}.toml"
    r = invoke("init", kind, "--out", path)
    assert r.exit_code == 0, r.output
    r = invoke("validate", path)
    assert r.exit_code == 0, r.output


def test_python_m_camopt():
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "camopt", "--help"], capture_output=True,
                       text=True)
    assert r.returncode == 0 and "run" in r.stdout


# ---- bad input: one line 'error: <file>: <key>: <what>', exit 2, nothing written ----

def _case(tmp_path, text):
    path = tmp_path / "case.toml"
    path.write_text(text)
    return path


GOOD = '[case]\nkind = "fast_switch"\n[solver]\nname = "enumeration"\n'


def assert_bad(result, *fragments, folder=None):
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("error: ")
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    if folder is not None:
        assert not [p for p in folder.iterdir() if p.suffix in (".h5", ".tmp")]


def test_missing_file(tmp_path):
    assert_bad(invoke("run", tmp_path / "nope.toml"), "nope.toml: file: no such file")


def test_toml_syntax_error_names_line(tmp_path):
    path = _case(tmp_path, GOOD + "[run]\nname = \n")
    assert_bad(invoke("run", path, "--out", tmp_path / "x.h5"), "case.toml: line 6:",
               "TOML syntax", folder=tmp_path)


def test_unknown_key(tmp_path):
    path = _case(tmp_path, GOOD.replace('"fast_switch"', '"fast_switch"\nspring_colour = 3'))
    assert_bad(invoke("run", path, "--out", tmp_path / "x.h5"),
               "case.toml: case.spring_colour: unknown key", folder=tmp_path)


def test_wrong_type(tmp_path):
    path = _case(tmp_path, GOOD.replace('"fast_switch"', '"fast_switch"\nm2_kg = "heavy"'))
    assert_bad(invoke("run", path), "case.m2_kg:", "number")


def test_lower_bound_not_below_upper(tmp_path):
    path = _case(tmp_path, GOOD.replace('"fast_switch"', '"fast_switch"\nr2_bounds_mm = [5, 5]'))
    assert_bad(invoke("run", path), "case.r2_bounds_mm:", "must be below")


@pytest.mark.parametrize("key", ["link2_length_mm", "m3_kg", "shear_modulus_gpa"])
def test_non_positive_length_mass_stiffness(tmp_path, key):
    path = _case(tmp_path, GOOD.replace('"fast_switch"', f'"fast_switch"\n{key} = 0'))
    assert_bad(invoke("run", path), f"case.{key}:", "greater than 0")


def test_unknown_case_kind_lists_known(tmp_path):
    path = _case(tmp_path, GOOD.replace('"fast_switch"', '"toaster"'))
    assert_bad(invoke("run", path), "case.kind: unknown case kind 'toaster'", "fast_switch")


def test_unknown_solver_lists_known(tmp_path):
    path = _case(tmp_path, GOOD.replace('"enumeration"', '"annealing"'))
    assert_bad(invoke("run", path), "solver.name: unknown solver 'annealing'", "de_gr",
               "enumeration")


def test_solver_that_cannot_run_the_case(tmp_path, sphere_case):
    path = _case(tmp_path, '[case]\nkind = "sphere"\n[solver]\nname = "enumeration"\n')
    assert_bad(invoke("run", path, "--out", tmp_path / "x.h5"), "solver.name:",
               "cannot run case 'sphere'", "family", folder=tmp_path)


def test_set_unknown_key(tmp_path):
    assert_bad(invoke("run", FAST, "--set", "case.colour=3", "--out", tmp_path / "x.h5"),
               "--set: case.colour: unknown key", folder=tmp_path)


def test_set_unparsable_value(tmp_path):
    assert_bad(invoke("run", FAST, "--set", "case.m2_kg=[1,", "--out", tmp_path / "x.h5"),
               "--set: case.m2_kg: cannot parse value", folder=tmp_path)


def test_set_without_equals():
    assert_bad(invoke("run", FAST, "--set", "case.m2_kg"), "--set:", "section.key=value")


def test_unwritable_out(tmp_path):
    """A read-only folder (root can write to chmod 500 folders, so root uses /sys)."""
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    target = locked if os.geteuid() != 0 else "/sys"
    try:
        assert_bad(invoke("run", FAST, "--out", f"{target}/x.h5"), "--out:", "not writable")
    finally:
        locked.chmod(0o700)


def test_out_in_missing_folder(tmp_path):
    assert_bad(invoke("run", FAST, "--out", tmp_path / "no" / "x.h5"), "--out:",
               "does not exist")


def test_existing_out_without_force(tmp_path):
    out = tmp_path / "x.h5"
    out.write_bytes(b"precious")
    assert_bad(invoke("run", FAST, "--out", out), "x.h5: --out: exists", "--force")
    assert out.read_bytes() == b"precious"
    assert invoke("run", FAST, "--out", out, "--force", "--quiet").exit_code == 0


@pytest.mark.parametrize("command", ["show", "compare"])
def test_show_compare_reject_non_archives(tmp_path, command, two_runs):
    junk = tmp_path / "notes.h5"
    junk.write_text("not hdf5")
    args = [junk] if command == "show" else [two_runs[0], junk]
    assert_bad(invoke(command, *args), "notes.h5: file: not a camopt archive")


def test_polish_of_an_unknown_metric_is_bad_input(tmp_path):
    out = tmp_path / "r.h5"
    r = invoke("run", DE, "--out", out, *SMALL_DE, "--set", "solver.polish.minimise=torque")
    assert_bad(r, "fast_switch_de.toml", "solver", "polish.minimise: no metric 'torque'",
               folder=tmp_path)


def test_validate_runs_the_solver_checks_too():
    r = invoke("validate", DE, "--set", "solver.polish.minimise=torque")
    assert_bad(r, "fast_switch_de.toml", "solver", "polish.minimise: no metric 'torque'")


# ---- a solver or option the case cannot serve: exit 2 at validate, before any work ----

VCB = str(CONFIGS / "vcb.toml")


def test_corrections_asked_of_a_case_without_them(tmp_path):
    r = invoke("validate", VCB, "--set", "solver.name=pso", "--set", "solver.repair=true")
    assert_bad(r, "solver:", "cannot run case 'vcb'", "repair")


def test_misspelt_correction_name(tmp_path):
    r = invoke("validate", str(CONFIGS / "emb.toml"), "--set",
               "solver.repair_probability={ adjacnet = [1.0, 0.1] }")
    assert_bad(r, "repair_probability", "'adjacnet'", "adjacent")


def test_step_two_without_a_step_one_design(tmp_path):
    assert_bad(invoke("validate", VCB, "--set", "case.step=fourbar"), "case:",
               "cam_design or cam_archive")
