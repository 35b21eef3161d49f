"""Sample archives: the draws of a tolerance analysis and what they gave, one HDF5 file
written atomically (``archive_kind = "tolerance"``).

Layout: root attributes (versions, the source run, the analysis as JSON); ``/inputs/<name>``
(n,) per varied input in its own unit; ``/metrics/<name>`` (n,) per metric; ``/g`` (n, m)
normalised constraints with the names in its ``names`` attribute; ``/feasible`` (n,)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from camopt.archive.files import atomic_write, claim, open_archive, passing_interrupt, versions
from camopt.core.documents import ToleranceDoc
from camopt.errors import ArchiveError
from camopt.mechanics import Bools, Floats

SCHEMA_VERSION = 1


def write_samples(path: str | Path, summary: Mapping[str, Any], inputs: Mapping[str, Floats],
                  metrics: Mapping[str, Floats], g: Floats, constraints: Sequence[str],
                  feasible: Bools, force: bool = False) -> Path:
    """Write a sample archive beside ``path`` and rename it into place when complete."""
    path = Path(path)

    def write(f: h5py.File) -> None:
        f.attrs.update({**versions(), "schema_version": SCHEMA_VERSION,
                        "archive_kind": "tolerance", "source_run": str(summary.get("run", "")),
                        "summary": json.dumps(summary),
                        "created": datetime.now(timezone.utc).isoformat()})
        for group, columns in (("inputs", inputs), ("metrics", metrics)):
            grp = f.create_group(group, track_order=True)
            for name, values in columns.items():
                grp.create_dataset(name, data=np.asarray(values, dtype=float))
        f.create_dataset("g", data=np.asarray(g, dtype=float))
        f["g"].attrs["names"] = json.dumps(list(constraints))
        f.create_dataset("feasible", data=np.asarray(feasible, dtype=bool))

    with claim(path, force):  # one writer per archive; never over another's file
        return atomic_write(path, write, replace=force)


@dataclass(frozen=True)
class ToleranceSamples:
    """A tolerance analysis as figures and reports read it, from a live analysis or a
    sample archive: the ``tolerance --format json`` summary, each metric's samples
    ``columns`` (n,), the normalised constraints ``g`` (n, m) named ``constraint_names``
    and ``feasible`` (n,)."""

    summary: ToleranceDoc
    columns: dict[str, Floats]
    g: Floats
    constraint_names: tuple[str, ...]
    feasible: Bools
    path: str = ""
    created: str = ""


def load_samples(path: str | Path) -> ToleranceSamples:
    """Read a sample archive (``archive_kind = "tolerance"``); anything else, or one that
    lacks its summary or datasets, is an ArchiveError naming the file."""
    with open_archive(path) as f:
        try:
            if str(f.attrs.get("archive_kind", "run")) != "tolerance":
                raise ArchiveError(f"{path}: archive: not a tolerance archive")
            summary = json.loads(str(f.attrs["summary"]))
            columns = {k: np.asarray(v[()], dtype=float) for k, v in f["metrics"].items()}
            names = tuple(json.loads(str(f["g"].attrs["names"])))
            return ToleranceSamples(summary, columns, np.asarray(f["g"][()], dtype=float),
                                    names, np.asarray(f["feasible"][()], dtype=bool),
                                    str(path), str(f.attrs.get("created", "")))
        except ArchiveError:
            raise
        except Exception as exc:  # a damaged attribute or dataset: one line, no traceback
            passing_interrupt(exc)
            raise ArchiveError(f"{path}: archive: damaged tolerance archive "
                               f"({type(exc).__name__})") from None
