"""Calibration archives: a ``camopt calibrate`` run, one HDF5 file written atomically
(``archive_kind = "calibration"``), under the same rules as run archives (one writer per
file, built in memory, moved into place when complete, never over an existing file
without ``force``: :mod:`camopt.archive.files`).

Layout: root attributes (versions, ``schema_version``, ``case_kind``, ``config_toml`` the
case file's text, ``summary`` the ``calibrate --format json`` document, ``report`` the
text report's lines as JSON, ``created``); ``/curves/<k>`` per form and curve with datasets
``time_s``, ``measured_m``, ``fitted_m`` (m,) and attributes ``form``, ``source``,
``design``."""

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
from camopt.core.calibration import FittedCurve
from camopt.errors import ArchiveError

SCHEMA_VERSION = 1
KIND = "calibration"


def write_calibration(path: str | Path, summary: Mapping[str, Any], lines: Sequence[str],
                      curves: Sequence[FittedCurve], case_kind: str, config_toml: str,
                      force: bool = False) -> Path:
    """Write a calibration archive at ``path`` (atomically; an existing file only with
    ``force``): the JSON ``summary``, the report's ``lines``, every fitted curve, the case's
    kind and file text."""
    path = Path(path)

    def write(f: h5py.File) -> None:
        f.attrs.update({**versions(), "schema_version": SCHEMA_VERSION, "archive_kind": KIND,
                        "case_kind": case_kind, "config_toml": config_toml,
                        "summary": json.dumps(summary), "report": json.dumps(list(lines)),
                        "created": datetime.now(timezone.utc).isoformat()})
        grp = f.create_group("curves", track_order=True)
        for k, c in enumerate(curves):
            g = grp.create_group(f"{k:04d}")
            g.attrs.update({"form": c.form, "source": c.source, "design": c.design})
            for name in ("time_s", "measured_m", "fitted_m"):
                g.create_dataset(name, data=np.asarray(getattr(c, name), dtype=float))

    with claim(path, force):  # one writer per archive; never over another's file
        return atomic_write(path, write, replace=force)


@dataclass(frozen=True)
class CalibrationView:
    """A calibration archive as ``show``, ``plot`` and ``report`` read it: the JSON
    ``summary`` (``calibrate --format json``), the text report's ``lines``, the fitted
    ``curves``, the case's kind and file text, when it was written and its path."""

    summary: dict[str, Any]
    lines: tuple[str, ...]
    curves: tuple[FittedCurve, ...]
    case_kind: str
    config_toml: str
    created: str
    path: str


def load_calibration(path: str | Path) -> CalibrationView:
    """Read a calibration archive; anything else, or one that lacks its summary or
    curves, is an ArchiveError naming the file."""
    with open_archive(path) as f:
        try:
            if str(f.attrs.get("archive_kind", "run")) != KIND:
                raise ArchiveError(f"{path}: archive: not a calibration archive")
            summary = json.loads(str(f.attrs["summary"]))
            lines = json.loads(str(f.attrs["report"]))
            if not isinstance(summary, dict) or not isinstance(lines, list):
                raise ValueError("summary or report")
            curves = tuple(
                FittedCurve(str(g.attrs["form"]), str(g.attrs["source"]),
                            str(g.attrs["design"]),
                            *(np.asarray(g[n][()], dtype=float)
                              for n in ("time_s", "measured_m", "fitted_m")))
                for g in f["curves"].values())
            return CalibrationView(summary, tuple(str(x) for x in lines), curves,
                                   str(f.attrs["case_kind"]), str(f.attrs["config_toml"]),
                                   str(f.attrs.get("created", "")), str(path))
        except ArchiveError:
            raise
        except Exception as exc:  # a damaged attribute or dataset: one line, no traceback
            passing_interrupt(exc)
            raise ArchiveError(f"{path}: archive: damaged calibration archive "
                               f"({type(exc).__name__})") from None
