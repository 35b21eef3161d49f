"""The VCB identifications (camopt/cases/vcb/identify.py): fast pins of what a fit must
never count as a good one."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.cases.vcb.identify import DATA, VcbDynamicsIdentification
from tests.conftest import CONFIGS
from tests.helpers import load


@pytest.fixture(scope="module")
def identification():
    return VcbDynamicsIdentification(
        load(CONFIGS / "vcb_identify_dynamics.toml", "case.dynamics_steps=100").case)


def test_a_prediction_that_never_happens_is_no_perfect_fit(identification):
    """A stall (an event at inf, a velocity NaN) is a residual of 1,000 %, not 0: the
    sum of squares of such a parameter set is far above any fit's (issue #37)."""
    targets = identification.targets
    for bad in (np.inf, np.nan):
        y = np.tile(targets, (len(DATA), 1)).astype(float)
        y[np.diag_indices(len(DATA))] = bad
        r = identification.residuals(y)
        assert np.all(np.abs(r[np.diag_indices(len(DATA))]) == 10.0)
        assert np.all(r[~np.eye(len(DATA), dtype=bool)] == 0)


def test_a_cam_that_never_releases_misfits(identification):
    """Friction at the search range's top holds the cam at its release: nothing of the
    closing happens, and the misfit says so (the closing data at 1,000 %)."""
    x = np.array([[5.8e-4, 2.88, 2.02, 14.07, 50.0]])
    ev = identification.evaluate(x)
    assert np.isinf(ev.extras["cam_contact_time_ms"][0])
    assert ev.f[0] >= 3 * 10.0**2
