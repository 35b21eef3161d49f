"""The 1-DOF integrator against closed-form answers."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.mechanics.dynamics import time_to_reach


def test_linear_spring_mass_quarter_period():
    """Constant mass m, spring k released from rest at q0 reaches its free length after
    a quarter period pi/2 sqrt(m/k); speed there is omega |q0 - q_free|."""
    m, k, q0, q_free = 1.3, 7400.0, 0.0, 0.052
    travel = time_to_reach(lambda q: m, lambda q: 0.0, lambda q: -k * (q - q_free),
                           q0, q_free, t_max=1.0)
    omega = np.sqrt(k / m)
    assert travel.reached
    assert travel.time == pytest.approx(np.pi / (2 * omega), rel=1e-9)
    assert travel.speed == pytest.approx(omega * q_free, rel=1e-8)


def test_position_dependent_mass_conserves_energy():
    """With M(q) = 1 + q^2 and a constant force, kinetic energy at the end equals the work."""
    force = 3.0
    travel = time_to_reach(lambda q: 1 + q * q, lambda q: 2 * q, lambda q: force,
                           0.0, 2.0, t_max=10.0)
    kinetic = 0.5 * (1 + 2.0**2) * travel.speed**2
    assert kinetic == pytest.approx(force * 2.0, rel=1e-8)


def test_unreached_target_is_reported_not_raised():
    travel = time_to_reach(lambda q: 1.0, lambda q: 0.0, lambda q: -q, 0.0, 1.0, t_max=0.1)
    assert not travel.reached and np.isnan(travel.time)


def test_call_budget_caps_an_oscillation_that_never_arrives():
    """A spring oscillating short of the target for t_max: with a budget of right-hand-side
    calls the integration stops early, capped and not reached, with no path."""
    free = time_to_reach(lambda q: 1.0, lambda q: 0.0, lambda q: -1e4 * q, 0.1, 1.0, t_max=1.0)
    capped = time_to_reach(lambda q: 1.0, lambda q: 0.0, lambda q: -1e4 * q, 0.1, 1.0,
                           t_max=1.0, max_calls=500)
    assert not free.reached and not free.capped and len(free.t) > 500 / 12
    assert capped.capped and not capped.reached and np.isnan(capped.time)
    assert capped.t.size == 0
