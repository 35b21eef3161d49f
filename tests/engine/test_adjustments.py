"""What ``camopt tolerance`` reports of a case's declared adjustments
(:func:`camopt.engine.tolerance.adjustment_use`): the travel the draws needed within the
reach and the share out of it."""

from __future__ import annotations

import numpy as np

from camopt.engine.tolerance import ADJUSTMENT_BINS, Tolerance, adjustment_use


class _Run:
    kind = "vcb"
    case = {"preload_setting_range_mm": 10.0}


def test_use_and_out_of_reach_share():
    need = np.array([-12.0, -9.0, -1.0, 0.0, 1.0, 2.0, 9.99, 10.0, np.inf, np.nan])
    t = Tolerance.__new__(Tolerance)
    t.run = _Run()  # type: ignore[assignment]
    (adj,) = adjustment_use(t, {"preload_setting_mm": need})
    assert adj["metric"] == "preload_setting_mm" and adj["reach"] == 10.0
    # out of reach: -12 (beyond), +inf (no travel sets it), NaN (no measurement)
    assert adj["out_of_reach_share"] == 0.3
    used = np.array([-9.0, -1.0, 0.0, 1.0, 2.0, 9.99, 10.0])
    assert adj["p50"] == float(np.percentile(used, 50)) == 1.0
    # bins of 2 mm: -9 | -1 | 0, 1 | 2 | 9.99, 10 (the last bin holds its right edge)
    assert adj["histogram"]["counts"] == [1, 0, 0, 0, 1, 2, 1, 0, 0, 2]
    assert len(adj["histogram"]["edges"]) == ADJUSTMENT_BINS + 1
    assert adj["histogram"]["edges"][0] == -10.0 and adj["histogram"]["edges"][-1] == 10.0


def test_a_run_without_the_metric_reports_none():
    t = Tolerance.__new__(Tolerance)
    t.run = _Run()  # type: ignore[assignment]
    assert adjustment_use(t, {"rod_travel_mm": np.zeros(3)}) == []
