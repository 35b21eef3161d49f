"""newton_pp and simplex on problems with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.config import RunSection
from camopt.core.problem import Evaluation, Problem, Variable
from camopt.engine.driver import run_repeat
from camopt.solvers import get_solver


class Circle(Problem):
    """x^2 + y^2 = 4 and x y = 1: four real roots, two in x, y > 0.

    Roots: x = sqrt(2 + sqrt(3)), y = 1/x and swapped (and their negatives)."""

    objective_name = "residual_sq"
    constraint_names = ()

    def __init__(self, lo: float = -3.0):
        self.variables = (Variable("x", lo, 3.0), Variable("y", lo, 3.0))

    def residuals(self, X):
        X = np.atleast_2d(X)
        return np.column_stack([X[:, 0] ** 2 + X[:, 1] ** 2 - 4, X[:, 0] * X[:, 1] - 1])

    def evaluate(self, X):
        X = np.atleast_2d(X)
        return Evaluation(np.sum(self.residuals(X) ** 2, axis=1), np.zeros((len(X), 0)))


class LineFit(Problem):
    """Least squares of y = a + b t through exact data: the answer is a = 1.5, b = -0.7."""

    objective_name = "sse"
    constraint_names = ()
    variables = (Variable("a", -5.0, 5.0), Variable("b", -5.0, 5.0))
    t = np.linspace(0, 1, 7)
    y = 1.5 - 0.7 * t

    def evaluate(self, X):
        X = np.atleast_2d(X)
        pred = X[:, :1] + X[:, 1:2] * self.t[None, :]
        return Evaluation(np.sum((pred - self.y) ** 2, axis=1), np.zeros((len(X), 0)))


class _Cfg:
    run = RunSection()
    path = "test.toml"

    def __init__(self, name, **opts):
        self.solver = get_solver(name).Options(**opts)


def test_newton_finds_every_root_of_a_polynomial_system():
    cls = get_solver("newton_pp")
    rec = run_repeat(Circle(), cls, _Cfg("newton_pp", starts=40), np.random.SeedSequence(1),
                     0, 1)
    roots = {(round(r["x"], 9), round(r["y"], 9)) for r in rec.table if r["success"]}
    a = np.sqrt(2 + np.sqrt(3))
    expected = {(round(s * a, 9), round(s / a, 9)) for s in (1, -1)}
    expected |= {(round(s / a, 9), round(s * a, 9)) for s in (1, -1)}
    assert roots == expected
    assert rec.notes[0].startswith("4 distinct roots")
    assert all(r["residual_max"] < 1e-12 for r in rec.table if r["success"])


def test_newton_reports_condition_number():
    cls = get_solver("newton_pp")
    rec = run_repeat(Circle(lo=0.0), cls, _Cfg("newton_pp", starts=5),
                     np.random.SeedSequence(2), 0, 1)
    x, y = rec.x
    J = np.array([[2 * x, 2 * y], [y, x]]) * 3.0  # d/du with u normalised by the 3-wide box
    row = next(r for r in rec.table if r["success"])
    assert row["jacobian_cond"] == pytest.approx(np.linalg.cond(J), rel=1e-4)


def test_simplex_fits_a_line_exactly():
    cls = get_solver("simplex")
    rec = run_repeat(LineFit(), cls, _Cfg("simplex", starts=3), np.random.SeedSequence(0),
                     0, 1)
    np.testing.assert_allclose(rec.x, [1.5, -0.7], atol=1e-6)
    assert rec.fun < 1e-12
    assert rec.notes[0].startswith("1 distinct optima")


def test_newton_never_offers_a_root_outside_the_bounds():
    """Circle with y >= 0.6: the root (1.932, 0.518) lies outside the bounds, (0.518, 1.932)
    inside. Starts that converge outside are tabulated but infeasible; the best is the
    root inside (to 1e-9)."""
    problem = Circle(lo=0.0)
    problem.variables = (Variable("x", 0.0, 3.0), Variable("y", 0.6, 3.0))
    rec = run_repeat(problem, get_solver("newton_pp"), _Cfg("newton_pp", starts=30),
                     np.random.SeedSequence(4), 0, 1)
    outside = [r for r in rec.table if r["success"] and not r["in_bounds"]]
    assert outside and not any(r["feasible"] for r in outside)  # the case is exercised
    a = np.sqrt(2 + np.sqrt(3))
    assert rec.feasible
    assert rec.x == pytest.approx([1 / a, a], abs=1e-9)


def test_newton_without_a_root_in_the_bounds_offers_no_design():
    """Circle restricted to x, y in [1, 1.2]: x^2 + y^2 <= 2.88 < 4, so no root there. The
    repeat's best is infeasible with objective +inf and a note that no start converged."""
    problem = Circle()
    problem.variables = (Variable("x", 1.0, 1.2), Variable("y", 1.0, 1.2))
    rec = run_repeat(problem, get_solver("newton_pp"), _Cfg("newton_pp", starts=5),
                     np.random.SeedSequence(0), 0, 1)
    assert not rec.feasible and rec.fun == np.inf
    assert any(n.startswith("no start converged inside the bounds") for n in rec.notes)
    assert not any(r["feasible"] for r in rec.table)
