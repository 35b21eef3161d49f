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
import datetime
import io
import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from camopt.cases import CaseSpec, get_case
from camopt.core.runview import RunView
from camopt.errors import CamoptError, ConfigError
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
CHORD_ERROR_MM = 0.005
"""Default largest distance of the drawn outline from the exact profile (mm): a sixth of
the VCB cam's ±0.03 mm milled profile tolerance, half the EMB's ±0.01 mm ground one."""
CHORD_RANGE_MM = (0.0005, 0.05)
"""Accepted ``--chord-error-mm`` (mm): finer than 0.5 um is below what a CNC controller
resolves and makes files of 10^5 vertices; coarser than 0.05 mm exceeds any profile
tolerance camopt's cases state."""
REFERENCE_DEG = 0.01
"""Sampling of the exact profile the drawn outline's chord error is measured against
(deg): its own chords err by ~1e-5 mm, far below any accepted chord error."""
TEXT_MM = 2.5
"""Height of the drawing's text (mm at 1:1): ISO 3098's smallest general lettering."""
TITLE_MM = 3.5
"""Height of the title block's heading and the rotation label (mm at 1:1)."""


def _series(analysis: dict[str, np.ndarray], keys: tuple[str, ...]) -> np.ndarray:
    return np.concatenate([np.asarray(analysis[k]) for k in keys])


def export_run(run: RunView, out_dir: Path, stem: str, fmt: str, force: bool = False,
               inputs: tuple[Path, ...] = (), step_deg: float = STEP_DEG,
               chord_error_mm: float | None = None) -> list[Path]:
    """Write the export files (``fmt`` one of :data:`FORMATS`; the DXF also writes the
    curves' point files and the CNC points table at ``step_deg``, its outline within
    ``chord_error_mm``, None: :data:`CHORD_ERROR_MM`); returns their paths. A DXF of a
    case without profiles is bad input (ConfigError against ``--format``), and so is a
    step outside :data:`STEP_RANGE_DEG` or a chord error :func:`check_chord_error`
    refuses. The files are built in memory and written all or nothing
    (:func:`camopt.archive.files.write_files`): never over an existing file without
    ``force``, never through a link, never over one of ``inputs``."""
    from camopt.archive.files import output_folder, write_files

    spec = get_case(run.kind)
    low, high = STEP_RANGE_DEG
    if not (np.isfinite(step_deg) and low <= step_deg <= high):
        raise ConfigError(run.path, "--step-deg", f"{step_deg:g}: must be in [{low:g}, "
                          f"{high:g}] deg")
    if fmt == "dxf":
        files = dxf_files(run, out_dir, stem, spec, step_deg, chord_error_mm)
    elif chord_error_mm is not None:
        raise ConfigError(run.path, "--chord-error-mm", f"applies to --format dxf, not {fmt}")
    else:
        files = export_files(run, out_dir, stem, fmt)
    with output_folder(out_dir):  # a folder this made is removed again on failure
        return write_files(files, force, inputs)


def dxf_files(run: RunView, out_dir: Path, stem: str, spec: CaseSpec, step_deg: float,
              chord_error_mm: float | None = None) -> dict[Path, bytes]:
    """The DXF export's files by path (nothing written): the drawing, each curve's point
    file and, with a closed outline, the CNC points table."""
    tolerance = spec.profile_tolerance_mm(run)
    chord = check_chord_error(run, CHORD_ERROR_MM if chord_error_mm is None
                              else chord_error_mm, tolerance)
    outline, measured, step = None, None, None
    if spec.outline is not None:
        found = chord_outline(run, spec, chord)
        if found is not None:
            outline, measured, step = found
    if outline is None and chord_error_mm is not None:
        raise ConfigError(run.path, "--chord-error-mm", f"case '{run.kind}' draws its "
                          "archived profile points (no closed outline to refine); leave "
                          "it out")
    curves = profiles(run) if outline is None else {
        "cam-profile": outline.profile / MM, "cam-pitch-curve": outline.pitch / MM}
    if not curves:
        raise ConfigError(run.path, "--format", f"dxf: case '{run.kind}' has no cam profile "
                          "to draw; use csv or json")
    sheet = title_sheet(run, spec, tolerance, chord if outline is not None else None,
                        measured, step, outline)
    files = {out_dir / f"{stem}.dxf": dxf_bytes(curves, circles(run, spec.circles), outline,
                                                sheet)}
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
        doc: dict[str, object] = dict(report.show(run).to_json())  # the show document
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




def check_chord_error(run: RunView, chord_mm: float, tolerance_mm: float | None) -> float:
    """``chord_mm`` when it lies in :data:`CHORD_RANGE_MM` and does not exceed the profile
    tolerance ``tolerance_mm`` (a drawing whose own geometry spends the whole tolerance
    cannot be released), else a ConfigError against ``--chord-error-mm``."""
    lo, hi = CHORD_RANGE_MM
    if not (np.isfinite(chord_mm) and lo <= chord_mm <= hi):
        raise ConfigError(run.path, "--chord-error-mm", f"{chord_mm:g}: must be in "
                          f"[{lo:g}, {hi:g}] mm")
    if tolerance_mm is not None and chord_mm >= tolerance_mm:
        raise ConfigError(run.path, "--chord-error-mm", f"{chord_mm:g} mm: must be below "
                          f"the profile tolerance ±{tolerance_mm:g} mm")
    return chord_mm


def chord_error(coarse: CamOutline, exact: CamOutline) -> float:
    """Largest distance (mm) of ``exact``'s profile and pitch points from ``coarse``'s
    closed polylines: each exact point against the chord whose cam angles bracket its own
    (both outlines are one law sampled at different steps)."""
    theta = coarse.theta
    i = np.clip(np.searchsorted(theta, exact.theta, side="right") - 1, 0, theta.size - 1)
    worst = 0.0
    for drawn, points in ((coarse.profile, exact.profile), (coarse.pitch, exact.pitch)):
        a, b = drawn[i] / MM, drawn[(i + 1) % theta.size] / MM
        p = points / MM
        ab = b - a
        t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
        worst = max(worst, float(np.max(np.hypot(*(p - a - t[:, None] * ab).T))))
    return worst


def chord_outline(run: RunView, spec: CaseSpec, chord_mm: float
                  ) -> tuple[CamOutline, float, float] | None:
    """The run's closed outline sampled so that its polylines lie within ``chord_mm`` of
    the exact profile and pitch curve, with that distance as measured
    (:func:`chord_error` against :data:`REFERENCE_DEG`) and the closure's step (deg);
    None when the case has no outline. The step starts from the sagitta of a circle of
    the profile's least radius (chord c errs by c^2 / 8 rho) and shrinks until the
    measured error meets ``chord_mm``."""
    exact = spec.cam_outline(run, REFERENCE_DEG * DEG)
    if exact is None:
        return None
    rho = np.minimum(np.abs(exact.curvature), np.abs(exact.curvature + exact.roller)) / MM
    speed = np.hypot(*np.gradient(exact.profile / MM, exact.theta, axis=0).T)
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = np.sqrt(8 * rho * chord_mm) / speed
    step = float(min(np.nanmin(steps) if np.any(np.isfinite(steps)) else DEG, DEG))
    for _ in range(8):
        coarse = spec.cam_outline(run, step)
        assert coarse is not None
        measured = chord_error(coarse, exact)
        if measured <= chord_mm:
            return coarse, measured, step * TO_DEG
        step *= 0.9 * np.sqrt(chord_mm / measured)
    raise CamoptError(f"{run.path}: the outline does not reach a chord error of "
                      f"{chord_mm:g} mm (measured {measured:.2g} mm)")


def rotation_sense(outline: CamOutline) -> str:
    """``"clockwise"`` or ``"counter-clockwise"``: how the cam turns, seen as drawn, while
    its cam angle grows (the actuated stroke). The follower's roller stays near its place
    while the cam turns under it, so in the cam's frame the roller centre circles the
    pivot against the cam's rotation."""
    polar = np.unwrap(np.arctan2(outline.pitch[:, 1], outline.pitch[:, 0]))
    return "clockwise" if polar[-1] > polar[0] else "counter-clockwise"


@dataclass(frozen=True)
class Sheet:
    """What a drawing's title block states: rows of (label, value), the failed
    requirements in words, and whether the design may be released (it meets its
    requirements at nominal or the case states none)."""

    rows: tuple[tuple[str, str], ...]
    failed: tuple[str, ...]
    verdict: str
    release: bool


def title_sheet(run: RunView, spec: CaseSpec, tolerance_mm: float | None,
                chord_mm: float | None, measured_mm: float | None, step_deg: float | None,
                outline: CamOutline | None) -> Sheet:
    """The title block of a run's drawing: part, source archive, dates, the verdict at
    nominal with its failed requirements, profile tolerance, chord error, units and
    rotation."""
    judged = report.verdict(run)
    failed = tuple(c.words for c in judged.checks if c.passed is False)
    if judged.verdict is None or not judged.checks:
        verdict = "not judged (the case states no requirements)"
    elif failed:
        verdict = f"FAIL at nominal: {len(failed)} requirement{'s' if len(failed) > 1 else ''}"
    else:
        verdict = "PASS at nominal"
        value = run.expected_yield.get("value")
        if value is not None:
            verdict += f", expected yield {100 * value:.1f} %"
    release = not failed
    tclass = run.case.get("tolerance_class") or spec.default_tolerance_class
    rows = [("PART", f"cam of run '{run.run.get('name', Path(run.path).stem)}' "
                     f"(case {run.kind})"),
            ("SOURCE", Path(run.path).name),
            ("DATE", f"drawn {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d}, run "
                     f"{run.created[:10] or 'undated'}"),
            ("VERDICT", verdict),
            *(("FAILED", _short(w.split(": ", 1)[-1] if ": " in w else w, 64))
              for w in failed),
            ("RELEASE", "yes, after review" if release else
             "NOT FOR RELEASE: fails its requirements at nominal"),
            ("PROFILE TOL", f"±{tolerance_mm:g} mm (class {tclass})"
             if tolerance_mm is not None else "not stated by the case"),
            ("CHORD ERROR", f"<= {chord_mm:g} mm (measured {measured_mm:.4f}), "
                            f"vertices every <= {step_deg:.3g} deg"
             if chord_mm is not None and measured_mm is not None and step_deg is not None
             else "profile as archived (not refined)"),
            ("UNITS", "mm, scale 1:1"),
            ("ROTATION", f"cam turns {rotation_sense(outline)} as drawn"
             if outline is not None else "not stated (no closed outline)")]
    return Sheet(tuple(rows), failed, judged.sentence, release)


def failed_warning(run: RunView, fmt: str = "dxf") -> str:
    """One line for a design that fails its requirements at nominal (else ''): the
    export goes ahead (a failing design is looked at in CAD too), a drawing marked."""
    judged = report.verdict(run)
    failed = [c.requirement.name for c in judged.checks if c.passed is False]
    if not failed:
        return ""
    marked = ", the drawing marked NOT FOR RELEASE" if fmt == "dxf" else ""
    return (f"{run.path}: the design fails {len(failed)} requirement"
            f"{'s' if len(failed) > 1 else ''} at nominal ({'; '.join(failed)}): exported "
            f"for review{marked}")


def _short(text: str, width: int) -> str:
    return text if len(text) <= width else text[:width - 3] + "..."


def dxf_bytes(curves: dict[str, np.ndarray],
              rings: dict[str, tuple[tuple[float, float], float]],
              outline: CamOutline | None = None, sheet: Sheet | None = None) -> bytes:
    """A DXF (R2010) in millimetres: each curve a 2-D polyline (LWPOLYLINE) on a layer of
    its name, each circle a CIRCLE on its own layer. With the case's closed ``outline``
    the curves are closed polylines and the drawing adds the roller's path (an ARC about
    the follower pivot), the pivots O and B (1 mm circles, labelled), a datum (axes
    through O, x towards B with the cam at the start of its actuated stroke), the
    rotation (an arrow and its sense, layer ``rotation``) and the law and angles as notes
    (MTEXT). With a ``sheet`` a title block (layer ``title-block``) below the drawing.
    Text is :data:`TEXT_MM` high (:data:`TITLE_MM` for headings)."""
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
    every = np.concatenate([*curves.values(), *(np.array([c]) + [[r, r], [-r, -r]]
                                                for c, r in rings.values())])
    box = (float(np.min(every[:, 0])), float(np.min(every[:, 1])),
           float(np.max(every[:, 0])), float(np.max(every[:, 1])))
    notes: list[str] = []
    if outline is not None:
        box, notes = _workshop_layers(doc, outline, colours)
    if sheet is not None or notes:
        _title_block(doc, sheet, box, notes)
    text = io.StringIO()
    doc.write(text)
    return text.getvalue().encode(doc.output_encoding)


def _workshop_layers(doc: Any, outline: CamOutline, colours: Iterator[int]
                     ) -> tuple[tuple[float, float, float, float], list[str]]:
    """The roller path, pivots, datum and rotation arrow of a closed outline (see
    dxf_bytes); returns the drawing's box (x0, y0, x1, y1 in mm) and its notes' lines."""
    msp = doc.modelspace()
    for name in ("roller-path", "pivots", "datum"):
        doc.layers.add(name, color=next(colours))
    doc.layers.add("rotation", color=7)
    pivot, arm = outline.pivot / MM, outline.arm / MM
    # the roller centre turns about B (l6, 0) at l2; its direction from B is pi - (xi + phi)
    ends = [(np.pi - outline.xi - f(outline.phi)) * TO_DEG for f in (np.max, np.min)]
    msp.add_arc((pivot, 0.0), arm, float(ends[0]), float(ends[1]),
                dxfattribs={"layer": "roller-path"})
    reach = float(np.max(np.hypot(*outline.profile.T))) / MM
    for label, (x, y) in (("O (cam pivot)", (0.0, 0.0)), ("B (follower pivot)", (pivot, 0.0))):
        msp.add_circle((x, y), 1.0, dxfattribs={"layer": "pivots"})
        msp.add_text(label, height=TEXT_MM, dxfattribs={"layer": "pivots"}
                     ).set_placement((x + 1.5, y + 1.5))
    span = 1.15 * reach
    right = max(span, pivot + 5.0)
    msp.add_line((-span, 0.0), (right, 0.0), dxfattribs={"layer": "datum"})
    msp.add_line((0.0, -span), (0.0, span), dxfattribs={"layer": "datum"})
    sense = rotation_sense(outline)
    _rotation_arrow(msp, 1.08 * reach, sense)
    lines = ["CAM OUTLINE, full turn, mm. Datum: cam pivot O at (0, 0); x axis towards "
             "the follower pivot B with the cam at the start of its actuated stroke "
             f"(cam angle 0); cam angles below are the cam's rotation from there; the cam "
             f"turns {sense} as drawn.",
             f"roller radius {outline.roller / MM:.3f} mm, follower arm {arm:.3f} mm, "
             f"O to B {pivot:.3f} mm", *outline.notes()]
    return (-span, -span, right, span), lines


ARROW_DEG = (100.0, 150.0)
"""Where the rotation arrow's arc runs (deg about O, away from the follower pivot)."""


def _rotation_arrow(msp: Any, radius: float, sense: str) -> None:
    """An arc about O with a filled head at the end the cam turns towards, and its label
    (layer ``rotation``)."""
    a0, a1 = ARROW_DEG
    msp.add_arc((0.0, 0.0), radius, a0, a1, dxfattribs={"layer": "rotation"})
    clockwise = sense == "clockwise"
    at = (a0 if clockwise else a1) * DEG
    tip = radius * np.array([np.cos(at), np.sin(at)])
    ahead = np.array([np.sin(at), -np.cos(at)]) * (1 if clockwise else -1)  # tangent
    side = np.array([np.cos(at), np.sin(at)])
    size = TITLE_MM
    base = tip - size * ahead
    head = [tip + size * ahead, base + 0.5 * size * side, base - 0.5 * size * side]
    msp.add_solid([tuple(p) for p in (head[0], head[1], head[2])],
                  dxfattribs={"layer": "rotation"})
    from ezdxf.enums import TextEntityAlignment

    far = (a1 + 8) * DEG  # beyond the arc's left end, the text ending there
    msp.add_text(f"ROTATION {sense.upper()}", height=TITLE_MM,
                 dxfattribs={"layer": "rotation"}).set_placement(
        (radius * np.cos(far), radius * np.sin(far)), align=TextEntityAlignment.BOTTOM_RIGHT)


TITLE_WIDTHS = (32.0, 118.0)
"""Width of the title block's label and value columns (mm): 64 characters of 2.5 mm text."""


def _title_block(doc: Any, sheet: Sheet | None, box: tuple[float, float, float, float],
                 notes: list[str]) -> None:
    """The title block below the drawing's right edge, and below it the notes: the law
    and angles, the verdict at nominal in words and, for a failing design, NOT FOR
    RELEASE (layers ``title-block`` and ``notes``)."""
    msp = doc.modelspace()
    for name in ("title-block", "notes"):
        doc.layers.add(name, color=7)  # black on white, white on black: printable
    x0, y0, x1, _ = box
    label_w, value_w = TITLE_WIDTHS
    row = 2.4 * TEXT_MM
    width = label_w + value_w
    left, top = x1 - width, y0 - 4 * TEXT_MM
    rows = [("CAMOPT CAM DRAWING", "")] + list(sheet.rows) if sheet is not None else []
    height = row * len(rows)
    attribs = {"layer": "title-block"}
    if rows:
        msp.add_lwpolyline([(left, top), (left + width, top), (left + width, top - height),
                            (left, top - height)], close=True, dxfattribs=attribs)
        msp.add_line((left + label_w, top - row), (left + label_w, top - height),
                     dxfattribs=attribs)
    for k, (label, value) in enumerate(rows):
        y = top - row * (k + 1)
        if k:
            msp.add_line((left, y + row), (left + width, y + row), dxfattribs=attribs)
        size = TITLE_MM if k == 0 else TEXT_MM
        msp.add_text(label, height=size, dxfattribs=attribs).set_placement(
            (left + 1.5, y + (row - size) / 2))
        if value:
            msp.add_text(value, height=TEXT_MM, dxfattribs=attribs).set_placement(
                (left + label_w + 1.5, y + (row - TEXT_MM) / 2))
    lines = list(notes)
    if sheet is not None:
        lines.append(f"VERDICT AT NOMINAL: {sheet.verdict}")
    if sheet is not None and not sheet.release:
        lines.append("NOT FOR RELEASE: the design fails its requirements at nominal "
                     "(listed above); exported for review only.")
    msp.add_mtext("\n".join(lines), dxfattribs={
        "layer": "notes", "char_height": TEXT_MM, "width": max(x1 - x0, width)}
    ).set_location((x0, top - height - 3 * TEXT_MM))
