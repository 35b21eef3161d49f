"""Export a run's summary and analysis curves as CSV or JSON, and cam profiles as point
files (x, y, z in mm, one point per line) that CAD tools import as curves."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from camopt import report
from camopt.cases import get_case
from camopt.runview import RunView


def _series(analysis: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(analysis[k]) for k in keys])


def export_run(run: RunView, out_dir: Path, stem: str, fmt: str) -> list[Path]:
    """Write the export files; returns their paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    analysis = run.analysis
    doc = report.show(run)
    written = []
    if fmt == "json":
        path = out_dir / f"{stem}.json"
        doc["analysis"] = {k: report.jsonable(np.asarray(v).tolist()) for k, v in analysis.items()}
        path.write_text(json.dumps(doc, indent=2))
        written.append(path)
    else:
        path = out_dir / f"{stem}-summary.csv"
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["section", "name", "value"])
            w.writerow(["best", "objective", doc["best"]["objective"]])
            w.writerow(["best", "feasible", doc["best"]["feasible"]])
            for section in ("x", "metrics"):
                for k, v in doc["best"][section].items():
                    w.writerow([section, k, json.dumps(v) if isinstance(v, list) else v])
        written.append(path)
        groups: dict[int, list[str]] = {}
        for k, v in analysis.items():
            groups.setdefault(np.asarray(v).size, []).append(k)
        for i, (_, keys) in enumerate(sorted(groups.items())):
            path = out_dir / f"{stem}-curves-{i + 1}.csv"
            with path.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(keys)
                w.writerows(np.column_stack([np.asarray(analysis[k]) for k in keys]).tolist())
            written.append(path)
    for curve in get_case(run.kind).profiles:
        if not all(k in analysis for k in (*curve.x, *curve.y)):
            continue
        x, y = _series(analysis, curve.x), _series(analysis, curve.y)
        ok = np.isfinite(x) & np.isfinite(y)
        path = out_dir / f"{stem}-{curve.name}.txt"
        np.savetxt(path, np.column_stack([x[ok], y[ok], np.zeros(ok.sum())]), fmt="%.6f",
                   delimiter=",")
        written.append(path)
    return written
