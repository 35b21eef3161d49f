"""Writers under faults (issue #11): one writer per archive, nothing partial or lost on a
full disk, a kill or a signal, --out never replaces anything but a regular file."""

from __future__ import annotations

import errno
import fcntl
import os
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from camopt import archive
from camopt.archive import files
from camopt.cli import app
from camopt.errors import ArchiveError
from tests.conftest import CONFIGS

runner = CliRunner()
FAST = str(CONFIGS / "fast_switch.toml")
DE = str(CONFIGS / "fast_switch_de.toml")
CAMOPT = [sys.executable, "-m", "camopt"]


def invoke(*args):
    return runner.invoke(app, [str(a) for a in args])


def leftovers(folder):
    """Temporary and lock files a writer left in ``folder``."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_a_second_writer_fails_naming_the_holder(tmp_path):
    out = tmp_path / "a.h5"
    with archive.claim(out):
        proc = subprocess.run([*CAMOPT, "run", FAST, "--out", str(out), "--quiet"],
                              capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1
    assert f"another camopt is writing this archive (pid {os.getpid()}" in proc.stderr
    assert leftovers(tmp_path) == []


def test_a_writer_racing_a_just_started_one_names_it(tmp_path):
    """The holder writes who it is a moment after taking the lock; a second writer that
    comes in between waits for the line instead of saying 'unknown process'."""
    out = tmp_path / "a.h5"
    lock = tmp_path / ".a.h5.lock"
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    fcntl.flock(fd, fcntl.LOCK_EX)  # taken, its line not yet written
    late = threading.Timer(0.3, os.pwrite, (fd, b"pid 4242 on host since now\n", 0))
    late.start()
    try:
        with pytest.raises(ArchiveError, match=r"another camopt is writing this archive "
                                               r"\(pid 4242 on host since now\)"):
            with archive.claim(out):
                pass
    finally:
        late.join()
        os.close(fd)


def test_two_concurrent_runs_into_one_file_never_both_succeed(tmp_path):
    out = tmp_path / "same.h5"
    # long enough for the loser to find the winner's claim (or, late, its archive); the
    # polish is no subject here
    cmd = [*CAMOPT, "run", DE, "--out", str(out), "--quiet", "--set", "solver.generations=100",
           "--set", "solver.polish.maxiter=5", "--repeats", "3"]
    procs = [subprocess.Popen([*cmd, "--seed", str(i)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for i in range(2)]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2], results
    loser = next(err for code, err in results if code == 2)
    assert loser.startswith("error: ") and loser.count("\n") == 1
    assert "another camopt is writing" in loser or "exists" in loser
    winner = next(i for i, (code, _) in enumerate(results) if code == 0)
    assert archive.load_run(out).run["seed"] == winner
    assert leftovers(tmp_path) == []


def test_two_sweeps_into_one_file(tmp_path):
    out = tmp_path / "s.h5"
    with archive.claim(out):
        proc = subprocess.run([*CAMOPT, "sweep", DE, "--out", str(out), "--seeds", "0:2",
                               "--quiet", "--jobs", "1", "--set", "solver.generations=5"],
                              capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "another camopt is writing" in proc.stderr
    assert not out.exists()


def test_full_disk_leaves_the_old_archive_and_no_temporary_file(tmp_path, monkeypatch):
    out = tmp_path / "a.h5"
    assert invoke("run", FAST, "--out", out, "--quiet").exit_code == 0
    before = out.read_bytes()
    calls = []

    write = os.write

    def full(fd, data):  # the disk fills up while the archive is written
        if len(data) < 1000:
            return write(fd, data)
        calls.append(fd)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "write", full)
    r = invoke("run", FAST, "--out", out, "--quiet", "--force")
    assert calls and r.exit_code == 2
    assert r.stderr == f"error: {out}: archive: cannot write (No space left on device); " \
                       "nothing written\n"
    assert out.read_bytes() == before and leftovers(tmp_path) == []


def _fsize_limit():  # the kernel's own 'file too large' (EFBIG) on a real write
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))


def test_a_real_write_failure_is_one_line_and_no_partial_file(tmp_path):
    out = tmp_path / "a.h5"
    proc = subprocess.run([*CAMOPT, "run", FAST, "--out", str(out), "--quiet"],
                          capture_output=True, text=True, timeout=60, preexec_fn=_fsize_limit)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith(f"error: {out}: archive: cannot write (File too large)")
    assert proc.stderr.count("\n") == 1
    assert not out.exists() and leftovers(tmp_path) == []


def test_sigterm_removes_everything_half_done(tmp_path):
    out = tmp_path / "a.h5"
    proc = subprocess.Popen([*CAMOPT, "run", DE, "--out", str(out), "--quiet",
                             "--set", "solver.generations=100000", "--set", "run.repeats=50"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 30
    while not (tmp_path / ".a.h5.lock").exists() and time.time() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and err == "error: interrupted; no archive written\n"
    assert list(tmp_path.iterdir()) == []


def _interrupt_after(monkeypatch, module, name, when=lambda *a: True):
    """``module.name`` does its work, then Ctrl-C lands on the way out (its return value
    lost, as a signal handled right after a call loses it); once."""
    real = getattr(module, name)
    fired = []

    def interrupted(*args, **kwargs):
        result = real(*args, **kwargs)
        if not fired and when(*args):
            fired.append(name)
            raise KeyboardInterrupt
        return result

    monkeypatch.setattr(module, name, interrupted)


def _is_lock(path, *args):
    return str(path).endswith(".lock")


@pytest.mark.parametrize("module, name, when", [
    (os, "open", _is_lock),  # the lock file made, its descriptor lost
    (fcntl, "flock", lambda *a: True),  # locked, not yet handed back
    (files, "_try_lock", lambda *a: True),  # handed back, not yet stored
    (os, "pwrite", lambda *a: True),  # the holder's line written
], ids=["open", "flock", "return", "holder"])
def test_an_interrupt_while_locking_leaves_no_lock_file(tmp_path, monkeypatch, module, name,
                                                        when):
    """SIGTERM sent the moment the lock file appears (the test above) once left
    ``.a.h5.lock`` behind: each point of the window, interrupted in turn."""
    _interrupt_after(monkeypatch, module, name, when)
    with pytest.raises(KeyboardInterrupt), archive.claim(tmp_path / "a.h5"):
        pass
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []
    assert files._opening == {} and files._held == {}
    with archive.claim(tmp_path / "a.h5"):  # and the archive can be claimed again
        pass


def test_an_interrupt_while_failing_to_lock_leaves_the_holders_lock_file(tmp_path,
                                                                         monkeypatch):
    """A second writer interrupted as it gives up on a taken lock never removes it."""
    lock = tmp_path / ".a.h5.lock"
    lock.write_bytes(b"pid 1 on elsewhere since 2026-11-28T00:00:00+00:00\n")
    holder = os.open(lock, os.O_RDONLY)  # another writer's lock
    try:
        fcntl.flock(holder, fcntl.LOCK_EX | fcntl.LOCK_NB)
        _interrupt_after(monkeypatch, os, "close")
        with pytest.raises(KeyboardInterrupt):
            files._try_lock(tmp_path / "a.h5")
        monkeypatch.undo()
        files._release(tmp_path / "a.h5")  # what claim's cleanup would do
        assert lock.read_bytes().startswith(b"pid 1 on elsewhere")
        assert files._opening == {}
    finally:
        os.close(holder)


def _dead_temporary(target):
    """A temporary file as a camopt SIGKILLed while writing ``target`` leaves it: camopt's
    name, its lock released with the dead process."""
    fd, tmp = files._new_temporary(target)
    os.write(fd, b"partial")
    os.close(fd)  # what the kernel does when its holder dies
    return tmp


def test_stale_temporary_files_of_a_killed_writer_are_removed(tmp_path):
    stale = _dead_temporary(tmp_path / "old.h5")
    out = tmp_path / "a.h5"
    fd, live = files._new_temporary(tmp_path / "busy.h5")  # its writer is alive: kept
    try:
        proc = subprocess.run([*CAMOPT, "run", FAST, "--out", str(out), "--quiet"],
                              capture_output=True, text=True, timeout=60)
    finally:
        os.close(fd)
    assert proc.returncode == 0
    assert proc.stderr == f"note: removed {stale} (a temporary file left by a killed camopt)\n"
    assert not os.path.exists(stale) and os.path.exists(live)


# names as editors and other programs make them: '.X.<8 characters>.tmp' (vim, gedit and
# camopt before issue #30 all used this shape); camopt's own names are '.camopt-<8 hex>'
user_names = st.builds(
    lambda stem, tag: f".{stem}.{tag}.tmp",
    st.text(st.characters(min_codepoint=33, max_codepoint=0x2FF, exclude_characters="/"),
            min_size=1, max_size=20),
    st.text("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_", min_size=8,
            max_size=8))


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=user_names)
def test_the_sweeper_never_removes_a_users_temporary_file(tmp_path, name):
    """A user's file named like a temporary (an editor's autosave) survives every claim;
    a dead camopt temporary in the same folder is removed (the sweeper does run)."""
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    mine = folder / name
    mine.write_bytes(b"my notes")
    stale = _dead_temporary(folder / "old.h5")
    with archive.claim(folder / "a.h5") as held:
        assert held.stale == [Path(stale)]
    assert mine.read_bytes() == b"my notes"


def test_a_run_starting_beside_a_live_export_leaves_its_temporary_file(tmp_path, monkeypatch):
    """export/report/plot/init write through write_files: a `run` that claims an archive
    in the same folder while their temporary files wait to be published (here: between
    writing and publishing) must not remove them; the export then completes."""
    publish = files._publish
    started = []

    def run_starts_meanwhile(tmp, path, replace):
        if not started:
            started.append(True)
            with archive.claim(tmp_path / "run.h5") as held:
                assert held.stale == []
        publish(tmp, path, replace)

    monkeypatch.setattr(files, "_publish", run_starts_meanwhile)
    written = files.write_files({tmp_path / "a.csv": b"x,y\n", tmp_path / "b.csv": b"1,2\n"})
    assert [p.read_bytes() for p in written] == [b"x,y\n", b"1,2\n"]
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("target", ["/dev/null", "link"])
def test_force_replaces_only_a_regular_file(tmp_path, target):
    if target == "link":
        (tmp_path / "real.h5").write_bytes(b"x")
        (tmp_path / "link").symlink_to(tmp_path / "real.h5")
        target = tmp_path / "link"
    r = invoke("run", FAST, "--out", target, "--force", "--quiet")
    assert r.exit_code == 2 and "not a regular file" in r.stderr
    assert os.path.exists("/dev/null")


def test_force_says_what_it_replaced(tmp_path):
    out = tmp_path / "a.h5"
    out.write_text("notes")
    r = invoke("run", FAST, "--out", out, "--force", "--quiet")
    assert r.exit_code == 0
    assert r.stderr == f"note: --force: replaced {out} (a file, 5 bytes)\n"


@pytest.mark.parametrize("out", ["x" * 250 + ".h5", "missing/a.h5"])
def test_bad_out_paths_fail_before_any_work(tmp_path, out):
    r = invoke("run", DE, "--out", tmp_path / out, "--quiet")
    assert r.exit_code == 2 and r.stderr.startswith("error: ") and r.stderr.count("\n") == 1
    assert leftovers(tmp_path) == []


def test_workers_die_with_a_killed_parent(tmp_path):
    out = tmp_path / "s.h5"
    proc = subprocess.Popen([*CAMOPT, "sweep", DE, "--out", str(out), "--seeds", "0:40",
                             "--jobs", "2", "--quiet", "--set", "solver.generations=2000"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    children: list[int] = []
    deadline = time.time() + 30
    while len(children) < 2 and time.time() < deadline:
        try:
            text = open(f"/proc/{proc.pid}/task/{proc.pid}/children").read()
        except OSError:
            break
        children = [int(c) for c in text.split()]
        time.sleep(0.1)
    assert len(children) >= 2
    proc.kill()
    proc.wait(timeout=10)
    deadline = time.time() + 10
    while any(os.path.exists(f"/proc/{c}") and _alive(c) for c in children):
        assert time.time() < deadline, "pool workers outlived their parent"
        time.sleep(0.1)


def _alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().split()[2] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_archives_get_the_permissions_of_any_new_file(tmp_path, umask):
    """0666 less the umask (issue #22: they were 0600 whatever the umask)."""
    old = os.umask(umask)
    try:
        path = files.atomic_write(tmp_path / "a.h5", lambda f: f.attrs.update(x=1))
    finally:
        os.umask(old)
    assert os.stat(path).st_mode & 0o777 == 0o666 & ~umask
    assert not list(tmp_path.glob(".*.tmp"))


def test_an_archive_reads_while_its_writer_still_holds_the_lock(tmp_path, monkeypatch):
    """A reader polling a running sweep opens each snapshot the moment it is published,
    while its writer still holds the temporary file's flock on it: the open must not read
    "not HDF5" (HDF5's own shared lock failed there; a flaky sweep test showed it)."""
    path = tmp_path / "a.h5"
    seen = []
    publish = files._publish

    def publish_then_read(tmp, target, replace):
        publish(tmp, target, replace)
        with files.open_archive(target) as f:  # the writer's lock is held until after this
            seen.append(str(f.attrs["archive_kind"]))

    monkeypatch.setattr(files, "_publish", publish_then_read)
    files.atomic_write(path, lambda f: f.attrs.update(
        {"schema_version": 1, "camopt_version": "test", "archive_kind": "sweep"}))
    assert seen == ["sweep"]


def test_an_interrupt_inside_h5py_s_callbacks_is_an_interrupt_not_a_damaged_archive(
        tmp_path, monkeypatch):
    """h5py turns a KeyboardInterrupt raised in a visiting callback (a SIGTERM landing
    there) into a SystemError; the reader called the intact archive damaged and exited 2
    (a randomised run of SIGTERMs into ``camopt tolerance``). It is an interruption."""
    out = tmp_path / "a.h5"
    assert invoke("run", FAST, "--out", out, "--quiet").exit_code == 0

    def interrupted_visit(f):
        def visitor(name, *args):
            raise KeyboardInterrupt
        f.visit_links(visitor)

    monkeypatch.setattr(files, "_reaches_outside", interrupted_visit)
    with pytest.raises(KeyboardInterrupt):
        archive.open_archive(out)
    monkeypatch.undo()
    with archive.open_archive(out):  # and it is intact
        pass


def test_passing_interrupt_finds_it_anywhere_in_the_chain():
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as inner:
            raise SystemError("returned a result with an exception set") from inner
    except SystemError as exc:
        with pytest.raises(KeyboardInterrupt):
            files.passing_interrupt(exc)
    files.passing_interrupt(ValueError("a damaged attribute"))  # others pass through


def _reaches_outside_high_level(f):
    """The check as h5py's high-level objects make it (every link visited as a Link
    object, every hard-linked object opened as a Dataset or Group): the reference the
    low-level :func:`camopt.archive.files._reaches_outside` is compared with."""
    import h5py

    found = []

    def visit(name, link):
        if isinstance(link, h5py.ExternalLink):
            found.append(f"/{name}: an external link to {link.filename}")
        elif isinstance(link, h5py.HardLink):
            obj = f.get(name)
            if isinstance(obj, h5py.Dataset):
                plist = obj.id.get_create_plist()
                if plist.get_layout() == h5py.h5d.VIRTUAL:
                    found.append(f"/{name}: a virtual dataset")
                elif plist.get_external_count() > 0:
                    found.append(f"/{name}: a dataset stored in external files")
        return True if found else None

    f.visititems_links(visit)
    return found[0] if found else None


@pytest.mark.parametrize("outside", [None, "external link", "virtual", "external storage",
                                     "soft link", "deep external link"])
def test_reaches_outside_finds_what_h5py_s_objects_find(tmp_path, outside):
    """Nested groups, datasets and a soft link (inside the file: allowed), with one
    object reaching outside or none: the same answer, word for word, as the check made
    with h5py's high-level objects."""
    import h5py

    raw = tmp_path / "raw.bin"
    raw.write_bytes(b"\0" * 80)
    path = tmp_path / "a.h5"
    with h5py.File(path, "w") as f:
        f.attrs["x"] = 1
        f.create_dataset("a/b/x", data=[1.0, 2.0])
        f.create_dataset("c", data="text")
        f.create_group("d/e")
        if outside == "external link":
            f["a/ext"] = h5py.ExternalLink(str(tmp_path / "other.h5"), "/x")
        elif outside == "deep external link":
            f["d/e/zz"] = h5py.ExternalLink("ü other.h5", "/y")
        elif outside == "virtual":
            layout = h5py.VirtualLayout(shape=(10,), dtype="f8")
            layout[:] = h5py.VirtualSource(str(raw), "x", shape=(10,))
            f["a"].create_virtual_dataset("v", layout)
        elif outside == "external storage":
            f["d"].create_dataset("s", shape=(10,), dtype="f8", external=[(str(raw), 0, 80)])
        elif outside == "soft link":
            f["d/e/soft"] = h5py.SoftLink("/a/b/x")
    with h5py.File(path, "r", locking=False) as f:
        low = files._reaches_outside(f)
        assert low == _reaches_outside_high_level(f)
    assert (low is None) == (outside in (None, "soft link")), low
