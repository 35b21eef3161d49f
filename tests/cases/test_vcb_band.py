"""A VCB design's closing band (camopt/cases/vcb/band.py): its extremes over the
identified parameters and the band's other sets, computed on given events (exact: a
least, a greatest, an all and a count of the given values)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from camopt.cases.vcb.band import BANDED, MotionBand, band_ends


def _events(latched, velocity, kinetic):
    """Stand-in closing events: the given latch flags, velocities and energies; every
    other field the velocity (only the reductions are under test)."""
    v = np.asarray(velocity, dtype=float)
    return SimpleNamespace(latched=np.asarray(latched, dtype=bool), closing_velocity_avg=v,
                           final_kinetic=np.asarray(kinetic, dtype=float), reach=v,
                           release_torque_ratio=v,
                           **{field: v for field, _, _ in BANDED.values()})


def test_latched_only_when_every_set_latches():
    """Three designs under the identified set and two more (set-major): the first latches
    under all three, the second misses under one member, the third under the nominal
    set alone. Latched needs every set (not some): [1, 0, 0]; the count of sets that do
    not latch is [0, 1, 1]."""
    nominal = _events([True, True, False], [1.0, 1.1, 0.9], [3.0, 2.0, 1.0])
    members = _events([True, True, True, True, False, True],
                      [0.8, 1.2, 1.0, 0.95, np.nan, 0.7], [2.5, 4.0, 0.5, 3.5, 1.5, 2.0])
    band = MotionBand.of(nominal, members, 2)
    assert band.latched.tolist() == [True, False, False]
    assert band.not_latched.tolist() == [0, 1, 1]
    assert band.sets == 3
    # a stalled set (NaN velocity) counts as 0 m/s at the low end
    assert band.velocity_low.tolist() == [0.8, 0.0, 0.7]
    assert band.velocity_high.tolist() == [1.0, 1.2, 1.0]
    assert band.kinetic_low.tolist() == [2.5, 1.5, 0.5]
    assert band.kinetic_high.tolist() == [3.5, 4.0, 2.0]


def test_a_band_of_the_nominal_set_alone_is_that_set():
    nominal = _events([True, False], [1.0, 0.5], [3.0, 1.0])
    band = MotionBand.of(nominal)
    assert band.latched.tolist() == [True, False] and band.sets == 1
    assert band.not_latched.tolist() == [0, 1]


def test_band_ends_put_low_and_high_before_the_unit():
    assert band_ends("touch_time_ms") == ("touch_time_low_ms", "touch_time_high_ms")
    assert band_ends("touch_velocity_m_s") == ("touch_velocity_low_m_s",
                                               "touch_velocity_high_m_s")


def test_merged_motion_and_band_put_each_group_s_rows_back():
    """Two groups' closings and bands merged into five rows: every per-design field, the
    curves (on first read; the grid once) and the set counts in row order, exactly (a
    copy, no arithmetic)."""
    from camopt.cases.vcb.band import merged_band, merged_motion
    from camopt.cases.vcb.motion import ClosingCurves, ClosingEvents, ClosingMotion

    groups = [np.array([0, 3]), np.array([1, 2, 4])]
    grid = np.linspace(0.0, 1.0, 4)

    def motion(values):
        v = np.asarray(values, dtype=float)
        curves = ClosingCurves(theta_c=grid, **{
            f: v[:, None] + grid for f in ("time", "omega", "rod", "rod_velocity",
                                            "contact", "contact_velocity", "cam_torque")})
        events = {f: v.copy() for f in ClosingEvents.__dataclass_fields__}
        events["latched"] = v > 2
        return ClosingMotion(cam_torque_min=-v, curves=lambda: curves, **events)

    motions = [motion([0.0, 3.0]), motion([1.0, 2.0, 4.0])]
    got = merged_motion(motions, groups, 5)
    np.testing.assert_array_equal(got.touch_velocity, [0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(got.cam_torque_min, [-0.0, -1.0, -2.0, -3.0, -4.0])
    np.testing.assert_array_equal(got.latched, [False, False, False, True, True])
    np.testing.assert_array_equal(got.theta_c, grid)
    np.testing.assert_array_equal(got.rod, np.arange(5.0)[:, None] + grid)
    bands = [MotionBand.of(motions[0]), MotionBand.of(motions[1])]
    bands[1] = MotionBand(**{**bands[1].__dict__, "sets": 8})
    band = merged_band(bands, groups, 5)
    np.testing.assert_array_equal(band.sets, [1, 8, 8, 1, 8])
    np.testing.assert_array_equal(band.velocity_low, [0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(band.not_latched, [1, 1, 1, 0, 0])
    for field in band.low:
        np.testing.assert_array_equal(band.high[field], [0.0, 1.0, 2.0, 3.0, 4.0])
