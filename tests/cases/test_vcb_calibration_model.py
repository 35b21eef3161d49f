"""The closing a VCB calibration simulates (camopt/cases/vcb/calibration_model.py)."""

from __future__ import annotations

import numpy as np

from camopt.cases.vcb.calibration_model import sample_travel


def test_sample_travel_interpolates_holds_and_rests():
    """Rows with their own time grids: linear between nodes, 0 before the first, the last
    value after the latch, the last finite value after a stall (inf times), and a row
    that never moves (inf from the start) at 0."""
    time = np.array([[1.0, 2.0, 3.0], [0.5, 1.0, np.inf], [np.inf, np.inf, np.inf]])
    rod = np.array([[0.0, 1.0, 3.0], [0.0, 2.0, 2.5], [0.0, 1.0, 2.0]])
    query = np.array([[0.0, 1.5, 2.5, 9.0]] * 3)
    out = sample_travel(time, rod, query)
    np.testing.assert_allclose(out[0], [0.0, 0.5, 2.0, 3.0])
    np.testing.assert_allclose(out[1], [0.0, 2.0, 2.0, 2.0])
    np.testing.assert_allclose(out[2], [0.0, 0.0, 0.0, 0.0])
