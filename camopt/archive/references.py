"""Case-file values taken from other run archives (e.g. VCB step 2's step-1 cam).

Generic: the case's spec says which values and how (``CaseSpec.resolve``); this module
finds and reads the archives, relative to the working folder or else to the case file's
folder, and turns a missing or foreign archive into bad input against the key.

:func:`camopt.archive.runs.load_run` is imported where used (that module imports this one)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

from camopt.cases import get_case
from camopt.config import LoadedConfig
from camopt.errors import ArchiveError, ConfigError

if TYPE_CHECKING:  # a case that refers to no archive needs no run records
    from camopt.core.runview import RunView


def resolve_references(config: LoadedConfig) -> LoadedConfig:
    """``config`` with every archive reference of its case filled in."""
    spec = get_case(config.case.kind)
    if spec.resolve is None:
        return config

    case = spec.resolve(config.case, _Loader(config.path))
    return config if case is config.case else dataclasses.replace(config, case=case)


class _Loader:
    """The :class:`~camopt.cases.registry.ArchiveLoader` of one case file: archives and
    other input files relative to the working folder, else to the case file's folder."""

    def __init__(self, case_path: str) -> None:
        self.case_path = case_path

    def _find(self, ref: str) -> Path:
        path = Path(ref)
        if not path.is_file() and (Path(self.case_path).parent / ref).is_file():
            path = Path(self.case_path).parent / ref
        return path

    def __call__(self, key: str, ref: str) -> RunView:
        from camopt.archive.runs import load_run  # h5py only for a case that refers

        try:
            return load_run(self._find(ref))
        except ArchiveError as exc:
            raise ConfigError(self.case_path, key, str(exc)) from None

    def locate(self, key: str, ref: str) -> Path:
        path = self._find(ref)
        if not path.exists():  # a FIFO or device: its reader says what it is
            raise ConfigError(self.case_path, key, f"{ref}: no such file (looked in the "
                              "working folder and beside the case file)")
        return path
