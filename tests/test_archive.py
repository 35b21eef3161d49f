"""Run archives: round trip, reproducibility, atomic writes, seeds."""

from __future__ import annotations

from dataclasses import replace

import h5py
import numpy as np
import pytest

from camopt import archive
from camopt.archive import runs
from camopt.engine.driver import execute
from camopt.errors import ArchiveError
from tests.conftest import CONFIGS
from tests.helpers import load

VOLATILE_ATTRS = {"created", "wall_s"}  # timestamps and measured wall time


def _contents(path):
    """Every dataset and attribute of an archive except timestamps and wall times."""
    items = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            for k, v in obj.attrs.items():
                if k not in VOLATILE_ATTRS:
                    items[f"{name}@{k}"] = v
            if isinstance(obj, h5py.Dataset) and not name.endswith("wall_s"):
                items[name] = obj[()]
        visit("/", f)
        f.visititems(visit)
    return items


def _de(*overrides):
    """fast_switch_de.toml, small and without its polish (archives are what is tested
    here; the integer-aware polish from a 20-generation search costs seconds)."""
    cfg = load(CONFIGS / "fast_switch_de.toml", "solver.generations=20",
               "solver.population=20", *overrides)
    return replace(cfg, solver=cfg.solver.model_copy(update={"polish": None}))


def test_same_config_and_seed_identical_archives(tmp_path):
    cfg = _de("run.repeats=2")
    a = archive.write_run(execute(cfg), tmp_path / "a.h5")
    b = archive.write_run(execute(cfg), tmp_path / "b.h5")
    ca, cb = _contents(a), _contents(b)
    assert ca.keys() == cb.keys()
    for key in ca:
        assert np.array_equal(np.asarray(ca[key]), np.asarray(cb[key])), key


def test_repeats_get_distinct_seeds_from_one_spawn(tmp_path):
    rec = execute(_de(), repeats=5, seed=11)
    assert [r.spawn_key for r in rec.repeats] == [(i,) for i in range(5)]
    assert len({r.seed for r in rec.repeats}) == 5
    assert len({r.fun for r in rec.repeats}) > 1
    run = archive.load_run(archive.write_run(rec, tmp_path / "r.h5"))
    assert run.seed_entropy == "11"
    # any repeat re-runs alone from entropy and spawn key
    again = execute(_de(), repeats=5, seed=11).repeats[3]
    assert again.fun == rec.repeats[3].fun


def test_round_trip_has_what_show_needs(tmp_path):
    rec = execute(_de("run.repeats=2"))
    run = archive.load_run(archive.write_run(rec, tmp_path / "x.h5"))
    assert run.best.objective == rec.best.fun
    assert set(run.best.x) == set(rec.problem.names)
    assert len(run.repeats) == 2 and len(run.histories()) == 2
    assert run.config_toml == (CONFIGS / "fast_switch_de.toml").read_text()
    with h5py.File(tmp_path / "x.h5", "r") as f:
        for key in ("python_version", "numpy_version", "scipy_version", "h5py_version"):
            assert f.attrs[key]
        assert f["repeats/r000/history/best_objective"].maxshape == (None,)


def test_interrupted_write_leaves_nothing(tmp_path, monkeypatch):
    rec = execute(_de())

    def boom(f, r):
        f.attrs["partial"] = 1
        raise KeyboardInterrupt

    monkeypatch.setattr(runs, "_write", boom)
    with pytest.raises(KeyboardInterrupt):
        archive.write_run(rec, tmp_path / "x.h5")
    assert list(tmp_path.iterdir()) == []


def test_existing_path_needs_force(tmp_path):
    rec = execute(_de())
    path = archive.write_run(rec, tmp_path / "x.h5")
    with pytest.raises(ArchiveError, match="--force"):
        archive.write_run(rec, path)
    archive.write_run(rec, path, force=True)


def test_non_archive_rejected(tmp_path):
    junk = tmp_path / "junk.h5"
    junk.write_text("hello")
    with pytest.raises(ArchiveError, match="not a camopt archive"):
        archive.load_run(junk)
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["a"] = 1
    with pytest.raises(ArchiveError, match="not a camopt archive"):
        archive.load_run(tmp_path / "other.h5")
