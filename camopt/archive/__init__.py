"""HDF5 archives (h5py only): run archives, sweep archives, their files and tables."""

from __future__ import annotations

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

__all__ = ["Claim", "archive_kind", "atomic_write", "check_not_input", "check_writable", "claim",
           "default_path", "describe_file", "ensure_folder", "load_run", "open_archive",
           "output_folder", "read_regular", "read_table", "resolve_references", "versions",
           "write_files", "write_run", "write_table"]
