"""``camopt export``: the DXF's profiles, base circle and roller read back with ezdxf
agree with the exported point files; the VCB cam is one closed outline that starts and
ends on the base circle and leaves the rise's geometry as the requirements judged it; the
CNC points table; formats into one folder do not collide."""

from __future__ import annotations

import ezdxf
import numpy as np
import pytest
from ezdxf import units
from typer.testing import CliRunner

from camopt import archive
from camopt.cli import app
from camopt.engine.driver import execute
from tests.conftest import CONFIGS
from tests.helpers import load

runner = CliRunner()
RUNS = {"vcb": ("vcb.toml", ["run.repeats=1", "solver.generations=30"]),
        "emb_cam": ("emb.toml", ["solver.iterations=20", "solver.particles=20",
                                 "run.repeats=1"])}
TOL_MM = 1e-3  # the point files hold 6 decimals; the DXF holds doubles


@pytest.fixture(scope="module", params=sorted(RUNS))
def exported(request, tmp_path_factory):
    name = request.param
    file, overrides = RUNS[name]
    folder = tmp_path_factory.mktemp(name)
    path = folder / f"{name}.h5"
    archive.write_run(execute(load(CONFIGS / file, *overrides)), path)
    out = folder / "export"
    r = runner.invoke(app, ["export", str(path), "--format", "dxf", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert r.stdout.splitlines()[0] == str(out / f"{name}.dxf")
    return name, archive.load_run(path), out


def test_dxf_profile_matches_the_point_file(exported):
    name, view, out = exported
    doc = ezdxf.readfile(out / f"{name}.dxf")
    assert doc.units == units.MM
    msp = doc.modelspace()
    layers = {e.dxf.layer for e in msp}
    expected = {"cam-profile", "base-circle", "title-block", "notes"} | (
        {"cam-pitch-curve", "roller", "roller-path", "pivots", "datum", "rotation"}
        if name == "vcb" else set())
    assert layers == expected
    for curve in ("cam-profile", "cam-pitch-curve"):
        if curve not in layers:
            continue
        (poly,) = msp.query(f'LWPOLYLINE[layer=="{curve}"]')
        drawn = np.array([(x, y) for x, y, *_ in poly.get_points("xy")])
        points = np.loadtxt(out / f"{name}-{curve}.txt", delimiter=",")
        assert drawn.shape == points[:, :2].shape and len(drawn) > 100
        assert np.max(np.abs(drawn - points[:, :2])) < TOL_MM


def _outline(msp):
    (poly,) = msp.query('LWPOLYLINE[layer=="cam-profile"]')
    return poly, np.array([(x, y) for x, y, *_ in poly.get_points("xy")])


def _circumradius(p):
    """Signed radius of the circle through each three successive points (mm), (m - 2,)."""
    a, b, c = p[:-2], p[1:-1], p[2:]
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    sides = (np.hypot(*(b - a).T) * np.hypot(*(c - b).T) * np.hypot(*(c - a).T))
    return sides / (2 * cross)


def test_vcb_cam_outline_is_one_closed_polyline_from_the_base_circle(exported):
    """Issue #35's "done when": one closed polyline (ezdxf) that starts and ends on the
    base circle (its first vertex, and the one the closure returns to)."""
    name, view, out = exported
    if name != "vcb":
        pytest.skip("the EMB cam draws its archived profile")
    msp = ezdxf.readfile(out / f"{name}.dxf").modelspace()
    assert len(msp.query('LWPOLYLINE[layer=="cam-profile"]')) == 1
    poly, drawn = _outline(msp)
    assert poly.closed
    rb = view.case["rb_mm"]
    assert np.hypot(*drawn[0]) == pytest.approx(rb, abs=1e-9)
    assert np.hypot(*drawn[-1]) == pytest.approx(rb, abs=1e-9)  # the base dwell's last
    # the cam stays outside the base circle (nothing under it) and turns once
    assert np.min(np.hypot(*drawn.T)) >= rb - 1e-9
    polar = np.unwrap(np.arctan2(drawn[:, 1], drawn[:, 0]))
    assert abs(polar[-1] - polar[0]) == pytest.approx(2 * np.pi, abs=np.radians(1.5))
    notes = msp.query('MTEXT[layer=="notes"]')[0].text
    for word in ("approach", "rise: 0.0 to 140.0 deg", "run-out", "top dwell",
                 "return", "3-4-5", "base dwell"):
        assert word in notes


def test_vcb_outline_leaves_the_rise_geometry_unchanged(exported):
    """Over the actuated angle the outline at the case's grid has the archived profile's
    vertices (1e-9 mm), the outline's pressure angle the archived one (1e-9 deg), and the
    curvature radius measured on that polyline (circumradius of successive vertices, a
    second code path, at the rise's inner vertices) is the archived Eq 15 radius within
    1 % (the case grid's chords' error); the drawn outline (refined to its chord error)
    passes within that error of every archived profile point."""
    name, view, out = exported
    if name != "vcb":
        pytest.skip("the EMB cam draws its archived profile")
    from camopt.cases import get_case
    from camopt.reporting.export import CHORD_ERROR_MM
    from camopt.units import MM

    _, on_drawing = _outline(ezdxf.readfile(out / f"{name}.dxf").modelspace())
    a = view.analysis
    stored = np.column_stack([a["profile_x_mm"], a["profile_y_mm"]])
    assert np.max(_distance_to_polyline(stored, on_drawing)) <= CHORD_ERROR_MM
    drawn = get_case("vcb").cam_outline(view).profile / MM
    # the rise's first vertex is the one nearest the archived start
    i = int(np.argmin(np.hypot(*(drawn - stored[0]).T)))
    rise = drawn[i:i + len(stored)]
    assert np.max(np.abs(rise - stored)) < 1e-9
    outline = get_case("vcb").cam_outline(view)
    assert np.max(np.abs(np.degrees(outline.pressure_angle[outline.rise])
                         - a["pressure_angle_deg"])) < 1e-9
    measured = _circumradius(rise)  # at the rise's inner vertices
    assert np.allclose(measured, a["curvature_mm"][1:-1], rtol=0.01)


def test_cnc_points_table(exported, tmp_path):
    """Polar and Cartesian (mm) at the chosen step; radii on the base circle where the
    cam dwells there; independent of the dense sampling (0.02 vs 0.01 deg: 1e-4 mm)."""
    name, view, out = exported
    if name != "vcb":
        pytest.skip("the EMB cam has no closed outline")
    from camopt.cases import get_case
    from camopt.reporting.export import points_table
    from camopt.units import DEG

    r = runner.invoke(app, ["export", str(view.path), "--format", "dxf", "--out",
                            str(tmp_path), "--step-deg", "2.5"])
    assert r.exit_code == 0, r.output
    table = np.loadtxt(tmp_path / f"{name}-cam-points.csv", delimiter=",", skiprows=1)
    assert (tmp_path / f"{name}-cam-points.csv").read_text().splitlines()[0] == \
        "polar_angle_deg,radius_mm,x_mm,y_mm"
    assert table.shape == (144, 4)
    assert np.allclose(table[:, 0], np.arange(0, 360, 2.5))
    assert np.allclose(np.hypot(table[:, 2], table[:, 3]), table[:, 1], atol=2e-6)
    assert np.min(table[:, 1]) == pytest.approx(view.case["rb_mm"], abs=1e-6)
    spec = get_case("vcb")
    fine = points_table(spec.cam_outline(view, 0.01 * DEG), 2.5)
    assert np.max(np.abs(fine - table)) < 1e-4
    bad = runner.invoke(app, ["export", str(view.path), "--format", "dxf", "--out",
                              str(tmp_path / "bad"), "--step-deg", "0"])
    assert bad.exit_code == 2 and bad.stderr.startswith("error: ")
    assert "--step-deg" in bad.stderr and not (tmp_path / "bad").exists()


def test_formats_into_one_folder_do_not_collide(exported, tmp_path):
    """csv, json and dxf into one folder, no --force: distinct files, none replaced;
    the curve tables put time first."""
    name, view, _ = exported
    written = []
    for fmt in ("csv", "json", "dxf"):
        r = runner.invoke(app, ["export", str(view.path), "--format", fmt, "--out",
                                str(tmp_path)])
        assert r.exit_code == 0, r.output
        written += r.stdout.split()
    assert len(written) == len(set(written)) == len(list(tmp_path.iterdir()))
    for table in tmp_path.glob(f"{name}-curves-*.csv"):
        header = table.read_text().splitlines()[0].split(",")
        times = [k for k in header if k.removeprefix("initial_").startswith("time_")]
        assert header[:len(times)] == times
    if name == "vcb":
        assert any(table.read_text().startswith("time_ms,")
                   for table in tmp_path.glob(f"{name}-curves-*.csv"))


def test_dxf_circles_are_the_case_radii(exported):
    name, view, out = exported
    msp = ezdxf.readfile(out / f"{name}.dxf").modelspace()
    (base,) = msp.query('CIRCLE[layer=="base-circle"]')
    radius = view.case["rb_mm" if name == "vcb" else "r_st_mm"]
    assert base.dxf.radius == pytest.approx(radius, abs=1e-12)
    assert tuple(base.dxf.center)[:2] == (0.0, 0.0)
    if name == "vcb":
        (roller,) = msp.query('CIRCLE[layer=="roller"]')
        assert roller.dxf.radius == pytest.approx(view.case["rf_mm"], abs=1e-12)
        start = (view.analysis["pitch_x_mm"][0], view.analysis["pitch_y_mm"][0])
        assert np.allclose(tuple(roller.dxf.center)[:2], start, atol=1e-9)
        # the roller touches the profile: its centre lies rf from the profile's first point
        p0 = (view.analysis["profile_x_mm"][0], view.analysis["profile_y_mm"][0])
        assert np.hypot(*np.subtract(p0, start)) == pytest.approx(view.case["rf_mm"],
                                                                  rel=1e-6)


def test_dxf_of_a_case_without_profiles_is_bad_input(tmp_path):
    path = tmp_path / "fs.h5"
    assert runner.invoke(app, ["run", str(CONFIGS / "fast_switch.toml"), "--out", str(path),
                               "--quiet"]).exit_code == 0
    r = runner.invoke(app, ["export", str(path), "--format", "dxf", "--out",
                            str(tmp_path / "x")])
    assert r.exit_code == 2
    assert r.stderr == (f"error: {path}: --format: dxf: case 'fast_switch' has no cam "
                        "profile to draw; use csv or json\n")
    assert not (tmp_path / "x").exists()


def _distance_to_polyline(points, vertices):
    """Each point's least distance (mm) to the closed polyline through ``vertices``, by
    brute force over every segment (in chunks): no assumption on which segment is near."""
    a = vertices
    ab = np.roll(vertices, -1, axis=0) - a
    out = []
    for chunk in np.array_split(points, max(1, len(points) // 2000)):
        ap = chunk[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("pmk,mk->pm", ap, ab) / np.einsum("mk,mk->m", ab, ab), 0, 1)
        gap = ap - t[..., None] * ab[None]
        out.append(np.min(np.hypot(gap[..., 0], gap[..., 1]), axis=1))
    return np.concatenate(out)


def _texts(msp, layer):
    return [e.dxf.text for e in msp.query(f'TEXT[layer=="{layer}"]')]


@pytest.mark.parametrize("chord", [0.005, 0.001])
def test_vcb_drawing_is_within_its_chord_error_and_states_it(exported, tmp_path, chord):
    """The outline read back lies within the stated chord error of the exact profile:
    the case's law evaluated every 0.005 deg (its own chords err by ~1e-5 mm), each point's
    distance to every drawn segment. A finer chord error draws more vertices. The title
    block states the chord error and the profile tolerance, which it stays below."""
    name, view, _ = exported
    if name != "vcb":
        pytest.skip("the EMB cam draws its archived profile")
    from camopt.cases import get_case
    from camopt.units import DEG, MM

    r = runner.invoke(app, ["export", str(view.path), "--format", "dxf", "--out",
                            str(tmp_path), "--chord-error-mm", str(chord)])
    assert r.exit_code == 0, r.output
    msp = ezdxf.readfile(tmp_path / f"{name}.dxf").modelspace()
    _, drawn = _outline(msp)
    exact = get_case("vcb").cam_outline(view, 0.005 * DEG).profile / MM
    gap = _distance_to_polyline(exact, drawn)
    assert np.max(gap) <= chord
    # the bound is used, not met by a needlessly dense polyline: a tenth of it would be
    assert np.max(gap) > chord / 10
    rows = dict(zip(*[iter(_texts(msp, "title-block")[1:])] * 2))
    assert rows["CHORD ERROR"].startswith(f"<= {chord:g} mm")
    assert rows["PROFILE TOL"].startswith("±0.03 mm")
    assert chord < 0.03


def test_vcb_drawing_has_title_block_and_rotation_sense(exported):
    """Title block: part, source archive, date, verdict at nominal (with the failed
    requirements, and NOT FOR RELEASE, when it fails), profile tolerance, units. The
    rotation's sense agrees with the outline: vertices run in growing cam angle, and the
    roller centre circles the cam's pivot against the cam's rotation, so a pitch curve
    whose polar angle grows means a clockwise cam; the arrow's head sits at the arc's end
    the cam turns towards. Text at least 2.5 mm high (ISO 3098)."""
    name, view, out = exported
    if name != "vcb":
        pytest.skip("the EMB cam draws its archived profile")
    from camopt.reporting import report

    msp = ezdxf.readfile(out / f"{name}.dxf").modelspace()
    texts = _texts(msp, "title-block")
    labels = texts[1::2]
    for label in ("PART", "SOURCE", "DATE", "VERDICT", "PROFILE TOL", "CHORD ERROR",
                  "UNITS", "ROTATION", "RELEASE"):
        assert label in texts
    assert f"{name}.h5" in texts
    judged = report.verdict(view)
    failed = [c for c in judged.checks if c.passed is False]
    verdict = texts[texts.index("VERDICT") + 1]
    notes = msp.query('MTEXT[layer=="notes"]')[0].text
    if failed:
        assert verdict.startswith("FAIL at nominal")
        assert labels and texts.count("FAILED") == len(failed)
        assert "NOT FOR RELEASE" in notes
    else:
        assert verdict.startswith("PASS at nominal") and "FAILED" not in texts
    assert "VERDICT AT NOMINAL" in notes
    (pitch,) = msp.query('LWPOLYLINE[layer=="cam-pitch-curve"]')
    p = np.array([(x, y) for x, y, *_ in pitch.get_points("xy")])
    polar = np.unwrap(np.arctan2(p[:, 1], p[:, 0]))
    sense = "clockwise" if polar[-1] > polar[0] else "counter-clockwise"
    assert _texts(msp, "rotation") == [f"ROTATION {sense.upper()}"]
    assert texts[texts.index("ROTATION") + 1] == f"cam turns {sense} as drawn"
    (arc,) = msp.query('ARC[layer=="rotation"]')
    (head,) = msp.query('SOLID[layer=="rotation"]')
    tip = np.array(head.dxf.vtx0)[:2]
    ends = {a: arc.dxf.radius * np.array([np.cos(np.radians(a)), np.sin(np.radians(a))])
            for a in (arc.dxf.start_angle, arc.dxf.end_angle)}
    # an ARC runs counter-clockwise from start to end: a clockwise arrow ends at its start
    nearest = min(ends, key=lambda a: np.hypot(*(ends[a] - tip)))
    assert nearest == (arc.dxf.start_angle if sense == "clockwise" else arc.dxf.end_angle)
    heights = [e.dxf.height for e in msp.query("TEXT")] + \
        [e.dxf.char_height for e in msp.query("MTEXT")]
    assert min(heights) >= 2.5


def test_chord_error_out_of_range_is_one_error_line(exported, tmp_path):
    """Outside [0.0005, 0.05] mm, or at the profile tolerance: one error line, exit 2,
    nothing written; on a case without a closed outline the option is refused too."""
    name, view, _ = exported
    values = ("0", "0.0001", "0.06", "nan") + (("0.03",) if name == "vcb" else ("0.005",))
    for value in values:
        r = runner.invoke(app, ["export", str(view.path), "--format", "dxf", "--out",
                                str(tmp_path / "bad"), "--chord-error-mm", value])
        assert r.exit_code == 2, (value, r.output)
        assert r.stderr.startswith("error: ") and len(r.stderr.splitlines()) == 1
        assert "--chord-error-mm" in r.stderr and not (tmp_path / "bad").exists()


def test_failing_design_warns_once_on_stderr(exported, tmp_path):
    """A design failing at nominal is exported with one warning line naming the failed
    requirements; a passing one without."""
    name, view, _ = exported
    from camopt.reporting import report

    failed = [c.requirement.name for c in report.verdict(view).checks if c.passed is False]
    r = runner.invoke(app, ["export", str(view.path), "--format", "dxf", "--out",
                            str(tmp_path)])
    assert r.exit_code == 0, r.output
    lines = r.stderr.splitlines()
    if failed:
        assert len(lines) == 1 and lines[0].startswith("warning: ")
        assert "NOT FOR RELEASE" in lines[0] and all(f in lines[0] for f in failed)
    else:
        assert not lines


def test_the_drawn_outline_closes_on_its_first_point_without_repeating_it():
    """The DXF's closure pinned without a run: the outline (a VCB-like cam,
    tests/mechanics/test_cam_outline.py) drawn as one LWPOLYLINE flagged closed whose
    vertices are the outline's points in mm, in order, the first not repeated at the end
    (a repeated vertex is a zero-length edge a CAM program may stop on); the closing
    edge, last vertex back to the first, is no longer than the outline's other steps."""
    import io

    from camopt.mechanics.cam_outline import closed_outline
    from camopt.reporting.export import dxf_bytes
    from tests.mechanics.test_cam_outline import END, L2, L6, LAW, RF, XI

    outline = closed_outline(LAW, END, 140, XI, L2, L6, RF, RF)
    points = outline.profile * 1000.0
    doc = ezdxf.read(io.StringIO(dxf_bytes({"cam-profile": points}, {}, outline).decode()))
    (poly,) = doc.modelspace().query('LWPOLYLINE[layer=="cam-profile"]')
    drawn = np.array([(x, y) for x, y, *_ in poly.get_points("xy")])
    assert poly.closed and drawn.shape == points.shape
    np.testing.assert_array_equal(drawn, points)  # doubles through DXF text: exact
    edges = np.hypot(*np.diff(np.vstack([drawn, drawn[:1]]), axis=0).T)
    # no vanishing edge (a repeated point a turn later differs by round-off only)
    assert edges.min() > 0.01 * np.median(edges) and edges[-1] <= edges[:-1].max()
