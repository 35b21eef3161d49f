"""The VCB judged at the end of its life (``life_friction_rise``, ``life_spring_relaxation``;
:func:`camopt.cases.vcb.life.aged`): every friction torque higher, the
closing springs relaxed, the factory setting's nut where it was left, and each requirement
at its worse of the start and the end."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases import build_problem
from camopt.cases.vcb.life import LIFE_END_METRICS
from camopt.cases.vcb.verdict import worst_of
from camopt.core.problem import Evaluation
from tests.conftest import CONFIGS
from tests.helpers import load

CONFIG = CONFIGS / "vcb_velocity_robust.toml"
LIFE = {"life_friction_rise": 0.25, "life_spring_relaxation": 0.03}


@pytest.fixture(scope="module")
def new():
    """The robust case as built only (no life check)."""
    config = load(CONFIG).case.model_copy(update={"life_friction_rise": 0.0,
                                                  "life_spring_relaxation": 0.0})
    return build_problem(config)


@pytest.fixture(scope="module")
def aged(new):
    return build_problem(new.config.model_copy(update=LIFE))


@pytest.fixture(scope="module")
def X(new):
    return new.sample(np.random.default_rng(5), 48)


def test_no_drift_no_second_judgement(new, aged):
    assert not new.ages and aged.ages
    assert not any(k.startswith("life_end_") for k in new.evaluate(new.vendor_x()[None]).extras)


def test_the_end_of_life_is_the_breaker_with_its_parts_aged(new, aged, X):
    """The end-of-life metrics equal the as-built case evaluated with every friction
    torque 1.25 times and both closing springs' opened compression 0.97 times (the
    parts' own path, :meth:`describe_with`): two code paths, so rtol 1e-9."""
    c = new.config
    fields = {"cam_friction_nm": np.full(len(X), 1.25 * c.cam_friction_nm),
              "kc1_precompression_mm": np.full(len(X), 0.97 * c.kc1_precompression_mm),
              "kc2_precompression_mm": np.full(len(X), 0.97 * c.kc2_precompression_mm)}
    old = new.describe_with(X, fields)
    ev = aged.describe(X)
    for name in LIFE_END_METRICS:
        np.testing.assert_allclose(ev.extras[f"life_end_{name}"], old.extras[name],
                                   rtol=1e-9, equal_nan=True, err_msg=name)


def test_each_requirement_at_its_worse_end(new, aged, X):
    """The aged case's constraints are the worse of the start (the case as built) and the
    end; the verdict fails wherever the end fails, and the band's low ends read the end's
    value where it is the lower."""
    c = new.config
    fields = {"cam_friction_nm": np.full(len(X), 1.25 * c.cam_friction_nm),
              "kc1_precompression_mm": np.full(len(X), 0.97 * c.kc1_precompression_mm),
              "kc2_precompression_mm": np.full(len(X), 0.97 * c.kc2_precompression_mm)}
    start, end, both = new.describe(X), new.describe_with(X, fields), aged.describe(X)
    np.testing.assert_allclose(both.g, np.maximum(start.g, end.g), rtol=1e-9)
    assert np.array_equal(both.feasible, start.feasible & end.feasible)
    assert ((start.g <= 0) & (end.g > 0)).any(), "nothing that only the end fails: weak test"
    low = np.fmin(start.extras["latch_kinetic_energy_low_j"],
                  end.extras["latch_kinetic_energy_low_j"])
    np.testing.assert_allclose(both.extras["latch_kinetic_energy_low_j"], low, rtol=1e-9)


def test_a_stall_at_either_end_is_no_velocity():
    """The closing velocity of a set that never closes is undefined (NaN): the worst of
    two judgements is NaN wherever either is, so a stall at the end of life is not hidden
    behind the start's velocity; other lower ends take the least defined value."""
    def ev(v, k):
        return Evaluation(f=np.zeros(2), g=np.zeros((2, 1)),
                          extras={"closing_velocity_low_m_s": np.array(v),
                                  "closing_velocity_avg_m_s": np.array(v),
                                  "latch_kinetic_energy_low_j": np.array(k)})
    out = worst_of([ev([0.9, 0.8], [3.0, np.nan]), ev([np.nan, 0.7], [2.0, 1.0])], 1e6)
    np.testing.assert_array_equal(out.extras["closing_velocity_low_m_s"], [np.nan, 0.7])
    np.testing.assert_array_equal(out.extras["latch_kinetic_energy_low_j"], [2.0, 1.0])
    # the identified set's own value is the first judgement's, not a band end
    np.testing.assert_array_equal(out.extras["closing_velocity_avg_m_s"], [0.9, 0.8])
