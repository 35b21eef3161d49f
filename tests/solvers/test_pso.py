"""The swarm's inertia schedule (Yan 2023 Eq 40) and velocity update (Eqs 38-41)."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.engine.driver import build_solver, prepare, validate
from camopt.solvers.pso import inertia


def test_inertia_falls_linearly_from_w_max_to_w_min():
    """Eq 40: w = w_max - (w_max - w_min) i / i_max: 0.9 at the start, 0.65 half-way, 0.4
    at i_max."""
    assert inertia(0, 300, 0.9, 0.4) == pytest.approx(0.9)
    assert inertia(150, 300, 0.9, 0.4) == pytest.approx(0.65)
    assert inertia(300, 300, 0.9, 0.4) == pytest.approx(0.4)
    assert inertia(30, 300, 0.9, 0.4) == pytest.approx(0.85)


def test_a_swarm_without_learning_moves_by_inertia_times_velocity():
    """With c1 = c2 = 0, Eqs 38-41 reduce to x' = x + w v: the second move of a 10-iteration
    swarm uses w = 0.9 - 0.5 / 10 = 0.85."""
    cfg = validate({"case": {"kind": "sphere"},
                    "solver": {"name": "pso", "particles": 8, "iterations": 10, "c1": 0.0,
                               "c2": 0.0, "v_max": 1.0}}, "sphere.toml")
    problem, cls = prepare(cfg)
    solver = build_solver(problem, cls, cfg, np.random.default_rng(0))
    X0 = solver.ask()
    solver.tell(X0, problem.evaluate(X0))
    v0 = solver.V.copy()
    X1 = solver.ask()
    inside = np.all((X1 > problem.lower) & (X1 < problem.upper), axis=1)  # not clipped
    assert inside.sum() >= 2
    np.testing.assert_allclose((X1 - X0)[inside], 0.85 * v0[inside], rtol=1e-12)
