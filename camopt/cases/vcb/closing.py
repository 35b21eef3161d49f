"""The driven closing in numpy (the reference the compiled kernel follows): the state of
the cam driving the roller from the pick-up impact to the latch, by the work-energy
equation on the graded cam-angle grid (:mod:`camopt.cases.vcb.dynamics` states the
equations), and the events and curves read from it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.locate import _at, _crossing, _cumulative_time, first_zero, graded_grid
from camopt.cases.vcb.model import Loads, VcbModel
from camopt.cases.vcb.motion import (
    ClosingCurves,
    ClosingEvents,
    ClosingMotion,
    MotionParameters,
    ParameterColumns,
    least_torque,
)
from camopt.cases.vcb.rotation import (
    free_steps,
    release_angle,
    release_torque_ratio,
    rotation_of,
    start_shortfall,
)

DAMPING_PASSES = 4
"""Fixed-point passes for a rod dashpot's work (:func:`closing_state`): each pass's
speed error is the previous one's times the dashpot's share of the energy lost
(250 N s/m, a sixth: 4 passes leave ~1e-3 of it; a test compares the ODE)."""


@dataclass(frozen=True)
class ClosingState:
    """Everything the closing's events and curves are read from, for n rows (designs, or
    sets x designs): the graded cam-angle grid ``theta`` (m,) with ``dtheta_du`` and the
    step ``du``; the kinematics ``s1``, ``ds1`` (n, m); the springs' driving torque
    ``drive`` (eps T_s - T_f, N m, (n, m)); the parameters ``p``; the free rotation's
    ``t_free``, ``release_ratio`` (n,); the speeds and energies before and after the
    contacts' touch (n, m); the touch interval ``k``, fraction ``w`` and instant
    (``theta_touch``, ``t_touch``, ``t_k`` the first node after it); ``stall_theta`` where
    the kinetic energy first reaches zero (nan: never) and ``stalled_at``, the first node
    at or beyond it (m if none); ``pickup_loss`` the pick-up impact's loss (J, (n,));
    ``shortfall`` how far the release is from starting the cam (n,;
    :func:`~camopt.cases.vcb.rotation.start_shortfall`). Built by :func:`closing_state`;
    read by the pure :func:`events_of` and :func:`curves_of`."""

    theta: NDArray
    dtheta_du: NDArray
    du: float
    gap: float
    s1: NDArray
    ds1: NDArray
    drive: NDArray
    p: ParameterColumns
    t_free: NDArray
    release_ratio: NDArray
    omega_before: NDArray
    omega_after: NDArray
    kinetic: NDArray
    after: NDArray
    k: NDArray
    touched: NDArray
    v_touch: NDArray
    loss: NDArray
    t_before: NDArray
    t_touch: NDArray
    t_k: NDArray
    cells: NDArray
    stall_theta: NDArray
    stalled_at: NDArray
    pickup_loss: NDArray
    shortfall: NDArray

    @property
    def latched(self) -> NDArray:
        """(n,) bool: the kinetic energy stays positive to the end of the stroke."""
        return np.isnan(self.stall_theta)


def closing_inputs(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, theta: NDArray,
                   pre: NDArray | None = None
                   ) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """What the closing of n designs needs from their geometry on the cam-angle nodes
    ``theta`` (m,), each (n, m), independent of the motion parameters: the follower rate
    phi', the rod travel s1 (m) and ds1/dtheta (m/rad), the closing springs' energy (J)
    and torque (N m), the resisting springs' energy V_r(s1) (J) and torque
    Fr ds1/dtheta (N m). ``pre`` (n, 2) m: each design's closing-spring compressions in
    the opened state (else the config's)."""
    kin = model.kinematics(A, link, rod_offset, theta)
    extension, rate = model.closing_spring_geometry(theta)
    spring = model.closing_energy(kc, extension, pre)
    springs_torque = model.closing_torque(kc, (extension, rate), pre)
    resisting = loads.resistant_energy(kin.s1)
    resisting_torque = loads.resistant_force(kin.s1) * kin.ds1  # Fr ds1/dtheta
    return kin.dphi, kin.s1, kin.ds1, spring, springs_torque, resisting, resisting_torque


def closing_state(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                  rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
                  steps: int, sets: int = 1, pre: NDArray | None = None) -> ClosingState:
    """The closing of n designs (follower law ``A`` (n, d + 1), spring rates ``kc``
    (n, 2) N/m, linkage ``link`` (n, 5)) from the release of the closing springs, by the
    work-energy equation on ``steps`` graded intervals of the cam angle, for ``sets``
    parameter sets per design (``params`` holds that many for every design,
    :meth:`MotionParameters.repeat`, set-major; the rows are sets x designs). The
    kinematics and the resisting springs' work, which do not depend on the parameters,
    are computed once per design. ``pre`` (n, 2) m: each design's closing-spring
    compressions in the opened state (else the config's)."""
    n = len(A) * sets
    p = params.columns(n, model.c.efficiency)
    theta, dtheta_du = graded_grid(model.theta_c[-1], steps)
    dphi, s1, ds1, spring, springs_torque, resisting, resisting_torque = closing_inputs(
        model, A, kc, link, rod_offset, loads, theta, pre)
    if sets > 1:
        dphi, s1, ds1, spring, springs_torque, resisting, resisting_torque, kc = (
            np.tile(a, (sets, 1)) for a in (dphi, s1, ds1, spring, springs_torque, resisting,
                                            resisting_torque, kc))
        loads = loads.tiled(sets)
        pre = None if pre is None else np.tile(pre, (sets, 1))
    eps, friction = p.efficiency, p.friction_nm
    # the closing springs' own mass (spring_kg, at their free ends) turns with the cam
    rate2 = model.closing_spring_geometry(theta)[1] ** 2 if np.any(p.spring_kg) else 0 * theta
    follower = p.follower_kg_m2 * dphi * dphi + p.spring_kg * rate2  # J_f phi'^2 (+ springs)
    # 1. free rotation, then the plastic impact of the cam on the roller at rest
    release_ratio = release_torque_ratio(model, kc, p, pre)
    omega_free, t_free = rotation_of(model, kc, p, free_steps(steps), pre, release_ratio)
    moving = p.rod_kg + p.contacts_kg
    j_before = p.cam_kg_m2 + follower + moving * ds1 * ds1
    j_free = p.cam_kg_m2[:, 0] + p.spring_kg[:, 0] * rate2[0]  # what turned before it
    omega0 = np.ravel(j_free[:, None] * omega_free[:, None] / j_before[:, :1])
    kinetic0 = 0.5 * j_before[:, 0] * omega0**2
    # Carnot: what the impact takes is the relative motion's energy, 1/2 J* omega_free^2
    pickup_loss = 0.5 * j_free * omega_free**2 - kinetic0
    # 2. work-energy equation up to the touch
    ke_before0 = kinetic0[:, None] + eps * (spring[:, :1] - spring) - resisting
    ke_before0 -= friction * theta
    gap = loads.gap
    k, w = _crossing(s1, gap)
    touched = k > 0
    rows = np.arange(n)
    index = np.arange(theta.size)[None, :]
    after = touched[:, None] & (index >= k[:, None])
    # the touch instant from smooth quantities only (Fr steps there, so omega_before at
    # the next node is no smooth continuation to interpolate)
    theta_touch = _at(theta[None, :], k, w)
    ds1_touch = _at(ds1, k, w)
    dphi_touch = _at(dphi, k, w)
    ke_touch0 = (kinetic0 + eps[:, 0] * (spring[:, 0] - _at(spring, k, w))
                 - loads.resistant_energy(np.full((n, 1), gap))[:, 0]
                 - friction[:, 0] * theta_touch)
    j_touch = (p.cam_kg_m2[:, 0] + p.follower_kg_m2[:, 0] * dphi_touch**2
               + p.spring_kg[:, 0] * _at(np.broadcast_to(rate2, ds1.shape), k, w)
               + moving[:, 0] * ds1_touch**2)
    j_after = p.cam_kg_m2 + follower + p.rod_kg * ds1 * ds1
    # a rod dashpot takes c ds1'^2 omega dtheta: its work depends on the speed it
    # brakes, found by fixed-point iteration from the undamped speed (each pass one
    # cumulative trapezoid; DAMPING_PASSES of them)
    damped = bool(np.any(p.rod_damping_n_s_per_m))
    lost = np.zeros_like(ke_before0)
    for _ in range(DAMPING_PASSES if damped else 1):
        ke_before = ke_before0 - lost
        ke_touch = ke_touch0 - (_at(lost, k, w) if damped else 0.0)
        with np.errstate(invalid="ignore"):
            omega_before = np.sqrt(np.maximum(2 * ke_before / j_before, 0.0))
            omega_touch = np.sqrt(np.maximum(2 * ke_touch / j_touch, 0.0))
        v_touch = np.where(touched, ds1_touch * omega_touch, np.nan)
        loss = np.where(touched, 0.5 * p.contacts_kg[:, 0] * np.nan_to_num(v_touch) ** 2,
                        0.0)
        # 3. after the touch the contacts rest; the rod goes on against the contact springs
        ke_after = ke_before - loss[:, None]
        with np.errstate(invalid="ignore"):
            omega_after = np.sqrt(np.maximum(2 * ke_after / j_after, 0.0))
        if damped:
            brake = (p.rod_damping_n_s_per_m * ds1 * ds1
                     * np.where(after, omega_after, omega_before))
            lost = np.zeros_like(brake)
            np.cumsum(0.5 * (brake[:, 1:] + brake[:, :-1]) * np.diff(theta), axis=1,
                      out=lost[:, 1:])
    kinetic = np.where(after, ke_after, ke_before)
    # the first zero of the kinetic energy, between nodes too: its slope is the net torque
    # (the dashpot's share is 0 where the energy is: omega = 0)
    drive = eps * springs_torque - friction
    stall_theta = first_zero(theta, kinetic, drive - resisting_torque)
    # a cam the springs cannot turn away from its release (friction at least their torque)
    # never reaches the roller: nothing of the closing happens
    stall_theta = np.where(np.isfinite(t_free), stall_theta, 0.0)
    stalled_at = np.where(np.isnan(stall_theta), theta.size,
                          np.searchsorted(theta, np.nan_to_num(stall_theta)))
    stalled_at = np.where(np.isfinite(t_free), np.maximum(stalled_at, 1), 1)
    # 4. time: before the touch from omega_before; after it from the touch instant on
    du = 1.0 / steps
    t_before = t_free[:, None] + _cumulative_time(dtheta_du[None, :], omega_before, du)
    km = np.maximum(k - 1, 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        last_cell = (theta_touch - theta[km]) * 0.5 * (1 / omega_before[rows, km]
                                                       + 1 / omega_touch)
    t_touch = np.where(touched, t_before[rows, km] + last_cell, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        first_cell = (theta[k] - theta_touch) * 0.5 * (1 / omega_touch + 1 / omega_after[rows, k])
        g = dtheta_du / omega_after
    cells = 0.5 * (g[:, 1:] + g[:, :-1]) * du  # cell i - 1 .. i at column i - 1
    cells = np.where(index[:, 1:] > k[:, None], cells, 0.0)  # only whole cells after k
    # a stall inside the touch's interval comes before or after the touch itself
    reached = touched & ~(stall_theta <= theta_touch)
    return ClosingState(
        theta=theta, dtheta_du=dtheta_du, du=du, gap=gap, s1=s1, ds1=ds1, drive=drive, p=p,
        t_free=t_free, release_ratio=release_ratio,
        omega_before=omega_before, omega_after=omega_after, kinetic=kinetic, after=after,
        k=k, touched=reached, v_touch=v_touch, loss=loss, t_before=t_before,
        t_touch=t_touch, t_k=t_touch + first_cell, cells=cells, stall_theta=stall_theta,
        stalled_at=stalled_at, pickup_loss=pickup_loss,
        shortfall=start_shortfall(release_angle(model, p.release_offset_rad[:, 0]),
                                  release_ratio, float(theta[-1])))


def events_of(s: ClosingState) -> ClosingEvents:
    """The closing's events (n,) read from its state (no curves: what a band member
    gives): the end time is the last node's, after the touch if it came (the running
    sum's last term: the same bits as :func:`curves_of`'s last time)."""
    touched = s.k > 0
    t_end = np.where(touched, s.t_k + np.cumsum(s.cells, axis=1)[:, -1], s.t_before[:, -1])
    return ClosingEvents(closing_time=np.where(s.latched, t_end, np.inf), **_events(s))


def _events(s: ClosingState) -> dict[str, NDArray]:
    """The events both readings share (all but the closing time)."""
    end = s.theta[-1]
    # the paper's average closing velocity: the last third of the contact stroke
    k3, w3 = _crossing(s.s1, 2 * s.gap / 3)
    t_two_thirds = np.where(k3 > 0, _at(s.t_before, k3, w3), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        v_avg = np.where(s.touched, (s.gap / 3) / (s.t_touch - t_two_thirds), np.nan)
    latched = s.latched
    return dict(
        cam_contact_time=s.t_free, touch_time=np.where(s.touched, s.t_touch, np.inf),
        touch_velocity=s.v_touch, closing_velocity_avg=v_avg,
        final_kinetic=np.where(latched, s.kinetic[:, -1], 0.0), touch_loss=s.loss,
        latched=latched, reach=np.where(latched, 1.0, np.nan_to_num(s.stall_theta) / end
                                        - s.shortfall),
        release_torque_ratio=s.release_ratio, pickup_loss=s.pickup_loss)


def curves_of(s: ClosingState) -> ClosingCurves:
    """The closing's curves (n, m) read from its state."""
    n = len(s.s1)
    index = np.arange(s.theta.size)[None, :]
    t_after = s.t_k[:, None] + np.concatenate([np.zeros((n, 1)), np.cumsum(s.cells, axis=1)],
                                              axis=1)
    time = np.where(s.after, t_after, s.t_before)
    time = np.where(index >= s.stalled_at[:, None], np.inf, time)
    omega = np.where(s.after, s.omega_after, s.omega_before)
    rod_velocity = s.ds1 * omega
    contact_velocity = np.where(s.after, 0.0, rod_velocity)
    # torque the cam passes on: eps T - T_f - J_cam omega domega/dtheta (negative: lift-off)
    accel = 0.5 * np.gradient(omega * omega, s.theta, axis=1)
    cam_torque = s.drive - s.p.cam_kg_m2 * accel
    return ClosingCurves(
        theta_c=s.theta, time=time, omega=omega, rod=s.s1, rod_velocity=rod_velocity,
        contact=np.minimum(s.s1, s.gap), contact_velocity=contact_velocity,
        cam_torque=cam_torque)


def motion_of(s: ClosingState) -> ClosingMotion:
    """The closing's events, least cam torque and curves read from its state."""
    curves = curves_of(s)
    return ClosingMotion(**vars(events_of(s)), cam_torque_min=least_torque(curves),
                         curves=lambda: curves)
