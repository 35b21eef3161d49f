"""Calibration archives (camopt/archive/calibrations.py): write, reload and compare; an
existing file is never replaced without force; a damaged or foreign file is one
ArchiveError naming it."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from camopt import archive
from camopt.archive.calibrations import load_calibration, write_calibration
from camopt.core.calibration import FittedCurve
from camopt.errors import ArchiveError

SUMMARY = {"velocity_points_mm": [7.33, 11.0], "kept_forms": ["a"],
           "forms": [{"form": "a", "rms_mm": 0.02, "kept": True, "parameters": []},
                     {"form": "b", "rms_mm": 0.4, "kept": False, "parameters": []}]}
CURVES = tuple(FittedCurve(form, "v.csv", "reference", np.linspace(0, 0.05, 11),
                           np.linspace(0, 0.018, 11), np.linspace(0, 0.018, 11) + k * 1e-5)
               for k, form in enumerate("ab"))


def _write(path, force=False):
    return write_calibration(path, SUMMARY, ["line one", "line two"], CURVES, "vcb",
                             "[case]\nkind = \"vcb\"\n", force)


def test_write_reload_compare(tmp_path):
    path = _write(tmp_path / "c.h5")
    assert archive.archive_kind(path) == "calibration"
    view = load_calibration(path)
    assert view.summary == SUMMARY
    assert view.lines == ("line one", "line two")
    assert view.case_kind == "vcb" and view.config_toml.startswith("[case]")
    assert [c.form for c in view.curves] == ["a", "b"]
    for a, b in zip(view.curves, CURVES):
        for name in ("time_s", "measured_m", "fitted_m"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert (a.source, a.design) == (b.source, b.design)
    assert [p.name for p in tmp_path.iterdir()] == ["c.h5"]  # no temporary or lock left


def test_an_existing_file_is_not_replaced_without_force(tmp_path):
    path = tmp_path / "c.h5"
    path.write_bytes(b"keep")
    with pytest.raises(ArchiveError):
        _write(path)
    assert path.read_bytes() == b"keep"
    _write(path, force=True)
    assert load_calibration(path).lines == ("line one", "line two")


def test_a_damaged_or_foreign_archive_is_one_error(tmp_path):
    path = _write(tmp_path / "c.h5")
    with h5py.File(path, "a") as f:
        f.attrs["summary"] = "{not json"
    with pytest.raises(ArchiveError, match="damaged calibration archive"):
        load_calibration(path)
    other = tmp_path / "o.h5"
    with h5py.File(other, "w") as f:
        f.attrs.update({"camopt_version": "x", "schema_version": 1, "archive_kind": "sweep"})
    with pytest.raises(ArchiveError, match="not a calibration archive"):
        load_calibration(other)
