"""Sample archives: the draws of a tolerance analysis and what they gave, one HDF5 file
written atomically (``archive_kind = "tolerance"``).

Layout: root attributes (versions, the source run, the analysis as JSON); ``/inputs/<name>``
(n,) per varied input in its own unit; ``/metrics/<name>`` (n,) per metric; ``/g`` (n, m)
normalised constraints with the names in its ``names`` attribute; ``/feasible`` (n,)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from numpy.typing import NDArray

from camopt.archive.files import atomic_write, claim, versions

SCHEMA_VERSION = 1


def write_samples(path: str | Path, summary: Mapping[str, Any], inputs: Mapping[str, NDArray],
                  metrics: Mapping[str, NDArray], g: NDArray, constraints: Sequence[str],
                  feasible: NDArray, force: bool = False) -> Path:
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
