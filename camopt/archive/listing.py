"""``camopt runs``: the archives in a folder, one row each, from their attributes only (no
dataset is read, so a folder of large archives lists quickly)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TypedDict

from camopt.archive.files import open_archive, passing_interrupt
from camopt.errors import ArchiveError


class _ArchiveRow(TypedDict):
    path: str
    archive: str
    case: str
    verdict: str
    objective: float | None
    created: str


class ArchiveRow(_ArchiveRow, total=False):
    """One archive of a folder (``runs --format json``): its path, kind (``run``,
    ``sweep``, ``calibration``, ``tolerance``; ``?`` unreadable), case, verdict, best
    objective and creation date; a run's ``feasible`` and ``objective_name``; and what
    ``camopt runs`` adds from the requirements (``verdict_grade``, ``expected_yield``,
    ``yield_target``)."""

    feasible: bool
    objective_name: str
    verdict_grade: str | None
    expected_yield: float | None
    yield_target: float | None


def describe(path: Path) -> ArchiveRow:
    """One archive as ``{path, archive, case, verdict, objective, created}`` (and a run's
    ``objective_name``): ``verdict``
    is the best design's ``feasible``/``infeasible`` for a run, ``N/M cells`` for a sweep;
    an unreadable file is a row whose verdict says why (a listing never stops at one)."""
    row: ArchiveRow = {"path": str(path), "archive": "?", "case": "-", "verdict": "-",
                           "objective": None, "created": "-"}
    try:
        with open_archive(path) as f:
            attrs = f.attrs
            kind = str(attrs.get("archive_kind", "run"))
            row.update({"archive": kind, "created": str(attrs.get("created", "-"))})
            if kind == "run":
                best = f["best"].attrs
                row.update({"case": str(attrs["case_kind"]), "feasible": bool(best["feasible"]),
                            "verdict": "feasible" if bool(best["feasible"]) else "infeasible",
                            "objective": float(best["objective"]),
                            "objective_name": str(attrs["objective_name"])})
                if bool(attrs.get("interrupted", False)):
                    row["verdict"] += " (interrupted)"
            elif kind == "calibration":
                summary = json.loads(str(attrs["summary"]))
                row.update({"case": str(attrs["case_kind"]),
                            "verdict": "kept: " + (", ".join(summary.get("kept_forms", []))
                                                   or "none")})
            elif kind == "sweep":
                spec = json.loads(str(attrs["spec"]))
                row.update({"case": str(spec["data"]["case"]["kind"]),
                            "verdict": f"{int(attrs['cells_done'])}/"
                                       f"{int(attrs['cells_total'])} cells"})
    except ArchiveError as exc:
        row["verdict"] = str(exc).split(": ", 1)[-1]
    except Exception as exc:  # a damaged attribute or group: listed, not fatal
        passing_interrupt(exc)
        row["verdict"] = f"damaged ({type(exc).__name__})"
    return row


def list_archives(folder: Path) -> list[ArchiveRow]:
    """Every ``*.h5`` in ``folder`` (not its sub-folders), newest first by ``created`` (then
    by name); a missing folder is an ArchiveError."""
    if not folder.is_dir():
        raise ArchiveError(f"{folder}: folder: no such folder")
    rows = [describe(p) for p in sorted(folder.glob("*.h5")) if p.is_file()]
    rows.sort(key=lambda r: r["path"])
    rows.sort(key=lambda r: r["created"], reverse=True)
    return rows
