"""Property test (issue #11): valid case files mutated at random — a value replaced by a
hostile one, a key dropped or added, a table turned into a scalar, text spliced into the
file — always end in exit 0, or exit 2 with one ``error:`` line; never a traceback, and
nothing is written but the requested archive."""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import tomli_w
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from camopt.cli import app
from camopt.cli.app import INTERNAL
from tests.conftest import CONFIGS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

runner = CliRunner()
# the VCB files are being rewritten (another issue); these cover the other three cases
BASES = ["fast_switch.toml", "fast_switch_de.toml", "emb.toml", "opening_spring_pp3.toml",
         "opening_spring_lse6.toml"]
# a budget small enough for a run per example (mutations may override it)
SMALL = {"de_gr": {"population": 8, "generations": 3}, "pso": {"particles": 6, "iterations": 3},
         "newton_pp": {"starts": 2}, "simplex": {"starts": 1, "maxiter": 40}}

HOSTILE = st.one_of(
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 0, 0.0, -1, 2**63 - 1,
                     -(2**63), 1e-320, 0.14, 1e11, "", "x" * 300, "../../x", "/tmp/x",
                     "[/]x", "[red]x[/red]", "a\0b", [], [[[1]]], {}, {"a": 1}, True,
                     ["fast_switch"], "fast_switch", "de_gr", "pso"]),
    st.floats(width=64), st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.text(max_size=12), st.lists(st.floats(), max_size=3),
)


def _paths(data: dict[str, Any], prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    out = []
    for key, value in data.items():
        out.append((*prefix, key))
        if isinstance(value, dict):
            out += _paths(value, (*prefix, key))
    return out


def _base(name: str) -> dict[str, Any]:
    data = tomllib.loads((CONFIGS / name).read_text())
    data.setdefault("run", {})["repeats"] = 1
    data["solver"].update(SMALL.get(data["solver"]["name"], {}))
    if isinstance(data["solver"].get("polish"), dict):  # the polish's own budget, small too
        data["solver"]["polish"].update(evaluations=120, maxiter=20)
    return data


@st.composite
def mutated(draw: st.DrawFn) -> str:
    data = _base(draw(st.sampled_from(BASES)))
    for _ in range(draw(st.integers(1, 2))):
        paths = _paths(data)
        path = draw(st.sampled_from(paths)) if paths else ("case",)
        node = data
        for part in path[:-1]:
            node = node[part]
        action = draw(st.sampled_from(["set", "set", "drop", "add", "scalar", "scale", "scale"]))
        value = node.get(path[-1])
        if action == "scale" and isinstance(value, (int, float)) and not isinstance(value, bool):
            # odd but valid values: the physics runs on them
            factor = draw(st.sampled_from([0.5, 0.9, 1.1, 2.0, 3.0, -1.0]))
            node[path[-1]] = type(value)(value * factor)
        elif action in ("set", "scale") or (action == "scalar" and isinstance(value, dict)):
            node[path[-1]] = draw(HOSTILE)
        elif action == "drop":
            node.pop(path[-1], None)
        elif action == "add":
            node[draw(st.sampled_from(["zz", "kind", "name", "extends", "repeats"]))] = draw(
                HOSTILE)
    try:
        return tomli_w.dumps(data)
    except (TypeError, ValueError):  # a value TOML cannot hold (a NUL in a key, say)
        return tomli_w.dumps(_base(BASES[0]))


def _check(text: str, command: str) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        case, out = folder / "case.toml", folder / "out.h5"
        case.write_text(text, encoding="utf-8", errors="surrogatepass")
        args = [command, str(case)] + (["--out", str(out), "--quiet"] if command == "run" else [])
        r = runner.invoke(app, args)
        assert r.exit_code in (0, 2), (r.exit_code, r.output, text)
        if r.exit_code == 2:
            assert r.stderr.startswith("error: ") and r.stderr.count("\n") == 1, r.stderr
            assert INTERNAL not in r.stderr, (r.stderr, text)
        assert isinstance(r.exception, (SystemExit, type(None))), (r.exception, text)
        written = sorted(p.name for p in folder.iterdir())
        expected = ["case.toml", "out.h5"] if command == "run" and r.exit_code == 0 else [
            "case.toml"]
        assert written == expected, (written, r.output)
        return r.exit_code


@settings(max_examples=80, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(mutated())
def test_mutated_case_files_run_or_fail_in_one_line(text):
    event(f"exit {_check(text, 'run')}")


@settings(max_examples=80, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(BASES), st.integers(0, 10_000), st.text(max_size=8), st.booleans())
def test_spliced_text_validates_or_fails_in_one_line(name, at, insert, cut):
    text = (CONFIGS / name).read_text()
    at %= len(text)
    text = text[:at] + ("" if cut else insert) + text[at + (len(insert) if cut else 0):]
    event(f"exit {_check(text, 'validate')}")
