"""One verdict over several judgements of the same VCB breakers (camopt/cases/vcb/
verdict.py): constraints at their worst, metrics through the declared reductions; exact
values (maxima, minima and sums of the given numbers)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.band import BANDED, band_ends
from camopt.cases.vcb.verdict import REDUCTIONS, Reduction, worst_of
from camopt.core.problem import Evaluation


def _ev(g, f, **extras):
    return Evaluation(f=np.asarray(f, dtype=float), g=np.asarray(g, dtype=float),
                      extras={k: np.asarray(v, dtype=float) for k, v in extras.items()})


def test_latched_holds_only_under_every_judgement():
    """Latched (1) under the first form and not (0) under the second for design 2: the
    verdict is not latched; design 1 latches under both."""
    a = _ev([[0.0], [0.0]], [1.0, 1.0], latched=[1.0, 1.0], band_sets=[3, 3],
            band_sets_not_latched=[0, 0])
    b = _ev([[0.0], [0.5]], [2.0, 2.0], latched=[1.0, 0.0], band_sets=[7, 7],
            band_sets_not_latched=[0, 2])
    out = worst_of([a, b], penalty=10.0, sum_counts=True)
    assert out.extras["latched"].tolist() == [1.0, 0.0]
    assert out.extras["band_sets"].tolist() == [10.0, 10.0]  # different sets add up
    assert out.extras["band_sets_not_latched"].tolist() == [0.0, 2.0]
    # the first judgement's objective with the worst violation's penalty: 1 + 10 * 0.5
    assert out.f.tolist() == [1.0, 6.0]
    assert out.g.tolist() == [[0.0], [0.5]]
    same = worst_of([a, b], penalty=10.0, sum_counts=False)  # the start and end of life
    assert same.extras["band_sets"].tolist() == [7.0, 7.0]
    assert same.extras["band_sets_not_latched"].tolist() == [0.0, 2.0]


def test_lower_ends_take_the_least_higher_ends_the_greatest():
    low, high = band_ends("touch_time_ms")
    a = _ev([[0.0]], [1.0], closing_velocity_low_m_s=[0.8], closing_velocity_high_m_s=[1.0],
            **{low: [20.0], high: [30.0]}, latch_kinetic_energy_low_j=[2.0],
            release_torque_margin_low=[1.5], preload_setting_mm=[-2.0],
            closing_velocity_avg_m_s=[0.9], pickup_tau_mpa=[100.0],
            life_end_closing_velocity_low_m_s=[0.7])
    b = _ev([[0.0]], [5.0], closing_velocity_low_m_s=[np.nan], closing_velocity_high_m_s=[1.2],
            **{low: [np.nan], high: [31.0]}, latch_kinetic_energy_low_j=[1.0],
            release_torque_margin_low=[1.7], preload_setting_mm=[1.5],
            closing_velocity_avg_m_s=[1.1], pickup_tau_mpa=[120.0],
            life_end_closing_velocity_low_m_s=[0.6])
    out = worst_of([a, b], penalty=1.0).extras
    assert np.isnan(out["closing_velocity_low_m_s"][0])  # a set that never closes: NaN
    assert out["closing_velocity_high_m_s"].tolist() == [1.2]
    assert out[low].tolist() == [20.0] and out[high].tolist() == [31.0]  # NaN ignored
    assert out["latch_kinetic_energy_low_j"].tolist() == [1.0]
    assert out["release_torque_margin_low"].tolist() == [1.5]
    assert out["preload_setting_mm"].tolist() == [-2.0]  # the longest travel, its sign
    assert out["pickup_tau_mpa"].tolist() == [120.0]
    assert out["closing_velocity_avg_m_s"].tolist() == [0.9]  # not reduced: the first's
    assert out["life_end_closing_velocity_low_m_s"].tolist() == [0.6]  # its metric's rule


@pytest.mark.parametrize("name", list(BANDED))
def test_every_banded_metric_has_its_ends_declared(name):
    low, high = band_ends(name)
    assert REDUCTIONS[low] is Reduction.LEAST and REDUCTIONS[high] is Reduction.GREATEST
    assert name not in REDUCTIONS
