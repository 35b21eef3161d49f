"""Export a run's summary and analysis curves as CSV or JSON, cam profiles as point files
(x, y, z in mm, one point per line) that CAD tools import as curves, and the profiles with
their base circle and roller as a DXF drawing (ezdxf)."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from camopt.cases import get_case
from camopt.core.runview import RunView
from camopt.errors import ConfigError
from camopt.reporting import report

FORMATS = ("csv", "json", "dxf")


def _series(analysis: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(analysis[k]) for k in keys])


def export_run(run: RunView, out_dir: Path, stem: str, fmt: str, force: bool = False,
               inputs: tuple[Path, ...] = ()) -> list[Path]:
    """Write the export files (``fmt`` one of :data:`FORMATS`; every format also writes the
    profiles' point files); returns their paths. A DXF of a case without profiles is bad
    input (ConfigError against ``--format``). The files are built in memory and written
    all or nothing (:func:`camopt.archive.files.write_files`): never over an existing
    file without ``force``, never through a link, never over one of ``inputs``."""
    from camopt.archive.files import ensure_folder, write_files

    spec = get_case(run.kind)
    curves = profiles(run)
    if fmt == "dxf" and not curves:
        raise ConfigError(run.path, "--format", f"dxf: case '{run.kind}' has no cam profile "
                          "to draw; use csv or json")
    ensure_folder(out_dir)
    return write_files(export_files(run, out_dir, stem, fmt, spec, curves), force, inputs)


def export_files(run: RunView, out_dir: Path, stem: str, fmt: str, spec: object,
                 curves: dict[str, np.ndarray]) -> dict[Path, bytes]:
    """The export files' contents by path (nothing written)."""
    analysis = run.analysis
    doc = report.show(run)
    files: dict[Path, bytes] = {}
    if fmt == "dxf":
        files[out_dir / f"{stem}.dxf"] = dxf_bytes(curves, circles(run, spec.circles))  # type: ignore[attr-defined]
    elif fmt == "json":
        doc["analysis"] = {k: report.jsonable(np.asarray(v).tolist()) for k, v in analysis.items()}
        files[out_dir / f"{stem}.json"] = json.dumps(doc, indent=2).encode()
    else:
        rows: list[list[object]] = [["section", "name", "value"],
                                    ["best", "objective", doc["best"]["objective"]],
                                    ["best", "feasible", doc["best"]["feasible"]]]
        for section in ("x", "metrics"):
            for k, v in doc["best"][section].items():
                rows.append([section, k, json.dumps(v) if isinstance(v, list) else v])
        files[out_dir / f"{stem}-summary.csv"] = _csv(rows)
        groups: dict[int, list[str]] = {}
        for k, v in analysis.items():
            groups.setdefault(np.asarray(v).size, []).append(k)
        for i, (_, keys) in enumerate(sorted(groups.items())):
            table = np.column_stack([np.asarray(analysis[k]) for k in keys]).tolist()
            header: list[object] = list(keys)
            files[out_dir / f"{stem}-curves-{i + 1}.csv"] = _csv([header, *table])
    for name, points in curves.items():
        text = io.BytesIO()
        np.savetxt(text, np.column_stack([points, np.zeros(len(points))]), fmt="%.6f",
                   delimiter=",")
        files[out_dir / f"{stem}-{name}.txt"] = text.getvalue()
    return files


def _csv(rows: list[list[object]]) -> bytes:
    text = io.StringIO(newline="")
    csv.writer(text).writerows(rows)
    return text.getvalue().encode()


def profiles(run: RunView) -> dict[str, np.ndarray]:
    """The case's profile curves of this run as ``{name: (n, 2) points in mm}`` (finite
    points only; curves whose analysis the archive lacks are left out)."""
    analysis = run.analysis
    curves = {}
    for curve in get_case(run.kind).profiles:
        if not all(k in analysis for k in (*curve.x, *curve.y)):
            continue
        x, y = _series(analysis, curve.x), _series(analysis, curve.y)
        ok = np.isfinite(x) & np.isfinite(y)
        curves[curve.name] = np.column_stack([x[ok], y[ok]])
    return curves


def circles(run: RunView, specs: tuple) -> dict[str, tuple[tuple[float, float], float]]:
    """The case's circles of this run: ``{name: ((x, y) centre in mm, radius in mm)}``;
    those whose radius or centre the archive lacks are left out."""
    found = {}
    for c in specs:
        radius = run.case.get(c.radius)
        if not isinstance(radius, (int, float)):
            continue
        centre = (0.0, 0.0)
        if c.centre is not None:
            if not all(k in run.analysis and np.size(run.analysis[k]) for k in c.centre):
                continue
            kx, ky = c.centre
            centre = (float(np.ravel(run.analysis[kx])[0]), float(np.ravel(run.analysis[ky])[0]))
        found[c.name] = (centre, float(radius))
    return found


def write_dxf(path: Path, curves: dict[str, np.ndarray],
              rings: dict[str, tuple[tuple[float, float], float]]) -> None:
    """Write :func:`dxf_bytes` to ``path`` (a new file, never over an existing one)."""
    from camopt.archive.files import write_files

    write_files({Path(path): dxf_bytes(curves, rings)})


def dxf_bytes(curves: dict[str, np.ndarray],
              rings: dict[str, tuple[tuple[float, float], float]]) -> bytes:
    """A DXF (R2010) in millimetres: each curve a 2-D polyline (LWPOLYLINE) on a layer of
    its name, each circle a CIRCLE on its own layer."""
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", setup=False)
    doc.units = units.MM
    doc.header["$MEASUREMENT"] = 1  # metric
    msp = doc.modelspace()
    colours = iter(range(1, 256))
    for name, points in curves.items():
        doc.layers.add(name, color=next(colours))
        msp.add_lwpolyline(points.tolist(), format="xy", dxfattribs={"layer": name})
    for name, (centre, radius) in rings.items():
        doc.layers.add(name, color=next(colours))
        msp.add_circle(centre, radius, dxfattribs={"layer": name})
    text = io.StringIO()
    doc.write(text)
    return text.getvalue().encode(doc.output_encoding)
