"""Command-line values for --set and --grid."""

from __future__ import annotations

import json
import os
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.config.loader import parse_overrides, parse_value
from camopt.errors import ConfigError
from tests.conftest import CONFIGS
from tests.helpers import load


@pytest.mark.parametrize("raw, value", [
    ("3", 3), ("1.5", 1.5), ("true", True), ("[1, 2]", [1, 2]), ('"a b"', "a b"),
    ("{peak_torque_nm = 5.4}", {"peak_torque_nm": 5.4}), ("simplex", "simplex"),
    ("runs/vcb-20261122.h5", "runs/vcb-20261122.h5"), ("/tmp/a.h5", "/tmp/a.h5"),
    ("./a.h5", "./a.h5"), ("~/runs/a.h5", "~/runs/a.h5"),
])
def test_values_are_toml_or_a_bare_word_or_path(raw, value):
    assert parse_value(raw) == value


@pytest.mark.parametrize("raw", ["[1,", "two words", "a=b"])
def test_other_text_is_refused(raw):
    with pytest.raises(ValueError):
        parse_value(raw)


def test_override_names_the_key_it_cannot_parse():
    with pytest.raises(ConfigError, match="case.x: cannot parse value"):
        parse_overrides(["case.x=two words"])


# ---- hostile case files (issue #11): one ConfigError naming file and key, never a crash


FAST = CONFIGS / "fast_switch.toml"
DE = CONFIGS / "fast_switch_de.toml"


@pytest.mark.parametrize("override, where, what", [
    ("case.m3_kg=nan", "case.m3_kg", "finite"),
    ("case.m3_kg=inf", "case.m3_kg", "finite"),
    ("run.target=nan", "run.target", "finite"),
    ("case.sf_bounds_mm=[1, inf]", "case.sf_bounds_mm.upper", "finite"),
    ("case.link2_length_mm=1e308", "case.link2_length_mm", "beyond 1e+12"),
    ("case.link2_length_mm=0.2", "case.link2_length_mm", "physical range [1, 5000] mm"),
    ("case.max_coils=100000000", "case.max_coils", "less than or equal to 1000"),
    ("solver.population=9223372036854775807", "solver.population", "10000"),
    ("solver.generations=9223372036854775807", "solver.generations", "100000"),
    ("run.repeats=1000000000", "run.repeats", "10000"),
    ("case.kind=[\"fast_switch\"]", "case.kind", "must be a string"),
    ("solver.name={a = 1}", "solver.name", "must be a string"),
    ("run.name='../../../x'", "run.name", "must be a file name"),
    ("run.name='/tmp/x'", "run.name", "must be a file name"),
    ("run.name='[/]x'", "run.name", "must be a file name"),
    ("run.name='" + "a" * 250 + "'", "run.name", "longer than 100 bytes"),
])
def test_hostile_values_are_refused_with_the_reason(override, where, what):
    with pytest.raises(ConfigError) as info:
        load(DE, override)
    assert info.value.where == where and what in info.value.what


def test_nul_in_a_run_name_is_refused():
    with pytest.raises(ConfigError, match="run.name: must be a file name"):
        load(FAST, 'run.name="a\\u0000b"')


def test_plausibility_can_be_switched_off():
    cfg = load(FAST, "case.link2_length_mm=0.2", "run.check_plausibility=false")
    assert cfg.case.link2_length_mm == 0.2


def test_a_string_solver_table_with_a_solver_override(tmp_path):
    case = tmp_path / "c.toml"
    case.write_text('solver = "x"\n[case]\nkind = "fast_switch"\n')
    cfg = load(case, "solver.name=de_gr")
    assert cfg.solver.name == "de_gr"


def test_deep_nesting_is_a_syntax_error(tmp_path):
    case = tmp_path / "deep.toml"
    case.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ConfigError, match="nested too deeply"):
        load(case)


def test_only_regular_files_under_the_size_cap(tmp_path):
    with pytest.raises(ConfigError, match="not a regular file"):
        load("/dev/zero")
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="not a regular file"):
        load(fifo)  # would block on open without O_NONBLOCK
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 2**20 + "\n")
    with pytest.raises(ConfigError, match="at most 1048576 bytes"):
        load(big)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load(binary)


@pytest.mark.skipif(sys.platform == "win32", reason="symlinks")
def test_extends_through_a_symlink_loop_or_itself(tmp_path):
    (tmp_path / "a.toml").symlink_to(tmp_path / "b.toml")
    (tmp_path / "b.toml").symlink_to(tmp_path / "a.toml")
    case = tmp_path / "c.toml"
    case.write_text('extends = "a.toml"\n[solver]\nname = "enumeration"\n')
    with pytest.raises(ConfigError, match="extends: cannot follow"):
        load(case)
    case.write_text('extends = "c.toml"\n')
    with pytest.raises(ConfigError, match="extends: circular"):
        load(case)


def test_a_solver_table_extending_the_same_solver_merges_key_by_key(tmp_path):
    """A file extending vcb_velocity_robust.toml (DE-gr) with ``population = 100`` alone
    keeps the base's generations and F/CR; a [solver] with a name replaces the table, the
    same solver's too (fast_switch_robust.toml drops fast_switch_de.toml's polish so)."""
    case = tmp_path / "c.toml"
    base = (CONFIGS / "vcb_velocity_robust.toml").as_posix()
    case.write_text(f'extends = "{base}"\n[solver]\npopulation = 100\n')
    solver = load(case).solver
    assert (solver.name, solver.population, solver.generations,
            solver.mutation_factor) == ("de_gr", 100, 500, 0.7)
    case.write_text(f'extends = "{base}"\n[solver]\nname = "pso"\n')
    swarm = load(case).solver
    assert swarm.name == "pso" and not hasattr(swarm, "mutation_factor")
    assert load(CONFIGS / "fast_switch_robust.toml").solver.polish is None
    assert load(CONFIGS / "fast_switch_de.toml").solver.polish is not None


# ---- did you mean (issue #34): a near name is offered for every unknown name


@pytest.mark.parametrize("override, where, hint", [
    ("case.link2_length_m=0.2", "case.link2_length_m", "did you mean 'link2_length_mm'?"),
    ("solver.populaton=20", "solver.populaton", "did you mean 'population'?"),
    ("solver.name=de_g", "solver.name", "did you mean 'de_gr'?"),
    ("case.kind=fast_swich", "case.kind", "did you mean 'fast_switch'?"),
    ("run.repeat=2", "run.repeat", "did you mean 'repeats'?"),
])
def test_unknown_names_get_the_nearest_known_one(override, where, hint):
    with pytest.raises(ConfigError) as info:
        load(DE, override)
    assert info.value.where == where and hint in info.value.what


def test_a_name_far_from_every_known_one_gets_no_guess():
    with pytest.raises(ConfigError) as info:
        load(DE, "case.zzzzqqq=1")
    assert info.value.what == "unknown key"


def test_init_of_a_mistyped_kind_offers_the_kind():
    from camopt.cases import get_case

    with pytest.raises(ConfigError, match=r"unknown case kind 'vbc' \(did you mean 'vcb'\?\)"):
        get_case("vbc")


def test_plausible_pairs_are_checked_number_by_number():
    """A pair field with a physical range (a velocity band in m/s) refuses mm/s typed into
    it, naming the first number outside, unless plausibility is switched off."""
    from typing import Annotated

    from pydantic import ValidationError

    from camopt.config.models import Pair, Plausible, Strict

    class Band(Strict):
        closing_velocity_m_s: Annotated[Pair, Plausible(0.0, 20.0)] = (0.7, 1.1)

    assert Band(closing_velocity_m_s=(0.7, 1.1)).closing_velocity_m_s == (0.7, 1.1)
    with pytest.raises(ValidationError, match=r"900 is outside the physical range \[0, 20\] "
                       "m/s"):
        Band(closing_velocity_m_s=(900.0, 1100.0))
    off = Band.model_validate({"closing_velocity_m_s": (900.0, 1100.0)},
                              context={"check_plausibility": False})
    assert off.closing_velocity_m_s == (900.0, 1100.0)


VCB = CONFIGS / "vcb_velocity.toml"


@pytest.mark.parametrize("override, where, what", [
    # issue #34: a link typed in cm, a velocity band typed in mm/s
    ("case.l1_mm=14.8", "case.l1_mm", "14.8 is outside the physical range [20, 2000] mm"),
    ("case.closing_velocity_m_s=[900, 1100]", "case.closing_velocity_m_s",
     "900 is outside the physical range [0, 20] m/s"),
])
def test_the_vcb_refuses_centimetres_and_millimetres_per_second(override, where, what):
    with pytest.raises(ConfigError) as info:
        load(VCB, override)
    assert info.value.where == where and what in info.value.what
    assert load(VCB, override, "run.check_plausibility=false").case.kind == "vcb"


# ---- types are strict (issue #49): a number is a number, a switch is true or false


def _typed_keys() -> list[tuple[str, str, str, object]]:
    """(config file, section, key, value) of every number and switch the shipped
    configs set at the top of a section, after loading."""
    out = []
    for path in sorted(CONFIGS.glob("*.toml")):
        for section, table in load(path).effective().items():
            out += [(path.name, section, k, v) for k, v in table.items()
                    if isinstance(v, (bool, int, float))]
    return out


TYPED = _typed_keys()


def _wrong(value: object) -> st.SearchStrategy[str]:
    """TOML text of a value of the wrong type for a field holding ``value``: a string
    holding a number (or a switch), a switch for a number, a float for an integer, a
    number for a switch."""
    as_string = st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=False),
                          st.booleans()).map(lambda v: json.dumps(str(v).lower()
                                                                  if isinstance(v, bool)
                                                                  else str(v)))
    if isinstance(value, bool):
        return st.one_of(as_string, st.integers(-2, 2).map(str))
    switch = st.sampled_from(["true", "false"])
    if isinstance(value, int):
        return st.one_of(as_string, switch, st.integers(1, 10**4).map(lambda v: f"{v}.0"))
    return st.one_of(as_string, switch)


@settings(max_examples=120, derandomize=True, deadline=None)
@given(data=st.data())
def test_wrong_types_are_refused_naming_the_field(data, tmp_path_factory):
    """``repeats = true``, ``population = "10"``, ``generations = 2.0``: pydantic's lax
    mode converted each to a number silently; strict mode refuses it, in a case file and
    in --set (whose value is TOML: ``--set solver.population=10`` is a number,
    ``--set 'solver.population="10"'`` a string), naming the field."""
    name, section, key, value = data.draw(st.sampled_from(TYPED))
    wrong = data.draw(_wrong(value))
    with pytest.raises(ConfigError) as info:
        load(CONFIGS / name, f"{section}.{key}={wrong}")
    assert info.value.source == "--set" and info.value.where == f"{section}.{key}"
    case = tmp_path_factory.mktemp("strict") / "case.toml"
    case.write_text(f"extends = {json.dumps(str(CONFIGS / name))}\n[{section}]\n"
                    f"{key} = {wrong}\n")
    with pytest.raises(ConfigError) as info:
        load(case)
    assert info.value.source == str(case) and info.value.where == f"{section}.{key}"


@pytest.mark.parametrize("override", ["run.repeats=true", "solver.generations=true",
                                      'solver.population="10"', "solver.population=10.0"])
def test_the_reported_conversions_are_refused(override):
    key = override.partition("=")[0]
    with pytest.raises(ConfigError, match=f"^--set: {key}: Input should be a valid"):
        load(DE, override)


def test_numbers_from_the_command_line_are_still_numbers():
    cfg = load(DE, "solver.population=12", "run.repeats=2", "case.m3_kg=3",
               "run.check_plausibility=false")
    assert (cfg.solver.population, cfg.run.repeats, cfg.case.m3_kg) == (12, 2, 3.0)
    assert cfg.run.check_plausibility is False
