"""Property test (issue #23): every command that reads an archive or writes files, given an
archive mutated at random (an attribute dropped or replaced by a hostile value, a group or
dataset dropped or replaced, a link leading outside the file) and an output folder with
a file, a symlink or a directory planted at random output names, ends in exit 0, or exit
2 with one ``error:`` line; never a traceback or camopt's internal-error line; nothing
outside the output folder changes and nothing there is replaced without ``--force``."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from camopt.cli import app
from camopt.cli.app import INTERNAL
from tests.conftest import CONFIGS

runner = CliRunner()
HOSTILE = [np.nan, np.inf, -1, 0, 2**62, "", "x" * 500, "[1, 2", "{}", "[]", "null",
           '["a"]', np.array([1.0, 2.0]), np.bytes_(b"\xff\xfe"), True]
COMMANDS = {  # how each command is called: {a} the archive, {d} the output folder
    "show": ["show", "{a}"], "show-json": ["show", "{a}", "--format", "json"],
    "compare": ["compare", "{a}", "{a}"], "export": ["export", "{a}", "--out", "{d}"],
    "export-dxf": ["export", "{a}", "--format", "dxf", "--out", "{d}"],
    "plot": ["plot", "{a}", "--out", "{d}"], "report": ["report", "{a}", "--out", "{d}/r.html"],
    "tolerance": ["tolerance", "{a}", "--samples", "20", "--out", "{d}/t.h5"],
}


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hostile-archives")
    run = folder / "run.h5"
    r = runner.invoke(app, ["run", str(CONFIGS / "fast_switch.toml"), "--out", str(run),
                            "--quiet"])
    assert r.exit_code == 0, r.output
    with h5py.File(run) as f:
        names: list[str] = []
        f.visit(names.append)
        attrs = [(name, key) for name in ["", *names] for key in (f[name] if name else f).attrs]
    return run, names, attrs


def mutate(path: Path, names: list[str], attrs: list[tuple[str, str]], data) -> str:
    kind = data.draw(st.sampled_from(["drop-attr", "attr", "drop", "replace", "link",
                                      "none"]))
    with h5py.File(path, "a") as f:
        if kind == "drop-attr" or kind == "attr":
            name, key = data.draw(st.sampled_from(attrs))
            obj = f[name] if name else f
            del obj.attrs[key]
            if kind == "attr":
                obj.attrs[key] = data.draw(st.sampled_from(HOSTILE))
        elif kind in ("drop", "replace", "link"):
            name = data.draw(st.sampled_from(names))
            if name in f:
                del f[name]
            if kind == "replace":
                f[name] = data.draw(st.sampled_from(["text", np.zeros(3), np.nan]))
            elif kind == "link":
                f[name] = h5py.ExternalLink(str(path), "/" + name)
    return kind


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_every_reading_command_survives_a_mutated_archive(sources, data):
    run, names, attrs = sources
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        archive, out, outside = tmp / "a.h5", tmp / "out", tmp / "outside.txt"
        shutil.copy(run, archive)
        out.mkdir()
        outside.write_text("precious")
        mutate(archive, names, attrs, data)
        command = data.draw(st.sampled_from(sorted(COMMANDS)))
        plant = data.draw(st.sampled_from(["none", "file", "symlink", "directory"]))
        planted = out / {"export": "a-summary.csv", "export-dxf": "a.dxf",
                         "plot": "a-convergence.png", "report": "r.html",
                         "tolerance": "t.h5"}.get(command, "x")
        if plant == "file":
            planted.write_text("mine")
        elif plant == "symlink":
            planted.symlink_to(outside)
        elif plant == "directory":
            planted.mkdir()
        force = data.draw(st.booleans()) and command in ("export", "export-dxf", "plot",
                                                         "report", "tolerance")
        args = [a.format(a=archive, d=out) for a in COMMANDS[command]]
        r = runner.invoke(app, args + (["--force"] if force else []))
        lines = [ln for ln in r.stderr.splitlines() if not ln.startswith("note:")]
        assert r.exit_code in (0, 2), (args, r.output)
        assert INTERNAL not in r.output and "Traceback" not in r.output, (args, r.output)
        if r.exit_code == 2:
            assert len(lines) == 1 and lines[0].startswith("error: "), (args, r.stderr)
        assert outside.read_text() == "precious"
        if plant == "file" and not force:
            assert planted.read_text() == "mine"
        assert not [p for p in out.rglob("*") if p.name.endswith((".tmp", ".lock"))]
