"""Case-file values taken from other run archives (e.g. VCB step 2's step-1 cam).

Generic: the case's spec says which values and how (``CaseSpec.resolve``); this module
finds and reads the archives, relative to the working folder or else to the case file's
folder, and turns a missing or foreign archive into bad input against the key."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from camopt.cases import get_case
from camopt.config import LoadedConfig
from camopt.core.runview import RunView
from camopt.errors import ArchiveError, ConfigError


def resolve_references(config: LoadedConfig) -> LoadedConfig:
    """``config`` with every archive reference of its case filled in."""
    spec = get_case(config.case.kind)
    if spec.resolve is None:
        return config

    def load(key: str, ref: str) -> RunView:
        from camopt.archive.runs import load_run  # h5py only for a case that refers

        path = Path(ref)
        if not path.is_file() and (Path(config.path).parent / ref).is_file():
            path = Path(config.path).parent / ref
        try:
            return load_run(path)
        except ArchiveError as exc:
            raise ConfigError(config.path, key, str(exc)) from None

    case = spec.resolve(config.case, load)
    return config if case is config.case else dataclasses.replace(config, case=case)
