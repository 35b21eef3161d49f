"""What a breaker analyser reads off the multibody closing (docs/verify.md): the simulated
trace, sampled every step (:class:`Trace`), and its events (:class:`Events`:
:func:`events_of`), with the same definitions as camopt's lumped model: the cam's first
push on the roller, the contacts' touch at the gap and their velocity there, the average
contact velocity over the last third of the contact stroke, the end of travel, the latch
energy, the least cam-roller torque, and after the touch the wipe, the rod's over-travel,
the contacts' bounce and rebound. Its own module: reading a trace needs no engine."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.mechanism import Mechanism

__all__ = ["LEAST_FROM", "Events", "Trace", "events_of"]

LEAST_FROM = 0.1
"""The least cam-roller torque is looked for from this fraction of the cam's travel on,
after the pick-up's ringing (in both models)."""

@dataclass(frozen=True)
class Trace:
    """The simulated closing, sampled every step: time (s), cam angle theta_c (rad) and
    speed (rad/s), rod and contact travel from the opened position (m) and velocities
    (m/s), the cam-roller normal force (N) and its torque on the cam (N m, about O,
    against its rotation when positive), and the kinetic energy of all bodies (J)."""

    time: NDArray
    cam_angle: NDArray
    cam_speed: NDArray
    rod: NDArray
    rod_velocity: NDArray
    contact: NDArray
    contact_velocity: NDArray
    normal_force: NDArray
    roller_torque: NDArray
    kinetic: NDArray


@dataclass(frozen=True)
class Events:
    """What the closing is judged by (SI), times from the release of the closing springs:
    ``cam_contact_time`` the cam first pushes the roller; ``touch_time`` the moving
    contacts meet the fixed ones, ``touch_velocity`` their velocity just before;
    ``contact_velocity_avg`` the breaker analyser's average over the last third of the
    contact stroke (gap/3 over the time between the travel points 2 gap/3 and gap);
    ``end_time`` the cam at the end of its travel, ``latch_energy`` the kinetic energy
    then (nan: it stopped first); ``least_roller_torque`` the least torque the cam passes to
    the roller (N m, the normal force's moment about O) from :data:`LEAST_FROM` of the
    cam's travel to its end (0: the roller lifts off). After the touch (to the end of
    travel): ``wipe_at_end`` the contact springs' compression beyond their preload when the
    cam reaches its end (rod travel less contact travel, m); ``rod_over_travel`` how far
    the rod's travel after the touch exceeds its travel at the end (m, the linkage's
    overshoot on the contact springs); ``bounce_time`` the time the moving contacts spend
    off the fixed ones after the first touch (s) and ``rebound`` their greatest reopening
    (m); ``arrivals`` how many times they arrive at the gap."""

    cam_contact_time: float
    touch_time: float
    touch_velocity: float
    contact_velocity_avg: float
    end_time: float
    latch_energy: float
    least_roller_torque: float
    wipe_at_end: float = math.nan
    rod_over_travel: float = math.nan
    bounce_time: float = math.nan
    rebound: float = math.nan
    arrivals: int = 0


def _crossing(t: NDArray, y: NDArray, level: float) -> tuple[float, int]:
    """First time ``y`` reaches ``level`` (linear between samples) and the sample index
    at or after it; (nan, -1) if it never does."""
    above = np.flatnonzero(y >= level)
    if not len(above):
        return math.nan, -1
    k = int(above[0])
    if k == 0:
        return float(t[0]), 0
    w = (level - y[k - 1]) / (y[k] - y[k - 1])
    return float(t[k - 1] + w * (t[k] - t[k - 1])), k


def events_of(mech: Mechanism, tr: Trace) -> Events:
    """The closing's events read from its trace (linear interpolation between steps)."""
    pushing = np.flatnonzero(tr.normal_force > 0)
    t_cam = float(tr.time[pushing[0]]) if len(pushing) else math.nan
    t_touch, k = _crossing(tr.time, tr.contact, mech.gap)
    if k > 0:
        # the velocity on arrival: the last sample before the fixed contact acts,
        # extrapolated to the crossing with the step's acceleration
        v0, v1 = tr.contact_velocity[k - 2], tr.contact_velocity[k - 1]
        t0, t1 = tr.time[k - 2], tr.time[k - 1]
        v_touch = float(v1 + (v1 - v0) / (t1 - t0) * (t_touch - t1))
    else:
        v_touch = math.nan
    t_two_thirds, _ = _crossing(tr.time, tr.contact, 2 * mech.gap / 3)
    v_avg = (mech.gap / 3) / (t_touch - t_two_thirds)
    t_end, j = _crossing(tr.time, tr.cam_angle, mech.cam_end)
    if j > 0:
        w = (t_end - tr.time[j - 1]) / (tr.time[j] - tr.time[j - 1])
        latch = float((1 - w) * tr.kinetic[j - 1] + w * tr.kinetic[j])
    else:
        latch = math.nan
    # the pick-up rings for a few periods of the contact's stiffness against the
    # linkage: the least force is taken from a tenth of the cam's travel on
    window = tr.cam_angle >= LEAST_FROM * mech.cam_end
    if j > 0:
        window[j:] = False
    least_torque = float(tr.roller_torque[window].min()) if window.any() else math.nan
    if k <= 0:
        return Events(t_cam, t_touch, v_touch, v_avg, t_end, latch, least_torque)
    after = slice(k, j if j > 0 else len(tr.time))  # from the touch to the end of travel
    last = (j if j > 0 else len(tr.time)) - 1
    wipe = float(tr.rod[last] - tr.contact[last])
    over = float(tr.rod[after].max() - tr.rod[last])
    apart = tr.contact[after] < mech.gap
    dt = np.diff(tr.time[after], append=tr.time[last])
    bounce = float(dt[apart].sum())
    rebound = float(max(0.0, mech.gap - tr.contact[after].min()))
    at = tr.contact >= mech.gap
    arrivals = int(np.sum(at[1:] & ~at[:-1]))
    return Events(t_cam, t_touch, v_touch, v_avg, t_end, latch, least_torque, wipe, over,
                  bounce, rebound, arrivals)
