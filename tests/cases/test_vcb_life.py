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


def test_the_release_at_the_end_of_life_needs_the_springs_work_of_the_equations(new):
    """The necessary condition docs/tolerance.md derives ("Adjustments at assembly and the
    end of life"): a breaker of friction scale s whose release passes at the end of life
    (eps T_s >= 1.2 x 1.25 s T_f, compressions x 0.97, the nut held) has, as built, a
    force at the release F >= (1.5 s T_f / rate_max - 0.03 eps K |ext|) / (0.97 eps),
    rate_max the springs' rate at the latest release the latch's space allows (the
    fit's 20.70 deg cap plus the band's 2.33 deg, rate rising toward the cam's meeting),
    so the springs give the cam, from the release to the latch, at least
    eps (F dL - K dL^2 / 2) (linear springs: the energy is F dL - K dL^2 / 2 exactly).
    Checked against the model's release_torque_ratio and closing_energy on 4,000 random
    springs (2-20 N/mm each), compressions (the nut anywhere), latches, efficiencies and
    friction torques; it fails if the torque, the relaxation or the rate's maximum were
    other than the argument takes."""
    from camopt.cases.vcb.motion import ParameterColumns
    from camopt.cases.vcb.rotation import release_torque_ratio
    from camopt.units import DEG, MM

    m = new.model
    rng = np.random.default_rng(20261129)
    n = 4000
    kc = rng.uniform(2e3, 20e3, (n, 2))
    pre = rng.uniform(20 * MM, 220 * MM, (n, 2))
    latch = rng.uniform(14.0, 23.03, n) * DEG
    eps = rng.uniform(0.8, 1.0, n)
    friction = rng.uniform(8.0, 16.0, n) * rng.uniform(0.75, 1.25, n)  # T_f s as built
    column = np.ones((n, 1))
    p = ParameterColumns(column, column, column, column, latch[:, None], column,
                         1.25 * friction[:, None], eps[:, None], column, column)
    passes = release_torque_ratio(m, kc, p, 0.97 * pre) >= 1.2
    assert 100 < passes.sum() < n - 100  # both sides of the requirement are sampled
    start = m.dead_centre + latch - m.contact_crank_angle
    ext, rate = m.closing_spring_geometry(start)
    latest = m.dead_centre + 23.03 * DEG - m.contact_crank_angle
    rates = m.closing_spring_geometry(np.linspace(-30 * DEG, latest, 400))[1]
    rate_max = float(rates.max())
    assert rate_max == pytest.approx(float(rates[-1]))  # rising up to the latest release
    end = m.closing_spring_geometry(np.array([np.deg2rad(140.0)]))[0][0]
    dL = end - ext
    K = kc.sum(axis=1)
    force = (kc * (pre - ext[:, None])).sum(axis=1)
    least_force = (1.5 * friction / rate_max - 0.03 * eps * K * np.abs(ext)) / (0.97 * eps)
    assert np.all(force[passes] >= least_force[passes] * (1 - 1e-12))
    energy = m.closing_energy_rows(kc, np.stack([ext, np.full(n, end)], axis=1), pre)
    given = eps * (energy[:, 0] - energy[:, 1])
    # the energy identity, to round-off (1e-9 of the work): the force and the rate alone
    np.testing.assert_allclose(given, eps * (force * dL - K * dL ** 2 / 2), rtol=1e-9)
    least = eps * (least_force * dL - K * dL ** 2 / 2)
    assert np.all(given[passes] >= least[passes] - 1e-9 * np.abs(given[passes]))
