"""Export a run's summary and analysis curves as CSV or JSON, and for the workshop a DXF
drawing (ezdxf) of the cam with its base circle and roller, point files of its curves
(x, y, z in mm, one point per line, which CAD tools import as curves) and a points table
for CNC (polar and Cartesian, mm, at a chosen angle step).

Where the case offers a closed outline (``CaseSpec.outline``: the VCB cam) the drawing's
profile and pitch curve are that outline, one closed polyline each, with the roller's
path, the pivots, a datum and the law and angles in a notes block; otherwise the case's
profile curves as archived. The formats write distinct file names, so all three can be
exported into one folder: csv ``STEM-summary.csv`` and ``STEM-curves-N.csv`` (time, when
a group has it, in the first column), json ``STEM.json``, dxf ``STEM.dxf``,
``STEM-<curve>.txt`` and ``STEM-cam-points.csv``."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from camopt.cases import CaseSpec, get_case
from camopt.core.runview import RunView
from camopt.errors import ConfigError
from camopt.mechanics.cam_outline import CamOutline
from camopt.reporting import report
from camopt.units import DEG, MM, TO_DEG

FORMATS = ("csv", "json", "dxf")
STEP_DEG = 1.0
"""Default angle step of the CNC points table (deg)."""
STEP_RANGE_DEG = (0.01, 30.0)
"""Steps of the CNC points table (deg): from 0.01 (36,000 rows, finer than the dense
outline of :data:`DENSE_DEG` it is interpolated from is of no use; 1e-5 deg was 36 million
rows, 78 s and 7.7 GB before running out of memory) to 30 (12 rows)."""
DENSE_DEG = 0.02
"""Sampling of the outline the points table is interpolated from (deg): linear
interpolation in polar angle then errs by well under 0.1 um (tested against 0.01 deg)."""


def _series(analysis: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(analysis[k]) for k in keys])


def export_run(run: RunView, out_dir: Path, stem: str, fmt: str, force: bool = False,
               inputs: tuple[Path, ...] = (), step_deg: float = STEP_DEG) -> list[Path]:
    """Write the export files (``fmt`` one of :data:`FORMATS`; the DXF also writes the
    curves' point files and the CNC points table at ``step_deg``); returns their paths.
    A DXF of a case without profiles is bad input (ConfigError against ``--format``), and
    so is a step outside :data:`STEP_RANGE_DEG`. The files are built in memory and written all or
    nothing (:func:`camopt.archive.files.write_files`): never over an existing file
    without ``force``, never through a link, never over one of ``inputs``."""
    from camopt.archive.files import output_folder, write_files

    spec = get_case(run.kind)
    low, high = STEP_RANGE_DEG
    if not (np.isfinite(step_deg) and low <= step_deg <= high):
        raise ConfigError(run.path, "--step-deg", f"{step_deg:g}: must be in [{low:g}, "
                          f"{high:g}] deg")
    if fmt == "dxf":
        files = dxf_files(run, out_dir, stem, spec, step_deg)
    else:
        files = export_files(run, out_dir, stem, fmt)
    with output_folder(out_dir):  # a folder this made is removed again on failure
        return write_files(files, force, inputs)


def dxf_files(run: RunView, out_dir: Path, stem: str, spec: CaseSpec, step_deg: float
              ) -> dict[Path, bytes]:
    """The DXF export's files by path (nothing written): the drawing, each curve's point
    file and, with a closed outline, the CNC points table."""
    outline = spec.cam_outline(run)
    curves = profiles(run) if outline is None else {
        "cam-profile": outline.profile / MM, "cam-pitch-curve": outline.pitch / MM}
    if not curves:
        raise ConfigError(run.path, "--format", f"dxf: case '{run.kind}' has no cam profile "
                          "to draw; use csv or json")
    files = {out_dir / f"{stem}.dxf": dxf_bytes(curves, circles(run, spec.circles), outline)}
    for name, points in curves.items():
        text = io.BytesIO()
        np.savetxt(text, np.column_stack([points, np.zeros(len(points))]), fmt="%.6f",
                   delimiter=",")
        files[out_dir / f"{stem}-{name}.txt"] = text.getvalue()
    if outline is not None:
        dense = spec.cam_outline(run, DENSE_DEG * DEG)
        assert dense is not None
        table = points_table(dense, step_deg)
        files[out_dir / f"{stem}-cam-points.csv"] = _csv(
            [["polar_angle_deg", "radius_mm", "x_mm", "y_mm"],
             *np.round(table, 6).tolist()])
    return files


def points_table(outline: CamOutline, step_deg: float) -> np.ndarray:
    """The cam profile at equal polar angles 0, step, .. < 360 deg about the cam pivot:
    (k, 4) columns polar angle (deg), radius, x, y (mm). The radius is interpolated
    linearly in polar angle between the outline's points (sample it finely:
    :data:`DENSE_DEG`). A profile that is not star-shaped about the pivot (its polar
    angle not monotonic) has no such table: CamoptError."""
    from camopt.errors import CamoptError

    x, y = outline.profile[:, 0] / MM, outline.profile[:, 1] / MM
    polar = np.unwrap(np.arctan2(y, x))
    if polar[-1] < polar[0]:  # the cam turns one way, its outline the other
        polar, x, y = polar[::-1], x[::-1], y[::-1]
    if np.any(np.diff(polar) <= 0):
        raise CamoptError("the cam profile is not star-shaped about its pivot: no polar "
                          "points table (use the DXF)")
    grid = np.arange(0.0, 360.0 - 1e-9, step_deg)
    radius = np.interp(grid * DEG, polar, np.hypot(x, y), period=2 * np.pi)
    return np.column_stack([grid, radius, radius * np.cos(grid * DEG),
                            radius * np.sin(grid * DEG)])


def _time_first(keys: list[str]) -> list[str]:
    """A curve group's columns: time (``time_*``, also ``initial_time_*``) first."""
    return sorted(keys, key=lambda k: not k.removeprefix("initial_").startswith("time_"))


def export_files(run: RunView, out_dir: Path, stem: str, fmt: str) -> dict[Path, bytes]:
    """The csv or json export's files by path (nothing written)."""
    analysis = run.analysis
    files: dict[Path, bytes] = {}
    if fmt == "json":
        doc = report.show(run).to_json()
        doc["analysis"] = {k: report.jsonable(np.asarray(v).tolist()) for k, v in analysis.items()}
        files[out_dir / f"{stem}.json"] = json.dumps(doc, indent=2).encode()
    else:
        best = report.jsonable({"objective": run.best.objective,
                                "feasible": run.best.feasible, "x": run.best.x,
                                "metrics": run.best.metrics})
        rows: list[list[object]] = [["section", "name", "value"],
                                    ["best", "objective", best["objective"]],
                                    ["best", "feasible", best["feasible"]]]
        for section in ("x", "metrics"):
            for k, v in best[section].items():
                rows.append([section, k, json.dumps(v) if isinstance(v, list) else v])
        files[out_dir / f"{stem}-summary.csv"] = _csv(rows)
        groups: dict[int, list[str]] = {}
        for k, v in analysis.items():
            groups.setdefault(np.asarray(v).size, []).append(k)
        for i, (_, keys) in enumerate(sorted(groups.items())):
            keys = _time_first(keys)
            table = np.column_stack([np.asarray(analysis[k]) for k in keys]).tolist()
            header: list[object] = list(keys)
            files[out_dir / f"{stem}-curves-{i + 1}.csv"] = _csv([header, *table])
    return files


# a spreadsheet reads a cell starting with one of these as a formula (OWASP's CSV
# injection list: tab and carriage return start one too)
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def neutralise(cell: object) -> object:
    """A CSV cell a spreadsheet will not run: a string starting with a formula character
    gets a leading apostrophe (shown as text, the apostrophe hidden); numbers, negative
    ones included, stay numbers. An archive handed over may carry any string (a metric's
    text, a curve's name)."""
    if isinstance(cell, str) and cell.startswith(FORMULA_STARTS):
        return "'" + cell
    return cell


def _csv(rows: list[list[object]]) -> bytes:
    text = io.StringIO(newline="")
    csv.writer(text).writerows([[neutralise(c) for c in row] for row in rows])
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
              rings: dict[str, tuple[tuple[float, float], float]],
              outline: CamOutline | None = None) -> bytes:
    """A DXF (R2010) in millimetres: each curve a 2-D polyline (LWPOLYLINE) on a layer of
    its name, each circle a CIRCLE on its own layer. With the case's closed ``outline``
    the curves are closed polylines and the drawing adds the roller's path (an ARC about
    the follower pivot), the pivots O and B (1 mm circles, labelled), a datum (axes
    through O, x towards B with the cam at the start of its actuated stroke) and the
    law and angles as notes (MTEXT)."""
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", setup=False)
    doc.units = units.MM
    doc.header["$MEASUREMENT"] = 1  # metric
    msp = doc.modelspace()
    colours = iter(range(1, 256))
    closed = outline is not None
    for name, points in curves.items():
        doc.layers.add(name, color=next(colours))
        msp.add_lwpolyline(points.tolist(), format="xy", close=closed,
                           dxfattribs={"layer": name})
    for name, (centre, radius) in rings.items():
        doc.layers.add(name, color=next(colours))
        msp.add_circle(centre, radius, dxfattribs={"layer": name})
    if outline is not None:
        _workshop_layers(doc, outline, colours)
    text = io.StringIO()
    doc.write(text)
    return text.getvalue().encode(doc.output_encoding)


def _workshop_layers(doc: object, outline: CamOutline, colours: object) -> None:
    """The roller path, pivots, datum and notes of a closed outline (see dxf_bytes)."""
    msp = doc.modelspace()  # type: ignore[attr-defined]
    layers = doc.layers  # type: ignore[attr-defined]
    for name in ("roller-path", "pivots", "datum", "notes"):
        layers.add(name, color=next(colours))  # type: ignore[call-overload]
    pivot, arm = outline.pivot / MM, outline.arm / MM
    # the roller centre turns about B (l6, 0) at l2; its direction from B is pi - (xi + phi)
    ends = [(np.pi - outline.xi - f(outline.phi)) * TO_DEG for f in (np.max, np.min)]
    msp.add_arc((pivot, 0.0), arm, float(ends[0]), float(ends[1]),
                dxfattribs={"layer": "roller-path"})
    reach = float(np.max(np.hypot(*outline.profile.T))) / MM
    height = max(reach / 40, 1.0)
    for label, (x, y) in (("O (cam pivot)", (0.0, 0.0)), ("B (follower pivot)", (pivot, 0.0))):
        msp.add_circle((x, y), 1.0, dxfattribs={"layer": "pivots"})
        msp.add_text(label, height=height, dxfattribs={"layer": "pivots"}
                     ).set_placement((x + 1.5, y + 1.5))
    span = 1.15 * reach
    msp.add_line((-span, 0.0), (max(span, pivot + 5.0), 0.0), dxfattribs={"layer": "datum"})
    msp.add_line((0.0, -span), (0.0, span), dxfattribs={"layer": "datum"})
    lines = ["CAM OUTLINE, full turn, mm. Datum: cam pivot O at (0, 0); x axis towards "
             "the follower pivot B with the cam at the start of its actuated stroke "
             "(cam angle 0); cam angles below are the cam's rotation from there.",
             f"roller radius {outline.roller / MM:.3f} mm, follower arm {arm:.3f} mm, "
             f"O to B {pivot:.3f} mm", *outline.notes()]
    msp.add_mtext("\n".join(lines), dxfattribs={"layer": "notes", "char_height": height}
                  ).set_location((-span, -span - 2 * height))
