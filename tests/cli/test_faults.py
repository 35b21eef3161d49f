"""Hardening round 3 (issue #23): no hang, no lost work, no write outside the output folder.

Every test here failed on main before the fix it names. Calls that hung there run in a
subprocess with a timeout, so a regression fails instead of hanging the suite."""

from __future__ import annotations

import errno
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest
from typer.testing import CliRunner

from camopt import archive
from camopt.archive import files
from camopt.archive.sweeps import cell_row, journal_path, load_sweep
from camopt.cli import app
from camopt.cli.app import INTERNAL
from camopt.engine import driver
from camopt.errors import ArchiveError
from tests.conftest import CONFIGS, ROOT

runner = CliRunner()
FAST = str(CONFIGS / "fast_switch.toml")
DE = str(CONFIGS / "fast_switch_de.toml")
EMB = str(CONFIGS / "emb.toml")
CAMOPT = [sys.executable, "-m", "camopt"]
OLDER_ARCHIVE = str(ROOT / "tests" / "data" / "archives" / "run_main_52e31ad.h5")
TINY = ["--set", "solver.generations=3", "--set", "solver.population=8",
        "--set", "solver.polish.maxiter=5"]


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def run_three_repeats_patched(patch: str, out: Path) -> subprocess.CompletedProcess[str]:
    """``camopt run`` of three tiny fast-switch repeats into ``out`` in a fresh Python
    whose modules ``patch`` (Python source, run first) has changed: a fault planted at an
    exact moment of the run."""
    script = (patch + "from camopt.cli import main\n"
              f"sys.argv = ['camopt', 'run', {DE!r}, '--out', {str(out)!r}, '--quiet',"
              f" '--repeats', '3', *{TINY!r}]\nmain()\n")
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60)


def one_error_line(text: str) -> bool:
    lines = [line for line in text.splitlines() if not line.startswith("note:")]
    return (len(lines) == 1 and lines[0].startswith("error: ") and INTERNAL not in text
            and "Traceback" not in text)


def run_all(calls: list[list[str]], timeout: float = 90) -> list[tuple[int | str, str]]:
    """Run CLI calls, two at a time (the test machine has two cores); a call still running
    after ``timeout`` s is killed and reported as 'hang' (so a hang fails the test instead
    of the suite)."""
    results: list[tuple[int | str, str]] = []
    for i in range(0, len(calls), 2):
        procs = [subprocess.Popen([*CAMOPT, *map(str, c)], stdin=subprocess.DEVNULL,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                 for c in calls[i:i + 2]]
        for p in procs:
            try:
                _, err = p.communicate(timeout=timeout)
                results.append((p.returncode, err))
            except subprocess.TimeoutExpired:
                p.kill()
                p.communicate()
                results.append(("hang", ""))
    return results


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A fast-switch run archive, an EMB run archive (it has cam profiles) and a small
    sweep archive."""
    folder = tmp_path_factory.mktemp("faults")
    fast, emb, sweep = folder / "fast.h5", folder / "emb.h5", folder / "sweep.h5"
    assert invoke("run", FAST, "--out", fast, "--quiet").exit_code == 0
    assert invoke("run", EMB, "--out", emb, "--quiet", "--set", "solver.iterations=3",
                  "--set", "solver.particles=6", "--set", "solver.polish.evaluations=48",
                  "--repeats", "2").exit_code == 0
    assert invoke("sweep", DE, "--out", sweep, "--seeds", "0:3", "--jobs", "1", "--quiet",
                  *TINY).exit_code == 0
    return fast, emb, sweep


def copy(src, dst):
    dst.write_bytes(src.read_bytes())
    return dst


# ---- hangs: only regular files are read ------------------------------------------------
def test_a_fifo_as_a_sweeps_journal_is_refused_by_every_reader(runs, tmp_path):
    sweep = copy(runs[2], tmp_path / "s.h5")
    os.mkfifo(journal_path(sweep))
    calls = [["show", sweep], ["compare", sweep], ["report", sweep, "--out", tmp_path / "r.html"],
             ["plot", sweep, "--out", tmp_path / "p"], ["sweep", "--resume", sweep, "--jobs", "1"]]
    for call, (code, err) in zip(calls, run_all(calls)):
        assert code == 2 and one_error_line(err), (call, code, err)
        assert "not a regular file" in err, (call, err)


def test_an_archive_linking_outside_itself_is_refused(runs, tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    run = copy(runs[0], tmp_path / "r.h5")
    with h5py.File(run, "a") as f:
        f["analysis/evil"] = h5py.ExternalLink(str(fifo), "/x")
    calls = [["show", run], ["export", run, "--out", tmp_path / "e"],
             ["report", run, "--out", tmp_path / "r.html"], ["plot", run, "--out", tmp_path / "p"],
             ["tolerance", run, "--samples", "50"], ["compare", run, run]]
    for call, (code, err) in zip(calls, run_all(calls)):
        assert code == 2 and one_error_line(err), (call, code, err)
        assert "external link" in err, (call, err)


@pytest.mark.parametrize("kind", ["virtual", "external storage"])
def test_datasets_stored_outside_the_archive_are_refused(runs, tmp_path, kind):
    run = copy(runs[0], tmp_path / "r.h5")
    raw = tmp_path / "raw.bin"
    raw.write_bytes(b"\0" * 80)
    with h5py.File(run, "a") as f:
        if kind == "virtual":
            layout = h5py.VirtualLayout(shape=(10,), dtype="f8")
            layout[:] = h5py.VirtualSource(str(raw), "x", shape=(10,))
            f["analysis"].create_virtual_dataset("v", layout)
        else:
            f["analysis"].create_dataset("e", shape=(10,), dtype="f8",
                                         external=[(str(raw), 0, 80)])
    with pytest.raises(ArchiveError, match="virtual|external files"):
        archive.load_run(run)


def test_export_into_a_fifo_fails_at_once_and_leaves_it(runs, tmp_path):
    out = tmp_path / "e"
    out.mkdir()
    fifo = out / f"{runs[0].stem}-summary.csv"
    os.mkfifo(fifo)
    [(code, err)] = run_all([["export", runs[0], "--out", out]], timeout=90)
    assert code == 2 and one_error_line(err) and "not a regular file" in err, (code, err)
    assert [p.name for p in out.iterdir()] == [fifo.name]


@pytest.mark.parametrize("plant", ["fifo", "directory"])
def test_force_onto_a_fifo_or_directory_at_the_output_name_fails_at_once(tmp_path, plant):
    """The corpus's two hangs: with --force, run and sweep described the file they were
    about to replace by opening it with HDF5 before checking it is a regular file (a
    FIFO blocked that open; the first fix then met a directory with an internal error)."""
    run_out, sweep_out = tmp_path / "a.h5", tmp_path / "s.h5"
    for p in (run_out, sweep_out):
        os.mkfifo(p) if plant == "fifo" else p.mkdir()
    calls = [["run", FAST, "--out", run_out, "--quiet", "--force"],
             ["sweep", DE, "--out", sweep_out, "--seeds", "0:1", "--jobs", "1", "--quiet",
              "--force", *TINY]]
    for call, (code, err) in zip(calls, run_all(calls, timeout=40)):
        assert code == 2 and one_error_line(err), (call, code, err)
        assert ("not a regular file" if plant == "fifo" else "is a directory") in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.h5", "s.h5"]
    assert all(p.is_fifo() if plant == "fifo" else p.is_dir() for p in tmp_path.iterdir())


# ---- writes where they must not ----------------------------------------------------------
@pytest.mark.parametrize("command", ["export", "plot"])
def test_export_and_plot_never_overwrite_without_force(runs, tmp_path, command):
    run = runs[1]
    first = invoke(command, run, "--out", tmp_path)
    assert first.exit_code == 0, first.output
    written = sorted(p for p in tmp_path.iterdir())
    for p in written:
        p.write_text("mine")
    again = invoke(command, run, "--out", tmp_path)
    assert again.exit_code == 2 and one_error_line(again.stderr), again.output
    assert "pass --force" in again.stderr
    assert all(p.read_text() == "mine" for p in written)
    assert invoke(command, run, "--out", tmp_path, "--force").exit_code == 0
    assert all(p.read_text() != "mine" for p in written if p.suffix != ".png")
    assert sorted(p for p in tmp_path.iterdir()) == written  # no temporary file left


@pytest.mark.parametrize("command", ["export", "plot"])
@pytest.mark.parametrize("force", [[], ["--force"]])
def test_export_and_plot_never_write_through_a_symlink(runs, tmp_path, command, force):
    outside = tmp_path / "outside.txt"
    outside.write_text("precious")
    out = tmp_path / "out"
    out.mkdir()
    name = f"{runs[1].stem}-summary.csv" if command == "export" else \
        f"{runs[1].stem}-convergence.png"
    (out / name).symlink_to(outside)
    r = invoke(command, runs[1], "--out", out, *force)
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert outside.read_text() == "precious" and (out / name).is_symlink()
    assert [p.name for p in out.iterdir()] == [name]  # all or nothing


@pytest.mark.parametrize("call", [
    ["tolerance", "{run}", "--samples", "20", "--out", "{run}", "--force"],
    ["report", "{run}", "--out", "{run}", "--force"],
    ["run", "{case}", "--out", "{case}", "--force", "--quiet"],
    ["sweep", "{case}", "--out", "{case}", "--force", "--quiet", "--seeds", "0:1"],
])
def test_force_never_replaces_the_commands_own_input(runs, tmp_path, call):
    run = copy(runs[0], tmp_path / "in.h5")
    case = tmp_path / "case.toml"
    case.write_text((CONFIGS / "fast_switch.toml").read_text())
    before = run.read_bytes(), case.read_bytes()
    r = invoke(*[a.format(run=run, case=case) for a in call])
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "own input" in r.stderr
    assert (run.read_bytes(), case.read_bytes()) == before


@pytest.mark.parametrize("command, old", [("plot", "in-convergence.png"),
                                          ("export", "in-summary.csv")])
def test_force_in_the_inputs_folder_replaces_only_the_commands_own_outputs(runs, tmp_path,
                                                                           command, old):
    """The decision of docs/reliability.md section 6: an output folder may hold the input
    (export's default folder is the archive's own); --force there replaces the names the
    command writes, nothing else, and never the input."""
    run = copy(runs[0], tmp_path / "in.h5")
    notes = tmp_path / "notes.txt"
    notes.write_text("the user's")
    (tmp_path / old).write_text("an earlier output")
    before = run.read_bytes()
    assert invoke(command, run, "--out", tmp_path).exit_code == 2  # exists: needs --force
    r = invoke(command, run, "--out", tmp_path, "--force")
    assert r.exit_code == 0, r.output
    assert (tmp_path / old).read_bytes() != b"an earlier output"
    assert run.read_bytes() == before and notes.read_text() == "the user's"


def test_export_whose_output_name_is_its_input_is_refused_even_with_force(runs, tmp_path):
    run = copy(runs[0], tmp_path / "in.json")  # an archive named like export's JSON output
    before = run.read_bytes()
    r = invoke("export", run, "--format", "json", "--out", tmp_path, "--force")
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "own input" in r.stderr and run.read_bytes() == before


def _fsize_limit():  # the kernel's own 'file too large' (EFBIG) on a real write
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (3000, 3000))


def test_export_on_a_full_disk_leaves_no_truncated_file(runs, tmp_path):
    out = tmp_path / "e"
    out.mkdir()
    proc = subprocess.run([*CAMOPT, "export", runs[1], "--out", out], capture_output=True,
                          text=True, timeout=60, preexec_fn=_fsize_limit)
    assert proc.returncode == 2 and one_error_line(proc.stderr), proc.stderr
    assert "nothing written" in proc.stderr
    assert list(out.iterdir()) == []


def test_export_with_enospc_mid_file_leaves_nothing(runs, tmp_path, monkeypatch):
    write, calls = os.write, []

    def full(fd, data):  # the third file fills the disk
        calls.append(fd)
        if len(calls) >= 3:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return write(fd, data)

    monkeypatch.setattr(files.os, "write", full)
    r = invoke("export", runs[1], "--out", tmp_path / "e")
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "No space left on device" in r.stderr
    assert not (tmp_path / "e").exists()  # the folder export made is removed (issue #30)


def test_an_unreachable_dask_scheduler_leaves_nothing_behind(tmp_path, monkeypatch):
    from camopt.engine import sweep as sweep_run

    monkeypatch.setattr(sweep_run, "CONNECT_TIMEOUT", "2s", raising=False)
    r = invoke("sweep", DE, "--out", tmp_path / "d.h5", "--executor", "dask", "--scheduler",
               "tcp://127.0.0.1:1", "--seeds", "0:1", "--quiet", *TINY)
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "cannot reach the Dask scheduler" in r.stderr
    assert list(tmp_path.iterdir()) == []


# ---- wrong results: journal lines tied to their sweep --------------------------------------
def _journal_line(results, **change):
    row = cell_row(next(iter(results.values())))
    row.update(change)
    return (json.dumps(row) + "\n").encode()


@pytest.mark.parametrize("line", ["foreign", "point true", "seed string", "x of strings"])
def test_journal_lines_of_another_sweep_or_the_wrong_type_are_refused(runs, tmp_path, line):
    sweep = copy(runs[2], tmp_path / "s.h5")
    spec, results = load_sweep(sweep)
    change = {"foreign": {}, "point true": {"point": True}, "seed string": {"seed": "1"},
              "x of strings": {"x": ["a"]}}[line]
    # a line as another sweep's journal (or an older camopt) wrote it: no sweep id
    journal_path(sweep).write_bytes(_journal_line(results, **change))
    r = invoke("sweep", "--resume", sweep, "--jobs", "1", "--quiet")
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    if line != "foreign":  # with this sweep's id, the types are checked
        row = json.loads(_journal_line(results, **change))
        row["sweep"] = spec.sweep_id
        journal_path(sweep).write_bytes((json.dumps(row) + "\n").encode())
        with pytest.raises(ArchiveError, match="not a"):
            load_sweep(sweep)


def test_a_journal_line_of_this_sweep_is_kept(runs, tmp_path):
    sweep = copy(runs[2], tmp_path / "s.h5")
    spec, results = load_sweep(sweep)
    row = json.loads(_journal_line(results, objective=-1.0))
    row["sweep"] = spec.sweep_id
    journal_path(sweep).write_bytes((json.dumps(row) + "\n").encode())
    assert min(r.fun for r in load_sweep(sweep)[1].values()) == -1.0


# ---- wrong results: BLAS threads ------------------------------------------------------------
def test_evaluation_runs_blas_on_one_thread_whatever_the_process_had():
    from threadpoolctl import threadpool_info, threadpool_limits

    from tests.helpers import load

    with threadpool_limits(limits=2, user_api="blas"):
        driver.prepare(load(DE))
        threads = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    assert threads and set(threads) == {1}


def test_a_sweep_gives_the_same_cells_with_one_or_the_default_blas_threads(tmp_path):
    calls, env = [], []
    for threads in ("1", None):
        e = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
        if threads:
            e["OPENBLAS_NUM_THREADS"] = threads
        env.append(e)
        calls.append([*CAMOPT, "sweep", DE, "--out", tmp_path / f"{threads}.h5", "--seeds",
                      "0:2", "--jobs", "1", "--quiet", "--set", "solver.generations=20",
                      "--set", "solver.population=20"])
    procs = [subprocess.Popen(list(map(str, c)), env=e, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE) for c, e in zip(calls, env)]
    assert all(p.wait(timeout=120) == 0 for p in procs)
    one, default = (load_sweep(tmp_path / f"{t}.h5")[1] for t in ("1", None))
    assert {k: (r.fun, r.x.tolist()) for k, r in one.items()} == \
        {k: (r.fun, r.x.tolist()) for k, r in default.items()}


# ---- lost work ----------------------------------------------------------------------------
def _wait_for_line(path: Path, timeout: float = 120) -> None:
    """Until ``path`` holds a complete line (an event another process records)."""
    deadline = time.monotonic() + timeout
    while not (path.exists() and b"\n" in path.read_bytes()):
        assert time.monotonic() < deadline, f"nothing recorded in {path}"
        time.sleep(0.02)


def test_a_dying_worker_of_run_jobs_keeps_the_finished_repeats(tmp_path, monkeypatch):
    """The worker of repeat 3 dies once the parent has collected a finished repeat (an
    observed event, recorded by the parent in ``collected``; a fixed sleep before the
    kill failed on a loaded machine when no repeat had finished yet)."""
    original, collected = driver.run_repeat, tmp_path / "collected"
    real_as_completed = driver.as_completed

    def recording(futures):  # the parent: a line once the loop body took the record
        for fut in real_as_completed(futures):
            yield fut
            with collected.open("a") as f:
                f.write("repeat\n")

    def dying(problem, solver_cls, config, child, index, *args, **kwargs):
        if index == 3:  # the OOM killer takes this worker (after a repeat is collected)
            _wait_for_line(collected)
            os.kill(os.getpid(), signal.SIGKILL)
        return original(problem, solver_cls, config, child, index, *args, **kwargs)

    monkeypatch.setattr(driver, "run_repeat", dying)  # forked workers inherit it
    monkeypatch.setattr(driver, "as_completed", recording)
    out = tmp_path / "a.h5"
    r = invoke("run", DE, "--out", out, "--quiet", "--repeats", "6", "--jobs", "2", *TINY)
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "worker process died" in r.stderr and "kept the" in r.stderr
    kept = list([r.index for r in archive.load_run(out).repeats])
    assert 1 <= len(kept) < 6 and 3 not in kept
    with h5py.File(out) as f:
        assert bool(f.attrs["interrupted"]) and f.attrs["repeats_done"] == len(kept)


def test_a_dying_sweep_worker_keeps_the_finished_cells(tmp_path, monkeypatch):
    from camopt.archive.sweeps import journal_path
    from camopt.engine import sweep as sweep_run

    original = sweep_run.run_cell
    out = tmp_path / "s.h5"

    def dying(cell, *args):
        if cell.seed == 3:  # dies once a finished cell is in the sweep's journal
            _wait_for_line(journal_path(out))
            os.kill(os.getpid(), signal.SIGKILL)
        return original(cell, *args)

    monkeypatch.setattr(sweep_run, "run_cell", dying)
    r = invoke("sweep", DE, "--out", out, "--seeds", "0:6", "--jobs", "2", "--quiet", *TINY)
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "worker process died" in r.stderr
    assert 1 <= len(load_sweep(out)[1]) < 6


@pytest.mark.parametrize("signals", [(signal.SIGINT, signal.SIGINT)])
def test_ctrl_c_during_the_final_write_keeps_the_archive(tmp_path, monkeypatch, signals):
    from camopt.archive import runs

    original = runs.atomic_write

    def interrupted(*args, **kwargs):  # Ctrl-C, then again because the first seemed slow
        for s in signals:
            os.kill(os.getpid(), s)
        return original(*args, **kwargs)

    monkeypatch.setattr(runs, "atomic_write", interrupted)
    out = tmp_path / "a.h5"
    r = invoke("run", DE, "--out", out, "--quiet", "--repeats", "3", *TINY)
    assert r.exit_code == 130, r.output
    assert one_error_line(r.stderr) and "kept all 3 finished of 3 repeats" in r.stderr
    assert len([r.index for r in archive.load_run(out).repeats]) == 3


def test_sigterm_then_ctrl_c_during_the_final_write_keep_the_archive(tmp_path):
    out = tmp_path / "a.h5"
    script = (
        "import os, signal, sys\n"
        "from camopt.archive import runs\n"
        "original = runs.atomic_write\n"
        "def interrupted(*a, **k):\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    return original(*a, **k)\n"
        "runs.atomic_write = interrupted\n"
    )
    proc = run_three_repeats_patched(script, out)
    assert proc.returncode == 130 and one_error_line(proc.stderr), proc.stderr
    assert len([r.index for r in archive.load_run(out).repeats]) == 3


def test_sigterm_while_the_command_loads_is_exit_130_and_one_line(tmp_path):
    """A SIGTERM landing after the handlers are in place but while the command's modules
    still load (a randomised stress run hit it: the process died by SIGINT, Python's exit
    for an uncaught KeyboardInterrupt, instead of exit 130)."""
    out = tmp_path / "a.h5"
    script = (
        "import os, signal, sys\n"
        "from camopt import cli\n"
        "original = cli.load_commands\n"
        "def loading(args):\n"
        "    os.kill(os.getpid(), signal.SIGTERM)\n"
        "    return original(args)\n"
        "cli.load_commands = loading\n"
    )
    proc = run_three_repeats_patched(script, out)
    assert proc.returncode == 130 and one_error_line(proc.stderr), (proc.returncode,
                                                                     proc.stderr)
    assert list(tmp_path.iterdir()) == []


def test_a_finished_command_ignores_signals_while_python_exits(tmp_path):
    """Once a command is over (its output written, or its error reported) SIGINT and
    SIGTERM are ignored: Python's finalisation restores their default actions, and a
    randomised run of signals saw a finished ``report`` killed by SIGTERM there (exit
    -15, the HTML whole). That moment cannot be hit from Python code, so the state
    main() leaves is checked, for a command that succeeds and one that fails."""
    script = (
        "import signal, sys\n"
        "from camopt.cli import main\n"
        "sys.argv = ['camopt', *sys.argv[1:]]\n"
        "try:\n"
        "    main()\n"
        "except SystemExit as exc:\n"
        "    code = exc.code\n"
        "print(code, signal.getsignal(signal.SIGTERM) is signal.SIG_IGN,\n"
        "      signal.getsignal(signal.SIGINT) is signal.SIG_IGN)\n"
    )
    for args, code in ((["export", OLDER_ARCHIVE, "--out", str(tmp_path / "export")], "0"),
                       (["show", str(tmp_path / "missing.h5")], "2")):
        proc = subprocess.run([sys.executable, "-c", script, *args], capture_output=True,
                              text=True, timeout=60)
        assert proc.stdout.split()[-3:] == [code, "True", "True"], (proc.stdout, proc.stderr)
    assert [p for p in (tmp_path / "export").iterdir() if p.stat().st_size > 0]


def validate_with_import_fault(where: str, nth: int, fault: str
                               ) -> subprocess.CompletedProcess[str]:
    """``camopt validate`` of the fast switch in a fresh Python whose ``nth`` import of
    module ``where`` first runs ``fault`` (Python source, indented 12 spaces): a signal
    or a library's error planted at an exact moment of the command's own imports."""
    script = (
        "import builtins, os, signal, sys\n"
        "real = builtins.__import__\n"
        "seen = []\n"
        "def importing(name, *a, **k):\n"
        f"    if name == {where!r}:\n"
        "        seen.append(name)\n"
        f"        if len(seen) == {nth}:\n"
        f"{fault}"
        "    return real(name, *a, **k)\n"
        "from camopt.cli import main\n"
        "builtins.__import__ = importing\n"
        f"sys.argv = ['camopt', 'validate', {FAST!r}]\n"
        "main()\n"
    )
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60)


def test_a_signal_typer_turns_into_a_silent_exit_is_reported_as_one_line():
    """A KeyboardInterrupt leaving a command's own imports, before its errors() block, is
    caught by typer and turned into a silent exit 130: camopt now says so in one line (a
    randomised run of SIGTERMs into ``camopt tolerance`` exited 130 with nothing said)."""
    proc = validate_with_import_fault("camopt.engine.targets", 1,
                                      "            os.kill(os.getpid(), signal.SIGTERM)\n")
    assert proc.returncode == 130 and proc.stderr == "error: interrupted\n", (
        proc.returncode, proc.stderr)


@pytest.mark.parametrize("where, nth, said", [
    ("camopt.engine.targets", 1, "error: interrupted\n"),  # a command's own imports
    # validate imports it first outside its errors() block, then in load_case inside it
    ("camopt.engine.setup", 2, "error: interrupted; no archive written\n"),
])
def test_a_library_s_error_for_an_interrupt_inside_it_is_an_interruption(where, nth, said):
    """An extension module interrupted during its initialisation raises ImportError
    ('initialization failed') with the KeyboardInterrupt as its context: camopt called it
    an internal error, exit 2 (an early signal into ``plot``). It is an interruption."""
    proc = validate_with_import_fault(where, nth, (
        "            try:\n"
        "                raise KeyboardInterrupt\n"
        "            except KeyboardInterrupt:\n"
        "                raise ImportError('initialization failed')\n"))
    assert proc.returncode == 130 and proc.stderr == said, (proc.returncode, proc.stderr)


# ---- unbounded or unwrapped -----------------------------------------------------------------
def test_a_second_ctrl_c_while_exiting_after_the_first_changes_nothing(tmp_path):
    """The corpus's 'other' exits: Ctrl-C once a repeat finished, then Ctrl-C again
    landing after camopt reported the first (here while Python exits): the second went
    to camopt's handler in an exit callback (a traceback) or, once Python had removed
    its handlers, killed the process by SIGINT instead of exit 130."""
    out = tmp_path / "a.h5"
    script = (
        "import atexit, os, signal, sys\n"
        "from camopt.engine import driver\n"
        "original = driver.run_repeat\n"
        "def first_ctrl_c(*a, **k):\n"
        "    if a[4] == 1:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "    return original(*a, **k)\n"
        "driver.run_repeat = first_ctrl_c\n"
        "atexit.register(lambda: os.kill(os.getpid(), signal.SIGINT))  # the second\n"
    )
    proc = run_three_repeats_patched(script, out)
    assert proc.returncode == 130 and one_error_line(proc.stderr), proc.stderr
    assert "kept the 1 finished of 3 repeats" in proc.stderr
    assert [r.index for r in archive.load_run(out).repeats] == [0]


def test_sweep_jobs_never_starts_more_workers_than_cells(tmp_path, monkeypatch):
    from camopt.engine import sweep as sweep_run

    asked = []
    real = sweep_run.fork_pool

    def recording(jobs):
        asked.append(jobs)
        return real(min(jobs, 2))  # never fork hundreds here, even on a regression

    monkeypatch.setattr(sweep_run, "fork_pool", recording)
    r = invoke("sweep", DE, "--out", tmp_path / "s.h5", "--seeds", "0:4", "--jobs", "1000",
               "--quiet", *TINY)
    assert r.exit_code == 0, r.output
    assert asked and max(asked) <= 4
    assert sweep_run.workers(1000, 10**6) <= sweep_run.WORKERS_PER_CORE * (os.cpu_count() or 1)


@pytest.mark.parametrize("seeds", ["9" * 5000, "0:" + "9" * 5000, "1" * 4301 + ":2"])
def test_seeds_with_thousands_of_digits_are_one_line(tmp_path, seeds):
    r = invoke("sweep", DE, "--out", tmp_path / "s.h5", "--seeds", seeds, "--quiet")
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert len(r.stderr) < 300 and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("target", ["file", "fifo", "unwritable"])
def test_tolerance_plot_into_a_file_fifo_or_unwritable_folder_is_one_line(runs, tmp_path,
                                                                           target):
    path = tmp_path / "p"
    if target == "file":
        path.write_text("x")
    elif target == "fifo":
        os.mkfifo(path)
    else:
        path = "/proc/camopt-plots"  # not even root can create a folder there
    [(code, err)] = run_all([["tolerance", runs[0], "--samples", "50", "--plot", path]],
                            timeout=60)
    assert code == 2 and one_error_line(err), (code, err)
    assert "--plot" in err


# ---- a Dask cluster losing its workers -------------------------------------------------------
@pytest.fixture
def dask_cluster():
    """A LocalCluster's scheduler on 127.0.0.1 with two worker processes of its own kind
    but nanny-less (``dask worker --no-nanny``): a killed worker stays dead, as on a node
    the OOM killer visited, instead of being restarted by a nanny."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=0, processes=True, host="127.0.0.1",
                                  dashboard_address=":0") as cluster:
        workers = [subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", cluster.scheduler_address,
             "--no-nanny", "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for _ in range(2)]
        try:
            with distributed.Client(cluster.scheduler_address, timeout="30s") as client:
                client.wait_for_workers(2, timeout=60)
            yield cluster.scheduler_address, workers
        finally:
            for w in workers:
                w.kill()
                w.wait(timeout=10)


def test_the_dask_watchdog_asks_the_scheduler_not_a_stale_copy(dask_cluster, monkeypatch):
    """The draft's false "no worker": the client's cached cluster identity is refreshed in
    the background without its worker list; when the watchdog's own fetch failed (an
    identity call timing out on a loaded machine) it read that copy and saw no worker
    while two ran."""
    import distributed

    from camopt.engine.sweep import _cluster_trouble

    address, _ = dask_cluster
    with distributed.Client(address, timeout="30s") as client:
        client.sync(client._update_scheduler_info)  # what the background refresh does

        async def timed_out(**kwargs):
            raise OSError("timed out")

        monkeypatch.setattr(client.scheduler, "identity", timed_out, raising=False)
        assert _cluster_trouble(client) is None


@pytest.mark.slow
def test_a_dask_sweep_survives_a_killed_worker_and_resumes_after_losing_all(
        dask_cluster, tmp_path, monkeypatch):
    """The worker holding the first finished batch SIGKILLed before the batch is fetched
    (its result lost: Dask runs it again): the sweep goes on on the other worker, and its
    cells are those of an inline sweep. The last worker killed once a cell is stored: one
    error line naming --resume within seconds (LOST_SECONDS shortened; the watchdog still
    needs LOST_CHECKS checks in a row), exit 2, the finished cells kept, and ``sweep
    --resume`` finishes them into the inline sweep's cells."""
    import distributed

    from camopt.archive.sweeps import SweepWriter
    from camopt.engine import sweep as sweep_run

    address, workers = dask_cluster
    monkeypatch.setattr(sweep_run, "LOST_SECONDS", 2.0)
    args = ["sweep", DE, "--seeds", "0:8", "--quiet", *TINY]
    assert invoke(*args, "--out", tmp_path / "inline.h5", "--jobs", "1").exit_code == 0
    inline = load_sweep(tmp_path / "inline.h5")[1]

    def same_cells(results):
        return {k: (r.fun, r.x.tolist()) for k, r in results.items()} == \
            {k: (r.fun, r.x.tolist()) for k, r in inline.items()}

    def kill(pid):
        [victim] = [w for w in workers if w.pid == pid]
        victim.kill()
        victim.wait(timeout=10)

    wait, lost_batches = distributed.wait, []

    def wait_then_kill_the_holder(futures, **kwargs):
        finished, pending = wait(futures, **kwargs)
        if finished and not lost_batches:
            first = next(iter(finished))
            holder = first.client.who_has([first])[first.key][0]
            kill(first.client.run(os.getpid)[holder])
            deadline = time.monotonic() + 20
            while first.status == "finished" and time.monotonic() < deadline:
                time.sleep(0.05)  # until the scheduler has told the client it is lost
            lost_batches.append(first.status)
        return finished, pending

    monkeypatch.setattr(distributed, "wait", wait_then_kill_the_holder)
    dask = [*args, "--executor", "dask", "--scheduler", address]
    r = invoke(*dask, "--out", tmp_path / "one.h5")
    assert lost_batches == ["lost"], lost_batches
    assert r.exit_code == 0, r.output
    assert sorted(w.poll() is None for w in workers) == [False, True]
    assert same_cells(load_sweep(tmp_path / "one.h5")[1])
    monkeypatch.setattr(distributed, "wait", wait)

    add = SweepWriter.add

    def add_then_kill_the_last(self, r):
        add(self, r)
        for w in workers:
            if w.poll() is None:
                kill(w.pid)

    monkeypatch.setattr(SweepWriter, "add", add_then_kill_the_last)
    lost = tmp_path / "none.h5"
    t0 = time.monotonic()
    r = invoke(*dask, "--out", lost)
    assert r.exit_code == 2 and one_error_line(r.stderr), r.output
    assert "lost the Dask cluster (no worker" in r.stderr and "--resume" in r.stderr
    assert time.monotonic() - t0 < 30
    assert 1 <= len(load_sweep(lost)[1]) < 8
    assert not any(p.name.endswith((".tmp", ".lock")) for p in tmp_path.iterdir())
    r = invoke("sweep", "--resume", lost, "--jobs", "1", "--quiet")
    assert r.exit_code == 0, r.output
    assert same_cells(load_sweep(lost)[1])


@pytest.mark.slow
def test_a_dask_sweep_whose_scheduler_is_killed_ends_in_one_line_and_resumes(
        tmp_path, monkeypatch):
    """The scheduler SIGKILLed once a cell is stored (a scheduler process of its own, on
    127.0.0.1, with one nanny-less worker): one error line naming --resume, exit 2, no
    traceback nor distributed's FutureCancelledError, the finished cells kept, and
    ``sweep --resume`` finishes them into the inline sweep's cells."""
    pytest.importorskip("distributed")
    from camopt.archive.sweeps import SweepWriter
    from camopt.engine import sweep as sweep_run

    monkeypatch.setattr(sweep_run, "LOST_SECONDS", 2.0)
    info = tmp_path / "scheduler.json"
    common = ["--scheduler-file", str(info), "--no-dashboard"]
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                               "--host", "127.0.0.1", "--port", "0", *common],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() or not info.read_text().strip().endswith("}"):
            assert time.monotonic() < deadline, "the scheduler did not start"
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", "--no-nanny", "--nthreads",
             "1", "--host", "127.0.0.1", *common],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        import distributed

        with distributed.Client(address, timeout="30s") as client:
            client.wait_for_workers(1, timeout=60)
        args = ["sweep", DE, "--seeds", "0:6", "--quiet", *TINY]
        assert invoke(*args, "--out", tmp_path / "inline.h5", "--jobs", "1").exit_code == 0
        inline = load_sweep(tmp_path / "inline.h5")[1]
        add = SweepWriter.add

        def add_then_kill_the_scheduler(self, r):
            add(self, r)
            if procs[0].poll() is None:
                procs[0].kill()
                procs[0].wait(timeout=10)

        monkeypatch.setattr(SweepWriter, "add", add_then_kill_the_scheduler)
        out = tmp_path / "s.h5"
        t0 = time.monotonic()
        r = invoke(*args, "--out", out, "--executor", "dask", "--scheduler", address)
        assert r.exit_code == 2 and one_error_line(r.stderr), r.output
        assert "lost the Dask cluster" in r.stderr and "--resume" in r.stderr, r.stderr
        assert "Traceback" not in r.output and "FutureCancelled" not in r.output
        assert time.monotonic() - t0 < 40
        assert 1 <= len(load_sweep(out)[1]) < 6
        monkeypatch.setattr(SweepWriter, "add", add)
        r = invoke("sweep", "--resume", out, "--jobs", "1", "--quiet")
        assert r.exit_code == 0, r.output
        assert {k: (x.fun, x.x.tolist()) for k, x in load_sweep(out)[1].items()} == \
            {k: (x.fun, x.x.tolist()) for k, x in inline.items()}
    finally:
        for p in procs:
            p.kill()
            p.wait(timeout=10)
