"""One repeat record (camopt/core/record.py): what a run, a sweep and both archives hold, with
scipy's names and a meaningful ``success``; archives written before the record (by
camopt at commit 52e31ad, tests/data/archives/) load to the values their HDF5 holds."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from camopt.archive import load_run, write_run
from camopt.archive.sweeps import load_sweep
from camopt.engine.driver import execute
from tests.conftest import CONFIGS
from tests.helpers import load

OLD = Path(__file__).parents[1] / "data" / "archives"
OLD_RUN, OLD_SWEEP = OLD / "run_main_52e31ad.h5", OLD / "sweep_main_52e31ad.h5"


def _first_hit(history: dict, target: float | None) -> int:
    """Evaluations at the first iteration whose best was feasible (and <= target)."""
    for nfev, f, v in zip(history["nfev"], history["best_objective"],
                          history["best_violation"]):
        if v == 0 and (target is None or f <= target):
            return int(nfev)
    return -1


def test_a_run_archive_of_the_previous_camopt_loads_to_what_it_holds():
    """configs/fast_switch_de.toml, 2 repeats (run.target 18.2 ms): repeat 0 feasible at
    17.98 ms, repeat 1 infeasible; ``success`` (not stored then) follows from them."""
    view = load_run(OLD_RUN)
    with h5py.File(OLD_RUN, "r") as f:
        assert "success" not in f["repeats/r000"].attrs
        scale = f.attrs["variable_scale"]
        target = json.loads(f.attrs["config_effective"])["run"]["target"]
        assert target == 18.2
        for r in view.repeats:
            g = f[f"repeats/r{r.index:03d}"]
            assert r.fun == g.attrs["objective"] and r.feasible == g.attrs["feasible"]
            assert r.spawn_key == (r.index,) and r.seed == g.attrs["seed"]
            assert (r.nfev, r.nit, r.message) == (g.attrs["nfev"], g.attrs["nit"],
                                                  g.attrs["message"])
            np.testing.assert_allclose(r.x * scale, g["x"][()], rtol=1e-15)  # SI again
            np.testing.assert_array_equal(r.g, g["g"][()])
            assert r.nfev_to_target == _first_hit(r.history, target)
    assert [r.feasible for r in view.repeats] == [True, False]
    assert [r.success for r in view.repeats] == [True, False]
    assert view.repeats[0].fun == pytest.approx(17.9848, abs=1e-4)


def test_a_sweep_archive_of_the_previous_camopt_loads_to_what_it_holds():
    spec, results = load_sweep(OLD_SWEEP)
    with h5py.File(OLD_SWEEP, "r") as f:
        cells = f["cells"]
        assert len(results) == len(cells["seed"]) == 4
        for i in range(len(cells["seed"])):
            point, k = int(cells["point"][i]), int(cells["seed"][i])
            r = results[(point, k)]
            assert (r.point, r.index, r.spawn_key) == (point, k, (k,))
            assert r.fun == cells["objective"][i] and r.success == cells["success"][i]
            assert r.nfev_to_target == cells["nfev_to_target"][i]
            lo, hi = cells["x/offsets"][i:i + 2]
            np.testing.assert_array_equal(r.x, cells["x/values"][lo:hi])
            # the identifier a run's repeat k carries: child k of SeedSequence(run.seed)
            child = np.random.SeedSequence(spec.entropy).spawn(k + 1)[k]
            assert r.seed == int(child.generate_state(1, np.uint64)[0]) >> 1
            assert np.isnan(r.violation) and r.message == ""


def test_a_run_record_survives_its_archive(tmp_path):
    """Written and read back: scipy's fields, the seed and the derived nfev_to_target."""
    rec = execute(load(CONFIGS / "fast_switch_de.toml", "solver.generations=3",
                       "solver.population=8", "run.repeats=2", "solver.polish.maxiter=5"))
    view = load_run(write_run(rec, tmp_path / "a.h5"))
    for a, b in zip(rec.repeats, view.repeats):
        np.testing.assert_allclose(b.x, a.x, rtol=1e-14)
        assert (a.fun, a.success, a.message, a.nfev, a.nit, a.seed, a.nfev_to_target) == \
            (b.fun, b.success, b.message, b.nfev, b.nit, b.seed, b.nfev_to_target)
        assert a.nfev_to_target == _first_hit(a.history, 18.2)


def test_a_run_record_is_archived_from_its_plain_fields_alone(tmp_path):
    """The archive reads the record's names, scales and constraint names, never the live
    Problem: without it the archive is the same, and it holds the record's fields."""
    import dataclasses

    rec = execute(load(CONFIGS / "fast_switch_de.toml", "solver.generations=2",
                       "solver.population=6", "run.repeats=1", "solver.polish.maxiter=5"))
    assert rec.problem is not None
    assert rec.names == rec.problem.names and rec.objective_name == "closure_time_ms"
    np.testing.assert_array_equal(rec.scale, rec.problem.scale)
    view = load_run(write_run(dataclasses.replace(rec, problem=None), tmp_path / "a.h5"))
    assert view.variables == rec.names and view.constraints == rec.constraint_names
    assert view.objective_name == rec.objective_name
    with h5py.File(tmp_path / "a.h5", "r") as f:
        np.testing.assert_array_equal(f.attrs["variable_scale"], rec.scale)
        np.testing.assert_array_equal(f["best/x"][()], rec.best.x * rec.scale)
