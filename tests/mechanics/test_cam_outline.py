"""The closed cam outline (camopt.mechanics.cam_outline): its quintic against scipy's
BPoly, C2 joints, a start on the base circle, the rise untouched, and angles that do not
depend on the sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import BPoly

from camopt.mechanics import cam
from camopt.mechanics.cam_outline import closed_outline, hermite5

# a VCB-like geometry (Kang 2023 Sec 2.3: l2 70 mm, B at (-72, -55) mm, rb 23, rf 15 mm)
L2, L6, RB, RF = 0.070, math.hypot(0.072, 0.055), 0.023, 0.015
XI = float(cam.base_angle(L2, L6, RB + RF))
END = math.radians(140.0)
LAW = np.array([0.0151851, 0.143538, 0.0747194, -0.0266738])  # a fitted cubic, rad


@given(st.lists(st.floats(-3, 3), min_size=6, max_size=6), st.floats(0.05, 2.0))
@settings(max_examples=50, deadline=None)
def test_hermite5_is_scipys_quintic_through_the_same_ends(ends, span):
    start, end = np.array(ends[:3]), np.array(ends[3:])
    u = np.linspace(0, 1, 11)
    poly = BPoly.from_derivatives([0.0, span], [start, end])
    got = hermite5(u, start, end, span)
    for k in range(3):  # value, slope, curvature: two code paths, rtol 1e-9
        want = poly.derivative(k)(u * span) if k else poly(u * span)
        assert np.allclose(got[k], want, rtol=1e-9, atol=1e-9 * (1 + np.abs(want).max()))


@pytest.fixture(scope="module")
def outline():
    return closed_outline(LAW, END, 140, XI, L2, L6, RF, RF)


def test_rise_is_the_design_law_on_the_case_grid(outline):
    theta = np.linspace(0.0, END, 141)
    f = cam.Follower.polynomial(LAW[None, :], theta, XI)
    xp, yp, dxp, dyp = cam.pitch_curve(L2, L6, f)
    xc, yc = cam.profile(xp, yp, dxp, dyp, RF)
    assert np.array_equal(outline.theta[outline.rise], theta)  # same computation: identical
    assert np.array_equal(outline.profile[outline.rise], np.column_stack([xc[0], yc[0]]))
    assert np.array_equal(outline.pressure_angle[outline.rise],
                          cam.pressure_angle(L2, L6, f)[0])
    assert np.array_equal(outline.curvature[outline.rise],
                          cam.curvature_radius(L2, L6, f, RF)[0])


def test_starts_on_the_base_circle_and_closes_over_one_turn(outline):
    assert np.hypot(*outline.profile[0]) == pytest.approx(RB, abs=1e-12)
    assert outline.phi[0] == 0 and outline.dphi[0] == 0
    steps = np.diff(np.r_[outline.theta, outline.theta[0] + 2 * np.pi])
    assert np.all(steps > 0) and steps.max() <= math.radians(1.0) + 1e-12
    names = [s.name for s in outline.segments]
    assert names == ["approach", "rise", "run-out", "top dwell", "return", "base dwell"]
    assert outline.segments[-1].end - outline.segments[0].start == pytest.approx(2 * np.pi)


def _joint_jumps(o, values):
    """At each joint, the change of ``values`` over the sample interval holding it."""
    theta = np.r_[o.theta, o.theta[0] + 2 * np.pi]
    v = np.r_[values, values[:1]]
    at = np.searchsorted(theta, [s.start for s in o.segments[1:]], side="right") - 1
    return np.abs(v[at + 1] - v[at])


def _turns(o):
    """The angle between successive edges of the closed profile polyline (rad), (m,)."""
    e = np.diff(np.vstack([o.profile, o.profile[:1]]), axis=0)
    e = np.vstack([e, e[:1]])
    cross = e[:-1, 0] * e[1:, 1] - e[:-1, 1] * e[1:, 0]
    return np.abs(np.arctan2(cross, np.sum(e[:-1] * e[1:], axis=1)))


def test_every_joint_is_c2(outline):
    """Each segment's own law at its end gives the next one's phi, phi', phi'' at its
    start (the last's end is the first's start): rtol 1e-9 of the rise's scale."""
    segs = outline.segments
    scale = np.max(np.abs(np.stack([s.ends for s in segs])), axis=(0, 1))
    for a, b in zip(segs, segs[1:] + segs[:1]):
        assert np.allclose(a.ends[1], b.ends[0], rtol=0, atol=1e-9 * scale.max()), a.name
    assert np.array_equal(segs[0].ends[0], np.zeros(3))  # on the base circle, at rest


def test_the_drawn_profile_is_tangent_continuous():
    """Halving the step halves the largest turn between the profile's edges and the
    change of phi, phi' over the interval holding each joint; a kink would stay (< 0.6)."""
    coarse, fine = (closed_outline(LAW, END, 140, XI, L2, L6, RF, RF, math.radians(h))
                    for h in (0.5, 0.25))
    for name in ("phi", "dphi"):
        assert np.all(_joint_jumps(fine, getattr(fine, name))
                      < 0.6 * _joint_jumps(coarse, getattr(coarse, name)) + 1e-12), name
    assert np.max(_turns(fine)) < 0.6 * np.max(_turns(coarse))


def test_closure_is_monotone_and_within_the_rise_limits(outline):
    closed = outline.closure()
    start, stop = outline.segments[0], outline.segments[2]
    approach = (outline.theta < 0)
    assert np.all(np.diff(outline.phi[approach]) >= 0)  # never under the base circle
    assert np.all(outline.phi >= -1e-15)
    assert np.all(outline.phi[approach] <= LAW[0])  # never reaches the resting roller
    psi_rise = np.max(np.abs(outline.pressure_angle[outline.rise]))
    assert np.max(np.abs(outline.pressure_angle[closed])) <= psi_rise + 1e-12
    convex, _ = outline.radii(closed)
    assert convex >= RF
    for seg in (start, stop):  # whole degrees
        span = math.degrees(seg.end - seg.start)
        assert span == pytest.approx(round(span), abs=1e-9)


def test_angles_do_not_depend_on_the_sampling(outline):
    fine = closed_outline(LAW, END, 140, XI, L2, L6, RF, RF, math.radians(0.1))
    for a, b in zip(outline.segments, fine.segments):
        assert (a.name, a.start, a.end) == (b.name, b.start, b.end)
        assert np.array_equal(a.ends, b.ends)
    assert outline.phi.max() == pytest.approx(fine.phi.max(), rel=1e-12)  # the top dwell


def test_the_closure_splits_the_rest_of_the_turn_exactly(outline):
    """The closure's decision pinned: what the approach, the rise and the run-out leave of
    the turn goes a quarter to the top dwell, half to the 3-4-5 return and a quarter to
    the base dwell (rtol 1e-12 of a turn: sums of the same floats in another order); the
    run-out overtravels by the rise's end slope times half its span (phi' and phi''
    zero at the top), and every segment
    starts where the one before ends, the last a turn after the first."""
    s = {seg.name: seg for seg in outline.segments}
    left = 2 * np.pi - (s["approach"].end - s["approach"].start) - END - (
        s["run-out"].end - s["run-out"].start)
    span = {name: seg.end - seg.start for name, seg in s.items()}
    assert span["top dwell"] == pytest.approx(left / 4, rel=1e-12)
    assert span["return"] == pytest.approx(left / 2, rel=1e-12)
    assert span["base dwell"] == pytest.approx(left / 4, rel=1e-12)
    for before, after in zip(outline.segments, outline.segments[1:]):
        assert after.start == before.end, after.name
    assert outline.segments[-1].end == pytest.approx(outline.segments[0].start + 2 * np.pi,
                                                     rel=0, abs=1e-12)
    k = np.arange(LAW.size)
    slope = float(LAW[1:] @ (k[1:] * END ** (k[1:] - 1)))
    top = float(LAW @ END ** k) + slope * span["run-out"] / 2
    # the ends as each segment's quintic evaluates them: round-off of O(1) terms
    np.testing.assert_allclose(s["run-out"].ends[1], [top, 0.0, 0.0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(s["top dwell"].ends, [[top, 0, 0], [top, 0, 0]], rtol=1e-12,
                               atol=1e-12)
    np.testing.assert_allclose(s["base dwell"].ends, 0.0, atol=1e-12)
