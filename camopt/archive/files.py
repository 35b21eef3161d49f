"""Archive files: where they go, one writer per archive, atomic writes, opening for reading.

Writing an archive (``claim`` then ``atomic_write``):

- One writer per archive: ``claim`` takes an exclusive ``flock`` on ``.<name>.lock``
  beside the archive for as long as the writer works; a second writer fails at once with
  an error naming the holder (pid, host, start time). The kernel drops the lock when its
  holder dies, so a killed writer never blocks the next one.
- Nothing half-written: the archive is built in memory (h5py on a ``BytesIO``), written to
  a temporary file ``.<name>.camopt-<random>.tmp`` beside the target with plain ``os.write``
  (a full disk is an ``OSError`` there, never inside HDF5), synced, and moved into
  place. Without ``force`` the move is a hard link, which fails rather than replace a
  file another program made meanwhile; with ``force`` only a regular file is replaced.
- Temporary files are removed on errors and on SIGINT/SIGTERM (the CLI turns SIGTERM into
  KeyboardInterrupt); those a SIGKILL leaves are removed by the next ``claim`` in that
  folder. Every temporary file (archives, and the files of ``export``, ``report``,
  ``plot`` and ``init``) carries a name only camopt makes (``.camopt-`` and 8 hex digits
  before ``.tmp``) and is held under an exclusive ``flock`` of its own from its creation
  until it is moved into place or removed; the sweeper removes only a file with such a
  name whose lock it can take (its writer is dead). A user's ``.notes.abcd1234.tmp`` (an
  editor's autosave) is never touched, nor a live writer's temporary file of any command.

scipy (its version, written once per archive) and the config loader are imported where used:
reading an archive starts without them.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import io
import os
import platform
import re
import secrets
import socket
import stat
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import BinaryIO

import h5py
import numpy as np

import camopt
from camopt.errors import ArchiveError, ConfigError, from_interrupt

# the temporary file's name adds 21 bytes and a leading dot to the archive's name, and a
# file name has at most 255 bytes
MAX_NAME_BYTES = 200
# a temporary file's name: only camopt makes '.camopt-<8 hex>.tmp' (docs/reliability.md)
_TMP = re.compile(r"\.(?P<target>.+)\.camopt-[0-9a-f]{8}\.tmp")
HOLDER_WAIT_S = 2.0
"""How long a second writer waits for a just-started holder to write who it is."""
_held: dict[Path, int] = {}  # archives this process holds locked -> lock file descriptor
_opening: dict[str, int] = {}  # lock files this process made -> descriptor (-1: not yet known)


def passing_interrupt(exc: BaseException) -> None:
    """Raise KeyboardInterrupt if ``exc`` came of one: h5py turns a Ctrl-C or SIGTERM
    (raised as KeyboardInterrupt) landing in its callbacks into a SystemError whose
    context is the interrupt, and a reader's ``except Exception`` then called an intact
    archive damaged (a randomised run of SIGTERMs into ``camopt tolerance``). Call first
    in every ``except Exception`` around h5py."""
    if from_interrupt(exc):
        raise KeyboardInterrupt from None


def default_path(name: str, out_dir: str | Path = "runs") -> Path:
    """``runs/<name>-<UTC timestamp>.h5`` (``name`` is a safe run name: no separators)."""
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S%fZ")
    return Path(out_dir) / f"{name}-{stamp}.h5"


def _folder(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def check_writable(path: Path, force: bool, key: str = "--out") -> None:
    """Fail before any work if ``path`` exists (without force), is not a regular file (even
    with force), has an over-long name, or its folder is not writable; ``key`` the option
    the messages name."""
    if "\0" in str(path):
        raise ArchiveError(f"{path!r}: {key}: contains a NUL byte")
    if len(path.name.encode()) > MAX_NAME_BYTES:
        raise ArchiveError(f"{path}: {key}: file name longer than {MAX_NAME_BYTES} bytes (its "
                           "temporary file beside it must fit the 255-byte limit)")
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        info = None
    except OSError as exc:
        raise ArchiveError(f"{path}: {key}: {exc.strerror}") from None
    if info is not None:
        if stat.S_ISDIR(info.st_mode):
            raise ArchiveError(f"{path}: {key}: is a directory")
        if not stat.S_ISREG(info.st_mode):
            raise ArchiveError(f"{path}: {key}: exists and is not a regular file (a link, "
                               f"device or FIFO); {key} replaces only a regular file")
        if not force:
            raise ArchiveError(f"{path}: {key}: exists; pass --force to overwrite")
    folder = _folder(path)
    if not folder.is_dir():
        raise ArchiveError(f"{path}: {key}: folder {folder} does not exist")
    _probe(folder, f"{path}: {key}")


def _probe(folder: Path, where: str) -> None:
    """A real probe (``os.access`` says yes to root even where writing fails): a file
    without a name (``O_TMPFILE``), so a signal can leave nothing behind; where the file
    system cannot make one, a named file removed at once."""
    try:
        os.close(os.open(folder, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o600))
        return
    except OSError as exc:
        if exc.errno not in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL):
            raise ArchiveError(f"{where}: folder {folder} is not writable "
                               f"({exc.strerror})") from None
    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".camopt-probe-")
    except OSError as exc:
        raise ArchiveError(f"{where}: folder {folder} is not writable "
                           f"({exc.strerror})") from None
    os.close(fd)
    os.unlink(probe)


def _lock_path(path: Path) -> Path:
    return _folder(path) / f".{path.name}.lock"


def _try_lock(path: Path) -> int | None:
    """Lock ``path``'s lock file; its descriptor, or None when another process holds it.

    The descriptor is noted in :data:`_opening` the moment ``os.open`` returns it, before
    anything a signal could interrupt, so :func:`_release` (in :func:`claim`'s ``finally``)
    removes the lock file this process made whenever Ctrl-C or SIGTERM lands: while it is
    being made, locked, or handed back (a return value is lost to an exception raised on
    the way out of a call; the note is not)."""
    lock = _lock_path(path)
    key = str(lock)
    while True:
        _opening[key] = -1  # a file may exist before its descriptor is known
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW
                     | os.O_NONBLOCK, 0o644)
        _opening[key] = fd
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # a FIFO or device planted there
            del _opening[key]
            os.close(fd)
            raise ArchiveError(f"{path}: --out: its lock file {lock} is not a regular "
                               "file; remove it")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            del _opening[key]  # another writer's: never removed by this one
            os.close(fd)
            return None
        try:  # the file may have been unlinked by its last holder after we opened it
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return fd
        del _opening[key]
        os.close(fd)


def _release(path: Path) -> None:
    """Remove ``path``'s lock file if this process made or holds it, and close it. Unlinked
    before unlocking: see :func:`_try_lock`'s inode check. A lock file whose descriptor a
    signal lost (``-1``) is removed only if nobody holds it."""
    lock = _lock_path(path)
    fd = _opening.pop(str(lock), None)
    if fd is None:
        return
    if fd < 0:
        try:
            fd = os.open(lock, os.O_RDONLY | os.O_CLOEXEC | os.O_NOFOLLOW | os.O_NONBLOCK)
        except OSError:
            return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # already held: kept; else taken
        if os.stat(lock, follow_symlinks=False).st_ino == os.fstat(fd).st_ino:
            os.unlink(lock)
    except OSError:  # held by another writer, or gone
        pass
    finally:
        os.close(fd)


def _holder(path: Path) -> str:
    """Who holds ``path``'s lock, as its holder wrote it. A holder that has just taken the
    lock writes its line a moment later: an empty lock file is read again for up to
    :data:`HOLDER_WAIT_S` before the holder is called unknown."""
    deadline = time.monotonic() + HOLDER_WAIT_S
    while True:
        try:
            text = (read_regular(_lock_path(path), "lock") or b"").decode().strip()
        except (OSError, UnicodeDecodeError):
            return "unknown process"
        if text or time.monotonic() >= deadline:
            return text or "unknown process"
        time.sleep(0.02)


@dataclass
class Claim:
    """An archive path held for writing; ``stale`` lists temporary files it removed."""

    path: Path
    force: bool
    stale: list[Path] = field(default_factory=list)


@contextlib.contextmanager
def claim(path: Path, force: bool = False) -> Iterator[Claim]:
    """Hold ``path`` for writing: checks (``check_writable``), then an exclusive lock that
    a second writer fails on, naming this one; stale temporary files in the folder are
    removed. Re-entrant within one process."""
    path = Path(path)
    key = Path(os.path.abspath(path))
    if key in _held:
        yield Claim(path, force)
        return
    check_writable(path, force)
    try:  # from before the lock file exists: whatever interrupts, _release cleans up
        try:
            fd = _try_lock(path)
        except ArchiveError:
            raise
        except OSError as exc:
            raise ArchiveError(f"{path}: --out: cannot create its lock file "
                               f"({exc.strerror})") from None
        if fd is None:
            raise ArchiveError(f"{path}: --out: another camopt is writing this archive "
                               f"({_holder(path)})")
        started = datetime.now(timezone.utc).isoformat(timespec="seconds")
        try:  # who holds it, for the error a second writer gets (best effort: disk full);
            # written over a dead holder's line before truncating, so never read empty
            line = f"pid {os.getpid()} on {socket.gethostname()} since {started}\n".encode()
            os.pwrite(fd, line, 0)
            os.ftruncate(fd, len(line))
        except OSError:
            pass
        _held[key] = fd
        check_writable(path, force)  # again under the lock: a writer may have just finished
        yield Claim(path, force, remove_stale(_folder(path)))
    finally:
        _held.pop(key, None)
        _release(path)


def remove_stale(folder: Path) -> list[Path]:
    """Remove camopt's temporary files in ``folder`` whose writer is dead (a SIGKILL left
    them): a name only camopt makes (:data:`_TMP`) and a lock nobody holds (every writer
    holds its temporary file's ``flock`` until it is published or removed). Anything else,
    a user's ``.X.abcd1234.tmp`` among them, is left alone. The paths removed."""
    removed: list[Path] = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        if not _TMP.fullmatch(name):
            continue
        tmp = folder / name
        try:
            fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
        except OSError:
            continue
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):
                continue
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:  # its writer is alive
                continue
            if os.stat(tmp, follow_symlinks=False).st_ino != os.fstat(fd).st_ino:
                continue  # replaced meanwhile: not the file we locked
            os.unlink(tmp)  # under the lock: its creator checks the name after locking
            removed.append(tmp)
        except OSError:
            pass
        finally:
            os.close(fd)
    return removed


def versions() -> dict[str, str]:
    """Library versions recorded in every archive's root attributes."""
    import scipy

    return {"camopt_version": camopt.__version__, "python_version": platform.python_version(),
            "numpy_version": np.__version__, "scipy_version": scipy.__version__,
            "h5py_version": h5py.__version__}


def atomic_write(path: Path, write: Callable[[h5py.File], None], replace: bool = True
                 ) -> Path:
    """Call ``write(h5py.File)`` on an in-memory file, write its bytes to a temporary file
    beside ``path`` and move that into place: readers see the old complete file or the
    new one, never a partial one. ``replace=False`` never replaces an existing file;
    ``replace=True`` replaces only a regular file. Any failure (a full disk included) is an
    ArchiveError with the temporary file removed."""
    path = Path(path)
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        write(f)
    data = buffer.getbuffer()
    held: tuple[int, str] | None = None
    try:
        held = _write_temp(path, data)
        _publish(Path(held[1]), path, replace)
        os.close(held[0])
        held = None
    except OSError as exc:
        if isinstance(exc, ArchiveError):
            raise
        raise ArchiveError(f"{path}: archive: cannot write ({exc.strerror or exc}); "
                           "nothing written") from None
    finally:
        if held is not None:
            _discard(held)
    return path


def _discard(held: tuple[int, str]) -> None:
    """Remove a temporary file, then release its lock (in that order: see remove_stale)."""
    with contextlib.suppress(OSError):
        os.unlink(held[1])
    with contextlib.suppress(OSError):
        os.close(held[0])


def temporary_name(path: Path) -> Path:
    """A fresh name ``.<name>.camopt-<8 hex>.tmp`` beside ``path``: a name only camopt
    makes, the one kind :func:`remove_stale` may remove."""
    return _folder(path) / f".{path.name}.camopt-{secrets.token_hex(4)}.tmp"


def _new_temporary(path: Path) -> tuple[int, str]:
    """A new file (:func:`temporary_name`, ``O_EXCL``) beside ``path``, open for writing and
    held under an exclusive ``flock`` until its descriptor is closed, with the permissions
    any new file gets (0666 less the umask; mkstemp's 0600 would keep the archive from the
    user's group). A sweeper that took the lock between the creation and ours has removed
    the name: the name is checked under the lock and another one made."""
    folder = _folder(path)
    for _ in range(100):
        tmp = temporary_name(path)
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
        except FileExistsError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)  # a sweeper holds it for a moment at most
            if os.stat(tmp, follow_symlinks=False).st_ino == os.fstat(fd).st_ino:
                return fd, str(tmp)
        except FileNotFoundError:
            pass
        except BaseException:
            _discard((fd, str(tmp)))
            raise
        os.close(fd)
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(folder))


def _write_temp(path: Path, data: bytes | memoryview) -> tuple[int, str]:
    """``data`` in a new, synced temporary file beside ``path`` (:func:`_new_temporary`;
    plain ``os.write``: a full disk is an OSError): its still locked descriptor and its
    name, for the caller to publish and then close (:func:`_discard` on failure). Removed
    on failure."""
    fd, tmp = _new_temporary(path)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
        os.fsync(fd)
    except BaseException:
        _discard((fd, tmp))
        raise
    return fd, tmp


def ensure_folder(folder: Path, key: str = "--out") -> Path:
    """``folder`` made if missing; a file, FIFO or device of that name, or a folder that
    cannot be made, is an ArchiveError naming ``key`` (checked before any work)."""
    _make_folder(Path(folder), key)
    return Path(folder)


def _make_folder(folder: Path, key: str) -> list[Path]:
    """:func:`ensure_folder`'s work; the folders it made, deepest first."""
    if os.path.lexists(folder) and not folder.is_dir():
        raise ArchiveError(f"{folder}: {key}: exists and is not a folder")
    missing = []
    level = folder
    while not os.path.lexists(level) and level != level.parent:
        missing.append(level)
        level = level.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ArchiveError(f"{folder}: {key}: cannot create the folder "
                           f"({exc.strerror})") from None
    try:
        _probe(folder, f"{folder}: {key}")
    except BaseException:
        _remove_empty(missing)
        raise
    return missing


def _remove_empty(folders: Sequence[Path]) -> None:
    for made in folders:  # deepest first; one another program filled stays
        with contextlib.suppress(OSError):
            os.rmdir(made)


@contextlib.contextmanager
def output_folder(folder: Path, key: str = "--out") -> Iterator[Path]:
    """:func:`ensure_folder` for a command's output files: when the command then fails (a
    full disk, Ctrl-C, bad input found later), the folders it made are removed again if
    still empty, so a failed ``plot --out p`` leaves no empty ``p/``."""
    made = _make_folder(Path(folder), key)
    try:
        yield Path(folder)
    except BaseException:
        _remove_empty(made)
        raise


def write_files(contents: dict[Path, bytes], force: bool = False,
                inputs: Sequence[Path] = ()) -> list[Path]:
    """Write several output files (plots, exports) all or nothing. Each target is checked
    first (``check_writable``: never over an existing file without ``force``, never a
    link, FIFO or device, even with it; never one of ``inputs``), every file is written
    to a temporary file beside it and synced (a full disk fails here, before anything is
    published), then moved into place (``_publish``: a hard link without ``force``). On
    any failure the temporary files and the files this call already published are
    removed: no truncated or partial set is left. The paths written."""
    for path in contents:
        check_writable(path, force)
        check_not_input(path, inputs)
    temps: dict[Path, tuple[int, str]] = {}
    published: list[Path] = []
    try:
        for path, data in contents.items():
            temps[path] = _write_temp(path, data)
        for path, (_, tmp) in temps.items():
            _publish(Path(tmp), path, force)
            published.append(path)
    except BaseException as exc:  # KeyboardInterrupt too: nothing half-done stays
        for held in temps.values():
            _discard(held)
        if not force:  # without --force every published file is new: ours to remove
            for path in published:
                with contextlib.suppress(OSError):
                    os.unlink(path)
        if isinstance(exc, OSError) and not isinstance(exc, ArchiveError):
            where = exc.filename or next(iter(contents), "")
            raise ArchiveError(f"{where}: --out: cannot write ({exc.strerror or exc}); "
                               "nothing written") from None
        raise
    for fd, _ in temps.values():  # published: release the temporary files' locks
        os.close(fd)
    return published


def _publish(tmp: Path, path: Path, replace: bool) -> None:
    if replace:
        with contextlib.suppress(FileNotFoundError):
            if not stat.S_ISREG(os.lstat(path).st_mode):
                raise ArchiveError(f"{path}: --out: is not a regular file; not replaced")
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)  # fails if path exists: never replaces what another writer made
    except FileExistsError:
        raise ArchiveError(f"{path}: --out: a file appeared there while camopt was "
                           "working; not replaced (pass --force to replace it)") from None
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EXDEV, errno.EMLINK):
            raise
        if os.path.lexists(path):  # a file system without hard links
            raise ArchiveError(f"{path}: --out: exists; not replaced") from None
        os.replace(tmp, path)
        return
    os.unlink(tmp)


def describe_file(path: Path) -> str | None:
    """'a camopt run archive, 12345 bytes' for an existing regular file (what --force
    replaces); None for anything else. Looked at through a descriptor opened without
    following a link and without blocking, checked with ``fstat`` first: a FIFO planted at
    the output name (which ``claim`` then refuses) must not block this note on open."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOFOLLOW | os.O_CLOEXEC)
    except (OSError, ValueError):
        return None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):  # a directory opens too, and fdopen refuses it
            return None
        with os.fdopen(fd, "rb", closefd=False) as handle:
            return f"{_kind_of(handle)}, {info.st_size} bytes"
    finally:
        os.close(fd)


def _kind_of(handle: BinaryIO) -> str:
    """'a camopt sweep archive', 'an HDF5 file' or 'a file' for an open regular file."""
    try:
        with h5py.File(handle, "r", locking=False) as f:
            kind = f"a camopt {f.attrs.get('archive_kind', 'run')} archive" if (
                "camopt_version" in f.attrs) else "an HDF5 file"
    except Exception as exc:  # anything h5py cannot open is simply 'a file'
        passing_interrupt(exc)
        kind = "a file"
    return kind


def open_archive(path: str | Path) -> h5py.File:
    """Open an archive read-only; anything else is an ArchiveError naming the file. Only a
    regular file is opened, and one whose objects reach outside it (external links, virtual
    or externally stored datasets: HDF5 would open those files, a FIFO among them, and
    block) is refused."""
    path = Path(path)
    try:
        info = os.stat(path)
    except (OSError, ValueError):
        raise ArchiveError(f"{path}: file: no such file") from None
    if not stat.S_ISREG(info.st_mode):
        raise ArchiveError(f"{path}: file: not a regular file")
    try:
        # No HDF5 file lock: an archive is never changed in place (atomic_write replaces
        # it whole), and its writer keeps the exclusive flock of its temporary file on the
        # published file until it closes it, so HDF5's shared lock would fail for that
        # moment and a reader polling a running sweep would read "not HDF5".
        f = h5py.File(path, "r", locking=False)
    except OSError:
        raise ArchiveError(f"{path}: file: not a camopt archive (not HDF5)") from None
    try:
        ok = "schema_version" in f.attrs and "camopt_version" in f.attrs
    except Exception as exc:  # a damaged attribute table
        passing_interrupt(exc)
        ok = False
    if not ok:
        f.close()
        raise ArchiveError(f"{path}: file: not a camopt archive (no camopt attributes)")
    try:
        outside = _reaches_outside(f)
    except Exception as exc:  # a damaged link table
        f.close()
        passing_interrupt(exc)
        raise ArchiveError(f"{path}: archive: damaged or incomplete: its objects cannot "
                           "be listed") from None
    if outside:
        f.close()
        raise ArchiveError(f"{path}: archive: {outside}; camopt reads only what the file "
                           "itself holds")
    return f


def _reaches_outside(f: h5py.File) -> str | None:
    """The first object of ``f`` that would make HDF5 open another file: an external
    link, a virtual dataset or a dataset stored in external raw files (None if none).
    Links are visited without being followed; h5py's low-level calls (link info, an
    object opened by its hard link) ask each link what a high-level ``Dataset`` would,
    without building one per link (a quarter of ``show``'s archive reading); a link of
    a kind h5py does not know is an error, as h5py's own ``get(getlink=True)`` raises."""
    found: list[str] = []
    links = f.id.links

    def visit(name: bytes) -> bool | None:
        kind = links.get_info(name).type
        if kind == h5py.h5l.TYPE_EXTERNAL:
            filename, _ = links.get_val(name)
            found.append(f"/{_name(name)}: an external link to {os.fsdecode(filename)}")
        elif kind == h5py.h5l.TYPE_HARD:
            try:
                obj = h5py.h5o.open(f.id, name)
            except KeyError:  # as h5py's get(): none there; what reads it says so
                obj = None
            if isinstance(obj, h5py.h5d.DatasetID):
                plist = obj.get_create_plist()
                if plist.get_layout() == h5py.h5d.VIRTUAL:
                    found.append(f"/{_name(name)}: a virtual dataset")
                elif plist.get_external_count() > 0:
                    found.append(f"/{_name(name)}: a dataset stored in external files")
        elif kind != h5py.h5l.TYPE_SOFT:  # a soft link names an object of this file
            raise TypeError(f"unknown link type {kind}")
        return True if found else None  # a non-None value stops the visit

    links.visit(visit)
    return found[0] if found else None


def _name(name: bytes) -> str:
    """An HDF5 link name as h5py shows it: UTF-8 text, else its bytes' repr."""
    try:
        return name.decode("utf-8")
    except UnicodeDecodeError:
        return str(name)


MAX_SIDE_FILE_BYTES = 2**30
"""Largest journal or lock file read (bytes): a journal line is a cell's result, at most
a few kB, and a sweep at most 100,000 cells (``sweep/spec.py``); a device or a runaway
file is refused before it fills memory."""


def read_regular(path: Path, what: str) -> bytes | None:
    """The bytes of the regular file ``path`` (None if there is none): the shared check of
    every input (:func:`camopt.config.loader.read_regular_file`), without following a
    symbolic link. A FIFO, device, directory or link put there is an ArchiveError naming
    ``what``, never a hang."""
    from camopt.config.loader import read_regular_file

    try:
        return read_regular_file(path, what, MAX_SIDE_FILE_BYTES, f"a {what} file",
                                 follow=False)
    except ConfigError as exc:
        if exc.what == "no such file":
            return None
        remedy = "; remove it" if "regular file" in exc.what or "directory" in exc.what \
            else ""
        raise ArchiveError(f"{path}: {what}: {exc.what}{remedy}") from None


def same_file(a: Path, b: Path) -> bool:
    """True when ``a`` and ``b`` name the same existing file (links resolved)."""
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def check_not_input(target: Path, inputs: Sequence[Path], key: str = "--out") -> None:
    """An output that is one of the command's own inputs is refused, with or without
    ``--force`` (``tolerance RUN --out RUN --force`` would destroy what it reads)."""
    for source in inputs:
        if same_file(target, source):
            raise ArchiveError(f"{target}: {key}: is this command's own input {source}; "
                               "choose another name")


KINDS = ("run", "sweep", "tolerance", "calibration")


def archive_kind(path: str | Path) -> str:
    """'run', 'sweep', 'tolerance' or 'calibration'."""
    with open_archive(path) as f:
        try:
            kind = str(f.attrs.get("archive_kind", "run"))
        except Exception as exc:
            passing_interrupt(exc)
            kind = "?"
    if kind not in KINDS:
        raise ArchiveError(f"{path}: archive: unknown archive_kind {kind!r}")
    return kind

