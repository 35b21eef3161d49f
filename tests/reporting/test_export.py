"""``camopt export --format dxf``: the profiles, base circle and roller read back with
ezdxf agree with the exported point files."""

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
    expected = {"cam-profile", "base-circle"} | ({"cam-pitch-curve", "roller"}
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
