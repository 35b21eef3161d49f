"""Hardening round 4 (issue #30): each test here failed on main before the fix it names.

Reuses round 3's helpers (tests/cli/test_faults.py)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from camopt import archive
from tests.cli.test_faults import CAMOPT, DE, FAST, TINY, _fsize_limit, invoke, one_error_line


# ---- a folder whose name is not valid UTF-8 ---------------------------------------------
@pytest.mark.parametrize("command", ["run", "sweep", "report", "tolerance", "show"])
def test_a_non_utf8_folder_is_refused_before_any_work(tmp_path, fast_run, command):
    """Decision (docs/reliability.md): an argument that is not valid UTF-8 is refused at
    once, one line naming it with its bytes escaped, exit 2; nothing written. (main: run,
    sweep, report and tolerance did all the work, then ended 'internal error:
    UnicodeEncodeError'.)"""
    folder = os.path.join(os.fsencode(tmp_path), b"caf\xe9")  # Latin-1 'cafe'
    os.mkdir(folder)
    case = os.path.join(folder, b"case.toml")
    run = os.path.join(folder, b"run.h5")
    Path(os.fsdecode(case)).write_bytes(Path(FAST).read_bytes())
    Path(os.fsdecode(run)).write_bytes(fast_run.read_bytes())
    out = os.path.join(folder, b"out.h5")
    args = {"run": [b"run", case, b"--out", out],
            "sweep": [b"sweep", case, b"--seeds", b"0:1", b"--out", out],
            "report": [b"report", run],
            "tolerance": [b"tolerance", run, b"--samples", b"20", b"--out", out],
            "show": [b"show", run]}[command]
    proc = subprocess.run([*map(os.fsencode, CAMOPT), *args], capture_output=True,
                          timeout=60)
    err = proc.stderr.decode()
    assert proc.returncode == 2 and one_error_line(err), err
    assert "caf\\xe9" in err and "not valid UTF-8" in err
    assert sorted(os.listdir(folder)) == [b"case.toml", b"run.h5"]


def test_inside_a_non_utf8_folder_relative_paths_work(tmp_path, fast_run):
    """The remedy the error names: from inside the folder, relative paths are UTF-8."""
    folder = os.path.join(os.fsencode(tmp_path), b"caf\xe9")
    os.mkdir(folder)
    Path(os.fsdecode(os.path.join(folder, b"run.h5"))).write_bytes(fast_run.read_bytes())
    proc = subprocess.run([*CAMOPT, "report", "run.h5"], cwd=folder, capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert archive.load_run(os.fsdecode(os.path.join(folder, b"run.h5"))).kind == "fast_switch"


# ---- a full disk leaves no empty output folder --------------------------------------------
def test_a_full_disk_leaves_no_empty_output_folder(tmp_path, fast_run):
    """`plot --out p/q` on a full disk (the PNGs exceed a 3000-byte file limit): one error
    line, and neither p/q nor p, made by the command, is left behind empty (main left
    them); a folder that existed stays (export: tests/cli/test_faults.py)."""
    command = "plot"
    out = tmp_path / "p" / "q"
    proc = subprocess.run([*CAMOPT, command, fast_run, "--out", out], capture_output=True,
                          text=True, timeout=60, preexec_fn=_fsize_limit)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert not (tmp_path / "p").exists()
    (tmp_path / "p").mkdir()
    proc = subprocess.run([*CAMOPT, command, fast_run, "--out", tmp_path / "p"],
                          capture_output=True, text=True, timeout=60, preexec_fn=_fsize_limit)
    assert proc.returncode == 2 and list((tmp_path / "p").iterdir()) == []


# ---- a huge note: show is fast and bounded ------------------------------------------------
@pytest.fixture(scope="module")
def de_run(tmp_path_factory) -> Path:
    """A tiny DE-gr run of two repeats (`show` prints their notes)."""
    out = tmp_path_factory.mktemp("de") / "de.h5"
    r = invoke("run", DE, "--out", out, "--quiet", "--repeats", "2", *TINY)
    assert r.exit_code == 0, r.output
    return out


@pytest.mark.parametrize("notes", [["x" * 5_000_000], ["y" * 3000] * 500])
def test_show_of_an_archive_with_a_huge_note_is_bounded(tmp_path, de_run, notes):
    """A handed-over archive whose repeat carries a 5 MB note (or 500 long ones): `show`
    prints a bounded excerpt saying how much it left out (main printed all of it: a 60 MB
    note took minutes and 850 MB)."""
    import json

    import h5py

    from camopt.archive import runs

    path = tmp_path / "noted.h5"
    path.write_bytes(de_run.read_bytes())
    with h5py.File(path, "a") as f:
        for repeat in f["repeats"].values():
            repeat.attrs["notes"] = json.dumps(notes)
            repeat.attrs["message"] = "m" * 100_000
    for repeat in archive.load_run(path).repeats:
        assert 0 < len(repeat.notes) <= runs.MAX_NOTES + 1
        assert all(len(n) <= runs.NOTE_CHARS + 100 for n in repeat.notes)
        assert len(repeat.message) <= runs.NOTE_CHARS + 100
    proc = subprocess.run([*CAMOPT, "show", path], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout) < 100_000 and "characters" in proc.stdout
