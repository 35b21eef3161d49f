"""Archive files: where they go, atomic writes, opening for reading."""

from __future__ import annotations

import os
import platform
import tempfile
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

import camopt
from camopt.errors import ArchiveError


def default_path(name: str, out_dir: str | Path = "runs") -> Path:
    """``runs/<name>-<UTC timestamp>.h5``."""
    stamp = datetime.now(timezone.utc).strftime("%Y%m%dT%H%M%S%fZ")
    return Path(out_dir) / f"{name}-{stamp}.h5"


def check_writable(path: Path, force: bool) -> None:
    """Fail before any work if ``path`` exists (without force) or its folder is not writable."""
    if path.exists() and not force:
        raise ArchiveError(f"{path}: --out: exists; pass --force to overwrite")
    if path.is_dir():
        raise ArchiveError(f"{path}: --out: is a directory")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise ArchiveError(f"{path}: --out: folder {folder} does not exist")
    try:  # a real probe: os.access says yes to root even where writing fails
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".camopt-probe-")
    except OSError as exc:
        raise ArchiveError(f"{path}: --out: folder {folder} is not writable "
                           f"({exc.strerror})") from None
    os.close(fd)
    os.unlink(probe)


def versions() -> dict[str, str]:
    """Library versions recorded in every archive's root attributes."""
    import scipy

    return {"camopt_version": camopt.__version__, "python_version": platform.python_version(),
            "numpy_version": np.__version__, "scipy_version": scipy.__version__,
            "h5py_version": h5py.__version__}


def atomic_write(path: Path, write: Callable[[h5py.File], None]) -> Path:
    """Call ``write(h5py.File)`` on a temporary file beside ``path``, then rename it into
    place: readers see the old complete file or the new one, never a partial one."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def open_archive(path: str | Path) -> h5py.File:
    """Open an archive read-only; anything else is an ArchiveError naming the file."""
    path = Path(path)
    if not path.is_file():
        raise ArchiveError(f"{path}: file: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise ArchiveError(f"{path}: file: not a camopt archive (not HDF5)") from None
    if "schema_version" not in f.attrs or "camopt_version" not in f.attrs:
        f.close()
        raise ArchiveError(f"{path}: file: not a camopt archive (no camopt attributes)")
    return f


def archive_kind(path: str | Path) -> str:
    """'run' or 'sweep'."""
    with open_archive(path) as f:
        return str(f.attrs.get("archive_kind", "run"))
