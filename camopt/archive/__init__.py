"""HDF5 archives (h5py only): run archives, sweep archives, their files and tables.

The names below are loaded from their modules on first use (PEP 562), so a command that
reads no archive (``validate`` resolving no archive reference) does not import h5py."""

from __future__ import annotations

from typing import TYPE_CHECKING

from camopt.lazy import lazy_names

if TYPE_CHECKING:
    from camopt.archive.files import (
        Claim,
        archive_kind,
        atomic_write,
        check_not_input,
        check_writable,
        claim,
        default_path,
        describe_file,
        ensure_folder,
        open_archive,
        output_folder,
        read_regular,
        versions,
        write_files,
    )
    from camopt.archive.references import resolve_references
    from camopt.archive.runs import load_run, write_run
    from camopt.archive.tables import read_table, write_table

_HOME = {
    **dict.fromkeys(("Claim", "archive_kind", "atomic_write", "check_not_input",
                     "check_writable", "claim", "default_path", "describe_file",
                     "ensure_folder", "open_archive", "output_folder", "read_regular", "versions",
                     "write_files"), "files"),
    "resolve_references": "references",
    "load_run": "runs", "write_run": "runs",
    "read_table": "tables", "write_table": "tables",
}

__all__ = ["Claim", "archive_kind", "atomic_write", "check_not_input", "check_writable", "claim",
           "default_path", "describe_file", "ensure_folder", "load_run", "open_archive",
           "output_folder", "read_regular", "read_table", "resolve_references", "versions",
           "write_files", "write_run", "write_table"]
assert sorted(__all__) == sorted(_HOME)


__getattr__ = lazy_names(globals(), _HOME)
