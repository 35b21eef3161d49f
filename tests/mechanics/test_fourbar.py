"""Four-bar position (Eq 3) and the trig-free hot-path form used by the VCB case."""

from __future__ import annotations

import numpy as np
import pytest

from camopt.mechanics import fourbar

L1, L2, L3, L4, TH1 = 0.13979, 0.070, 0.1247, 0.140, np.radians(-121.98)


@pytest.mark.parametrize("branch", [1.0, -1.0])
def test_output_motion_matches_eq3_and_its_derivative(branch):
    th2 = np.linspace(np.radians(-10), np.radians(13), 50)
    c4, s4, rate = fourbar.output_motion(L1, L2, L3, L4, np.cos(TH1), np.sin(TH1),
                                         np.cos(th2), np.sin(th2), branch)
    th4 = fourbar.output_angle(L1, L2, L3, L4, TH1, th2, branch)
    np.testing.assert_allclose(np.arctan2(s4, c4), th4, atol=1e-12)
    h = 1e-7
    fd = (fourbar.output_angle(L1, L2, L3, L4, TH1, th2 + h, branch)
          - fourbar.output_angle(L1, L2, L3, L4, TH1, th2 - h, branch)) / (2 * h)
    np.testing.assert_allclose(rate, fd, rtol=1e-6)


def test_output_motion_takes_scalars():
    th2 = np.radians(5.0)
    c4, s4, _ = fourbar.output_motion(L1, L2, L3, L4, np.cos(TH1), np.sin(TH1),
                                      np.cos(th2), np.sin(th2))
    assert np.ndim(c4) == 0
    assert np.arctan2(s4, c4) == pytest.approx(fourbar.output_angle(L1, L2, L3, L4, TH1, th2))


def test_output_motion_rejects_other_branches():
    with pytest.raises(ValueError, match="branch"):
        fourbar.output_motion(L1, L2, L3, L4, 1.0, 0.0, 1.0, 0.0, 0.5)


def test_input_angle_inverts_output_angle():
    th2 = np.radians(5.0)
    th4 = fourbar.output_angle(L1, L2, L3, L4, TH1, th2, 1.0)
    assert np.isclose(fourbar.input_angle(L1, L2, L3, L4, TH1, th4, -1.0), th2)


def test_grashof_margin():
    assert fourbar.grashof_margin(1.0, 0.3, 0.9, 0.8) > 0  # 0.3 + 1.0 < 0.9 + 0.8
    assert fourbar.grashof_margin(1.0, 0.3, 0.5, 0.4) < 0
