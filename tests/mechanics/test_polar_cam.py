"""Profile-based analysis (Yan et al. 2023): closed forms against the printed equations."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.mechanics import polar_cam as pc


@settings(max_examples=50, deadline=None)
@given(r=st.floats(10, 25), dr=st.floats(0.1, 20), theta=st.floats(0.1, 3.0))
def test_normal_arm_equals_eq8(r, dr, theta):
    """Eq 8 through the slopes of Eqs 5-7 equals r |dr| / sqrt(r^2 + dr^2)."""
    x, y = r * np.cos(theta), r * np.sin(theta)
    k_b = (dr * np.sin(theta) + r * np.cos(theta)) / (dr * np.cos(theta) - r * np.sin(theta))
    k_n = -1 / k_b
    eq8 = abs(y - k_n * x) / np.sqrt(1 + k_n**2)
    assert np.isclose(pc.normal_arm(r, dr), eq8, rtol=1e-9)


@settings(max_examples=50, deadline=None)
@given(kappa=st.floats(0.0, 1.1))
def test_eq9_at_the_start_equals_eq22(kappa):
    """At r = r_st with dr = r_st tan(kappa) (Eq 20), Eq 9 gives Eq 22's |AO|."""
    r_st, rg = 15.0, 20.0
    l = pc.normal_arm(r_st, r_st * np.tan(kappa))
    assert np.isclose(pc.center_distance(r_st, l, rg), pc.start_distance(r_st, rg, kappa))


def test_total_angle_puts_both_ends_on_the_ring():
    """Eq 23: with the angles it sums, both end points lie on the ring around A."""
    r_st, r_end, rg, kappa = 15.0, 17.0, 20.0, 0.2
    oa = pc.start_distance(r_st, rg, kappa)
    g1, g2 = pc.angle_to_center(oa, r_st, rg), pc.angle_to_center(oa, r_end, rg)
    a = np.array([oa, 0.0])
    for r, ang in ((r_st, g1), (r_end, -g2)):
        b = r * np.array([np.cos(ang), np.sin(ang)])
        assert np.isclose(np.linalg.norm(b - a), rg)
