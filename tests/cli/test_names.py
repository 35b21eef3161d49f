"""File, folder and run names print as they are (review 75; docs/reliability.md, Names).

A printable name prints verbatim: markup (``[bold]``), emoji codes and backslashes are
text. A character that is not printable (ESC of an ANSI escape, CR, LF, tab, U+202E) prints
as its Python escape (``\\x1b``), so no name can drive the terminal or break a line; the
exact name is in ``--format json``. Each CLI test here failed on main: rich dropped the
backslash of ``t\\[x``, stripped CR and BEL, expanded tabs, and every command passed ESC,
LF and U+202E to the terminal."""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import camopt
from camopt.cli import app
from camopt.cli.console import NameConsole, escape, visible
from camopt.cli.layout import print_table
from tests.cli.test_faults import CAMOPT, one_error_line
from tests.conftest import CONFIGS

runner = CliRunner()

# control characters, C1's CSI, bidirectional and zero-width characters: never printed
UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u200b-\u200f\u202a-\u202e\u2066-\u2069]")

# names with markup, emoji codes and backslashes (printed verbatim), and with control and
# invisible characters (printed escaped)
NAMES = ["a[bold]b", "[link=http:e.vil]c[/link]", ":smile:", "t\\[x", "tail\\",
         "back\\\\sl", "sp ace", "esc\x1b[31mred", "nl\nX", "cr\rX", "tab\tX", "bell\x07",
         "csi\x9b31m", "rlo\u202etxt", "zw\u200bsp"]


def printed(markup: str, width: int = 10_000, **options) -> str:
    """What a camopt console prints for ``markup`` (no colour), without the newline."""
    console = NameConsole(file=io.StringIO(), emoji=False, width=width, color_system=None)
    console.print(markup, **options)
    return console.file.getvalue()[:-1]


# ---- the helpers: exact, whatever the name and the markup around it ---------------------
@settings(max_examples=400, deadline=None)
@given(st.text(st.characters(codec="utf-8")) | st.text("[]\\/:ab =#@"))
def test_a_name_prints_as_visible_shows_it_in_any_markup(name):
    shown = visible(name)
    assert not UNSAFE.search(shown) and shown.isprintable()
    if name.isprintable():
        assert shown == name
    for template, plain in (("{}", "{}"), ("[bold]{}[/]", "{}"), ("{}: [bold]z[/] w", "{}: z w"),
                            ("[italic]a {}[/] [red]b[/]", "a {} b")):
        for highlight in (False, True):
            assert printed(template.format(escape(name)), highlight=highlight) == \
                plain.format(shown), (template, name)


def test_rich_markup_escape_is_not_exact():
    """Why camopt has its own escape: rich's drops or doubles a backslash next to '['."""
    from rich.markup import escape as rich_escape

    assert printed(rich_escape("t\\[x")) == "t[x"
    assert printed(rich_escape("tail\\") + ": x") == "tail\\\\: x"
    assert printed(escape("t\\[x")) == "t\\[x"
    assert printed(escape("tail\\") + ": x") == "tail\\: x"


def test_visible_escapes_each_unprintable_character_as_python_does():
    assert visible("a\x1b[31mb\n\r\t\u202e\u00a0c") == "a\\x1b[31mb\\n\\r\\t\\u202e\\xa0c"
    assert visible("caf\u00e9 \u65e5\u672c \U0001f600") == "caf\u00e9 \u65e5\u672c \U0001f600"


def test_a_table_is_laid_out_by_the_width_it_prints(monkeypatch):
    """A cell is measured as printed: escaped characters and double-width ones (main
    measured len(): an escaped or CJK name that looked short was split inside a word)."""
    from camopt.cli import console, layout

    for name in ("esc\x1b[31m\x1b[31mred-swe.h5", "\u8a2d\u8a08" * 10 + ".h5"):
        stream = NameConsole(file=io.StringIO(), emoji=False, width=80, color_system=None)
        monkeypatch.setattr(layout, "out", stream)
        monkeypatch.setattr(console, "out", stream)
        print_table("t", ["archive", "case", "verdict", "objective", "created"],
                    [[name, "fast_switch", "pass", "18.9039", "2026-11-27 10:41"]],
                    numeric=[False, False, False, True, False])
        lines = stream.file.getvalue().splitlines()
        assert visible(name) in lines, lines


# ---- the commands ------------------------------------------------------------------------
def _file_name(name: str) -> str:
    return name.replace("/", "_")


@pytest.fixture(scope="module")
def named(tmp_path_factory, fast_run):
    """Per name: a folder holding NAME.toml (fast_switch) and NAME.h5 (a run archive)."""
    root = tmp_path_factory.mktemp("names")
    folders = {}
    for i, name in enumerate(NAMES):
        folder = root / f"n{i}"
        folder.mkdir()
        base = _file_name(name)
        shutil.copy(CONFIGS / "fast_switch.toml", folder / f"{base}.toml")
        shutil.copy(fast_run, folder / f"{base}.h5")
        folders[name] = folder
    return folders


def _check(result, name: str, *, code: int = 0) -> str:
    text = result.stdout + result.stderr
    assert result.exit_code == code, text
    assert not UNSAFE.search(text), repr(text)
    assert visible(_file_name(name)) in text, (name, text)
    return text


@pytest.mark.parametrize("name", NAMES)
def test_validate_init_and_errors_print_the_name(named, name):
    folder = named[name]
    base = str(folder / _file_name(name))
    _check(runner.invoke(app, ["validate", base + ".toml"]), name)
    _check(runner.invoke(app, ["init", "fast_switch", "--out", base + "-init.toml"]), name)
    missing = runner.invoke(app, ["show", base + "-missing.h5"])
    _check(missing, name, code=2)
    assert one_error_line(missing.stderr), missing.stderr


@pytest.mark.parametrize("name", NAMES)
def test_run_show_runs_and_compare_print_the_name(named, name):
    folder = named[name]
    base = str(folder / _file_name(name))
    run = runner.invoke(app, ["run", base + ".toml", "--out", base + "-run.h5", "--quiet"])
    assert run.stdout == visible(base + "-run.h5") + "\n"
    _check(run, name)
    _check(runner.invoke(app, ["show", base + ".h5"]), name)
    _check(runner.invoke(app, ["runs", str(folder)]), name)
    _check(runner.invoke(app, ["compare", base + ".h5", base + "-run.h5"]), name)
    # the exact name: --format json
    rows = json.loads(runner.invoke(app, ["runs", str(folder), "--format", "json"]).stdout)
    assert base + ".h5" in [r["path"] for r in rows]


# one name per hazard: markup, a backslash before "[", ESC, a line break, a bidirectional
# override and an invisible character (the outputs print names through the same console
# as the commands above, which take every name; each output costs seconds a name)
HAZARDS = ["[link=http:e.vil]c[/link]", "t\\[x", "esc\x1b[31mred", "nl\nX", "rlo\u202etxt",
           "zw\u200bsp"]


@pytest.mark.parametrize("name", HAZARDS)
def test_report_export_plot_and_tolerance_print_the_name(named, name):
    folder = named[name]
    base = str(folder / _file_name(name))
    _check(runner.invoke(app, ["report", base + ".h5", "--out", base + ".html"]), name)
    _check(runner.invoke(app, ["export", base + ".h5", "--out", str(folder)]), name)
    _check(runner.invoke(app, ["plot", base + ".h5", "--out", base + "-plots"]), name)
    _check(runner.invoke(app, ["tolerance", base + ".h5", "--samples", "20", "--out",
                               base + "-tol.h5", "--plot", base + "-tol"]), name)
    _check(runner.invoke(app, ["show", base + "-tol.h5"]), name)


@pytest.mark.parametrize("name", ["esc\x1b[31mred", "nl\nX", "t\\[x"])
def test_a_sweep_prints_the_name(named, name):
    base = str(named[name] / _file_name(name))
    sweep = runner.invoke(app, ["sweep", base + ".toml", "--seeds", "0:1", "--jobs", "1",
                                "--out", base + "-sweep.h5"])
    _check(sweep, name)
    quiet = runner.invoke(app, ["sweep", "--resume", base + "-sweep.h5", "--quiet"])
    assert quiet.stdout == visible(base + "-sweep.h5") + "\n"
    _check(runner.invoke(app, ["show", base + "-sweep.h5"]), name)


def test_next_quotes_a_path_for_the_shell(named):
    """show's `next: camopt tolerance PATH` is a command to copy: a path with a space is
    quoted (main printed it bare: two arguments)."""
    base = named["sp ace"] / "sp ace.h5"
    out = " ".join(runner.invoke(app, ["show", str(base)]).stdout.split())
    assert f"camopt tolerance '{base}' --samples 2000" in out, out


def test_in_a_terminal_width_nothing_reaches_the_terminal_raw(named):
    """A real process at 80 columns (show, runs, validate of a name holding ESC)."""
    name = "esc\x1b[31mred"
    root = str(Path(camopt.__file__).parents[1])  # this checkout's camopt, installed or not
    env = {**os.environ, "COLUMNS": "80", "PYTHONPATH": root}
    for args in (["show", f"{name}.h5"], ["runs", "."], ["validate", f"{name}.toml"]):
        proc = subprocess.run([*CAMOPT, *args], cwd=named[name], env=env,
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0, proc.stderr
        assert not UNSAFE.search(proc.stdout + proc.stderr)
        assert "esc\\x1b[31mred" in proc.stdout
