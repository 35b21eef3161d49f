"""The VCB follower law beyond the paper's cubic (``a4_bounds``/``a5_bounds``): the
rate's zeros and the exact largest swing against dense sampling, and the cubic path
unchanged when the higher terms are zero."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camopt.cases.vcb.model import phi_max, polynomial_value, rate_zeros
from camopt.cases.vcb.problem import VcbProblem
from camopt.engine.driver import load
from camopt.errors import ConfigError

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
VELOCITY_PAPER = CONFIGS / "reference" / "vcb_velocity_paper.toml"
END = 140 * np.pi / 180


def test_quintic_rate_zeros_and_largest_swing_against_dense_sampling():
    """phi' of random quintics: every sign change of phi' on a fine grid is within
    the grid step of a returned zero, and phi_max is the grid maximum within 1e-9 rad
    (never below it)."""
    rng = np.random.default_rng(3)
    A = np.column_stack([rng.uniform(-0.5, 0.5, (300, 4)), rng.uniform(-0.03, 0.03, 300),
                         rng.uniform(-0.006, 0.006, 300)])
    t = np.linspace(0.0, END, 20001)
    dphi = np.polynomial.polynomial.polyval(t, (A[:, 1:] * np.arange(1, 6)).T)
    zeros = rate_zeros(A, END)
    assert zeros.shape == (300, 4)
    changes = 0
    for row, z in zip(np.sign(dphi), zeros):
        where = np.flatnonzero(row[1:] * row[:-1] < 0)
        changes += len(where)
        for i in where:
            assert np.nanmin(np.abs(z - t[i])) <= 2 * (t[1] - t[0])
    assert changes > 50  # the sample exercises the root finder
    dense = polynomial_value(A, t).max(axis=1)
    exact = phi_max(A, END, zeros)
    assert np.all(exact >= dense - 1e-12)
    np.testing.assert_allclose(exact, dense, atol=1e-9)


@pytest.mark.parametrize("degree", [3, 5])
def test_rows_sharing_the_rate_are_solved_once_with_the_same_zeros(degree, monkeypatch):
    """Runs of rows that differ in a0 alone (a robust design's draws) are solved once a
    run, with each row's zeros those of the row alone (rtol 1e-15: the same arithmetic
    on the same numbers); a NaN row is a run of its own."""
    from camopt.cases.vcb import law

    rng = np.random.default_rng(4)
    designs = rng.uniform(-0.5, 0.5, (5, degree + 1)) * np.r_[1, 1, 1, 1, 0.06, 0.012][
        :degree + 1]
    A = np.repeat(designs, [3, 1, 4, 2, 2], axis=0)
    A[:, 0] += rng.uniform(-0.01, 0.01, len(A))  # the profile error moves a0 alone
    A[8, 1] = np.nan
    alone = np.vstack([rate_zeros(row[None, :], END) for row in A])
    solved: list[int] = []
    real = law._rate_zeros
    monkeypatch.setattr(law, "_rate_zeros", lambda a, end: (solved.append(len(a)),
                                                             real(a, end))[1])
    np.testing.assert_allclose(rate_zeros(A, END), alone, rtol=1e-15, atol=0)
    assert solved == [6]  # runs of 3, 1, 4, the NaN row and its twin apart, 2


def test_higher_terms_at_zero_give_the_cubic():
    """A quintic design whose a4 = a5 = 0 evaluates exactly as the cubic one."""
    cubic = VcbProblem(load(VELOCITY_PAPER).case)
    quintic = VcbProblem(load(VELOCITY_PAPER, ["case.a4_bounds=[-0.01,0.01]",
                                                              "case.a5_bounds=[-0.002,0.002]"]
                              ).case)
    assert [v.name for v in quintic.variables][-2:] == ["a4", "a5"]
    x = cubic.vendor_x()
    a, b = cubic.describe(x[None, :]), quintic.describe(np.r_[x, 0.0, 0.0][None, :])
    np.testing.assert_allclose(b.f, a.f, rtol=1e-12)
    np.testing.assert_allclose(b.g, a.g, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(quintic.vendor_x(), np.r_[x, 0.0, 0.0])


def test_a5_without_a4_is_refused():
    with pytest.raises(ConfigError, match="a4_bounds"):
        load(VELOCITY_PAPER, ["case.a5_bounds=[-0.002,0.002]"])
