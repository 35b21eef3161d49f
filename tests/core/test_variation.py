"""camopt/core/variation.py: rows whose inputs leave their physical range marked failed."""

from __future__ import annotations

import numpy as np

from camopt.core.problem import Evaluation
from camopt.core.variation import mark

BAD = np.array([False, True, False, True])


def _evaluation() -> Evaluation:
    return Evaluation(f=np.arange(4.0), g=np.zeros((4, 2)),
                      extras={"speed_m_s": np.full(4, 3.0), "count": np.arange(4)})


def test_marked_rows_fail_and_the_others_are_kept():
    """A marked row has every constraint +inf and objective and metrics NaN (integer
    metrics become float to hold it); the other rows keep their values."""
    ev = mark(_evaluation(), BAD)
    assert np.array_equal(ev.f, [0.0, np.nan, 2.0, np.nan], equal_nan=True)
    assert np.isinf(ev.g[BAD]).all() and (ev.g[~BAD] == 0).all()
    assert np.array_equal(ev.extras["speed_m_s"], [3.0, np.nan, 3.0, np.nan], equal_nan=True)
    assert np.array_equal(ev.extras["count"], [0.0, np.nan, 2.0, np.nan], equal_nan=True)
    assert not ev.feasible[BAD].any() and ev.feasible[~BAD].all()


def test_owned_float_arrays_are_marked_in_place():
    """The batch layer's own float arrays are written, not copied (a copy of a 10^6-sample
    VCB evaluation was another 520 bytes a sample, issue #36)."""
    before = _evaluation()
    ev = mark(before, BAD)
    assert ev.f is before.f and ev.g is before.g
    assert ev.extras["speed_m_s"] is before.extras["speed_m_s"]
    assert ev.extras["count"] is not before.extras["count"]  # int: a float copy


def test_views_and_read_only_arrays_are_copied_and_left_as_they_were():
    """An array that does not own its memory (it may be another output's) or that is
    read-only is never written: the marked values are in a copy."""
    base = np.zeros((4, 3))
    frozen = np.ones(4)
    frozen.flags.writeable = False
    before = Evaluation(f=base[:, 0], g=base[:, 1:], extras={"frozen": frozen})
    ev = mark(before, BAD)
    assert (base == 0).all() and (frozen == 1).all()
    assert np.isnan(ev.f[BAD]).all() and np.isinf(ev.g[BAD]).all()
    assert np.isnan(ev.extras["frozen"][BAD]).all()


def test_nothing_marked_is_the_same_evaluation():
    ev = _evaluation()
    assert mark(ev, np.zeros(4, dtype=bool)) is ev
