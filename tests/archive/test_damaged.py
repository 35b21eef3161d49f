"""Damaged archives (issue #11): every reader checks the schema and answers
``error: FILE: archive: what is wrong`` with exit code 2, never a traceback."""

from __future__ import annotations

import json
import shutil

import h5py
import numpy as np
import pytest
from typer.testing import CliRunner

from camopt.archive.sweeps import SWEEP_KEY, cell_row, journal_path, load_sweep
from camopt.cli import app
from camopt.cli.app import INTERNAL
from tests.conftest import CONFIGS

runner = CliRunner()
FAST = str(CONFIGS / "fast_switch.toml")
DE = str(CONFIGS / "fast_switch_de.toml")


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    d = tmp_path_factory.mktemp("good")
    run, sweep = d / "run.h5", d / "sweep.h5"
    assert invoke("run", FAST, "--out", run, "--quiet").exit_code == 0
    r = invoke("sweep", DE, "--out", sweep, "--seeds", "0:2", "--quiet", "--jobs", "1",
               "--set", "solver.generations=5", "--set", "solver.population=8")
    assert r.exit_code == 0, r.output
    return run, sweep


def one_error_line(r, path):
    assert r.exit_code == 2, r.output
    assert r.stderr.count("\n") == 1 and r.stderr.startswith(f"error: {path}: ")
    assert INTERNAL not in r.stderr


def _del_attr(name, where="/"):
    def damage(f):
        del f[where].attrs[name]
    return damage


def _set_attr(name, value, where="/"):
    def damage(f):
        f[where].attrs[name] = value
    return damage


def _del(where):
    def damage(f):
        del f[where]
    return damage


RUN_DAMAGE = {
    "missing variables": _del_attr("variables"),
    "missing best": _del("best"),
    "missing repeat attribute": _del_attr("nfev", "/repeats/r000"),
    "bad JSON": _set_attr("config_effective", "{not json"),
    "JSON of the wrong shape": _set_attr("variables", json.dumps({"a": 1})),
    "x of the wrong length": lambda f: (f["best"].__delitem__("x"),
                                        f["best"].create_dataset("x", data=[1.0])),
    "newer schema": _set_attr("schema_version", 99),
    "no repeats": lambda f: [f["repeats"].__delitem__(k) for k in list(f["repeats"])],
    # issue #30: names that are not the case's (tolerance ended 'internal error: KeyError')
    "variables renamed": lambda f: f.attrs.__setitem__("variables", json.dumps(
        [f"v{i}" for i in range(len(json.loads(f.attrs["variables"])))])),
    "variables swapped": lambda f: f.attrs.__setitem__("variables", json.dumps(
        json.loads(f.attrs["variables"])[::-1])),
    # issue #30: a NaN best was shown 'PASS: meets all 6 requirements'
    "NaN best design": lambda f: f["best"]["x"].__setitem__(0, np.nan),
    "NaN best objective": _set_attr("objective", np.nan, "/best"),
}


@pytest.mark.parametrize("damage", RUN_DAMAGE)
def test_damaged_run_archives(good, tmp_path, damage):
    path = tmp_path / "bad.h5"
    shutil.copy(good[0], path)
    with h5py.File(path, "a") as f:
        RUN_DAMAGE[damage](f)
    for args in (["show", path], ["compare", good[0], path], ["export", path, "--out", tmp_path],
                 ["tolerance", path, "--samples", "20"], ["report", path, "--out",
                                                          tmp_path / "r.html"]):
        r = invoke(*args)
        one_error_line(r, path)
        assert ": archive: " in r.stderr


def test_names_checked_on_the_validated_config_when_the_stored_table_cannot_answer(
        good, tmp_path, monkeypatch):
    """Names the stored ``[case]`` does not confirm as written (an archive of another
    version) are checked on the config validated: an intact archive is shown, renamed
    variables are still refused."""
    from camopt.cases import CaseSpec

    monkeypatch.setattr(CaseSpec, "stored_names", lambda self, case: None)
    assert invoke("show", good[0]).exit_code == 0
    path = tmp_path / "bad.h5"
    shutil.copy(good[0], path)
    with h5py.File(path, "a") as f:
        RUN_DAMAGE["variables renamed"](f)
    r = invoke("show", path)
    one_error_line(r, path)
    assert "do not match case 'fast_switch'" in r.stderr


def _set_cell(column, index, value):
    def damage(f):
        f["cells"][column][index] = value
    return damage


SWEEP_DAMAGE = {
    "extra cell column": lambda f: f["cells"].create_dataset("z", data=[1, 2]),
    "missing cell column": lambda f: f["cells"].__delitem__("objective"),
    "bad spec": _set_attr("spec", json.dumps({"data": {}, "grid": 3, "seeds": [0]})),
    "cell outside the sweep": _set_cell("seed", 0, 99),
    "offsets past the values": lambda f: f["cells"]["x"]["offsets"].__setitem__(-1, 10**6),
    "missing cells": _del("cells"),
}


@pytest.mark.parametrize("damage", SWEEP_DAMAGE)
def test_damaged_sweep_archives(good, tmp_path, damage):
    path = tmp_path / "bad.h5"
    shutil.copy(good[1], path)
    with h5py.File(path, "a") as f:
        SWEEP_DAMAGE[damage](f)
    for args in (["compare", path], ["sweep", "--resume", path, "--quiet", "--jobs", "1"]):
        r = invoke(*args)
        one_error_line(r, path)
        assert ": archive: " in r.stderr


def test_flipped_and_truncated_bytes(good, tmp_path):
    """Bytes flipped at random places (a failing disk), and a truncated copy: every
    reader answers with one line, or reads an archive the flip did not touch."""
    rng = np.random.default_rng(11)
    outcomes = {0: 0, 2: 0}
    for i, source in enumerate([*[good[0]] * 12, *[good[1]] * 6]):
        raw = bytearray(source.read_bytes())
        for at in rng.integers(0, len(raw), 4):
            raw[at] ^= 0xFF
        path = tmp_path / f"flip{i}.h5"
        path.write_bytes(bytes(raw))
        command = ["show", path, "--format", "json"] if source == good[0] else ["compare", path]
        r = invoke(*command)
        if r.exit_code == 2:
            one_error_line(r, path)
        else:
            assert r.exit_code == 0, r.output
        outcomes[r.exit_code] += 1
    cut = tmp_path / "cut.h5"
    cut.write_bytes(good[0].read_bytes()[:5000])
    one_error_line(invoke("show", cut), cut)
    assert sum(outcomes.values()) == 18


def test_damaged_sweep_journal(good, tmp_path):
    """A journal line that is complete but not a cell (a failing disk) is bad input with
    one line; a line cut short by a kill (no newline) is ignored."""
    path = tmp_path / "bad.h5"
    shutil.copy(good[1], path)
    journal = tmp_path / f".{path.name}.cells"
    journal.write_text('{"point": 0, "seed"')
    assert invoke("compare", path).exit_code == 0
    journal.write_text('{"point": 0, "seed": 1}\n')
    for args in (["compare", path], ["sweep", "--resume", path, "--quiet", "--jobs", "1"]):
        r = invoke(*args)
        one_error_line(r, path)
        assert ": archive: " in r.stderr


def _journal_lines(sweep):
    """Complete journal lines for the cells of ``sweep`` (as a running sweep writes them)."""
    spec, cells = load_sweep(sweep)
    return [json.dumps({SWEEP_KEY: spec.sweep_id, **cell_row(r)}) for r in cells.values()]


def test_a_blank_journal_line_is_skipped(good, tmp_path):
    """Issue #30: a blank line between complete ones holds no cell: the sweep reads."""
    path = tmp_path / "s.h5"
    shutil.copy(good[1], path)
    a, b = _journal_lines(path)[:2]
    journal_path(path).write_text(f"{a}\n\n  \n{b}\n")
    assert len(load_sweep(path)[1]) == 2
    assert invoke("compare", path).exit_code == 0


def test_a_cut_line_in_the_middle_of_the_journal_names_the_remedy(good, tmp_path):
    """Issue #30: a line cut short with another written after it is one error line naming
    the line, the journal and the remedy (delete it, --resume); after that remedy the
    sweep resumes and reads."""
    path = tmp_path / "s.h5"
    shutil.copy(good[1], path)
    a, b = _journal_lines(path)[:2]
    journal = journal_path(path)
    journal.write_text(f"{a}\n{b[:len(b) // 2]}\n{a}\n")
    r = invoke("compare", path)
    one_error_line(r, path)
    assert "line 2: damaged" in r.stderr and str(journal) in r.stderr
    assert f"camopt sweep --resume {path}" in r.stderr
    journal.write_text(f"{a}\n{a}\n")  # the remedy: the line deleted
    assert invoke("sweep", "--resume", path, "--quiet", "--jobs", "1").exit_code == 0
    assert invoke("compare", path).exit_code == 0
