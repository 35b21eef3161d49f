"""camopt/core/problem.py: an Evaluation's feasibility."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.core.problem import FEASIBILITY_TOL, Evaluation

EDGES = [0.0, FEASIBILITY_TOL, np.nextafter(FEASIBILITY_TOL, 1.0),
         np.nextafter(FEASIBILITY_TOL, -1.0), -1.0, 1e300, -np.inf, np.inf, np.nan, 5e-324]


@settings(max_examples=200, deadline=None)
@given(g=st.lists(st.lists(st.sampled_from(EDGES) | st.floats(allow_nan=True), min_size=3,
                           max_size=3), min_size=1, max_size=8),
       f=st.lists(st.sampled_from([1.0, np.nan, np.inf, -2.0]), min_size=8, max_size=8))
def test_feasible_is_zero_violation_and_a_finite_objective(g, f):
    """``feasible`` (a bool comparison, no float temporary) is exactly ``violation == 0``
    and a finite objective: at the tolerance, one step either side of it, at +-inf, NaN
    and subnormal values."""
    ev = Evaluation(f=np.array(f[:len(g)]), g=np.array(g, dtype=float))
    with np.errstate(over="ignore"):  # the reference's sum of 1e300s overflows to inf
        reference = (ev.violation == 0.0) & np.isfinite(ev.f)
    assert np.array_equal(ev.feasible, reference)


def test_no_constraints_is_feasible_where_the_objective_is_finite():
    ev = Evaluation(f=np.array([1.0, np.nan]), g=np.zeros((2, 0)))
    assert ev.feasible.tolist() == [True, False]
