"""Closing and opening dynamics of the VCB mechanism by the work-energy equation.

Kang, Huang & Yang (2023) simulate the closing in ADAMS (Sec 3.2, Figs 23-25, 32) and
report the average closing velocity of the movable contact over the last third of the
contact stroke (Sec 2.1): 1.71 m/s for the vendor design, 1.17 m/s for Table 6's. The
mechanism has one degree of freedom while the cam drives the roller, so with the cam angle
theta as coordinate its kinetic energy is 1/2 J(theta) omega^2 with a
configuration-dependent generalised inertia

    J(theta) = J_cam + (m_rod + m_contacts) (ds1/dtheta)^2     before the contacts touch
    J(theta) = J_cam + m_rod (ds1/dtheta)^2                    after (the contacts stop)

and the work-energy equation gives omega(theta) directly, without an ODE:

    1/2 J omega^2 = KE_0 + eps (E_cs(0) - E_cs(theta)) - V_r(s1(theta)) - losses at impacts

E_cs is the closing springs' elastic energy, V_r the work against the general resistant
force (opening spring, contact springs, free-contact force; exact potential differences
from :mod:`camopt.cases.vcb.model`), eps the paper's mechanical efficiency (Eq 26) applied
to the driving springs' power, so that the surplus of Eq 26 is the kinetic energy left at
the end divided by eps. Time follows as t = integral d(theta) / omega on a grid graded
toward the start, theta_c = theta_end u^2, where omega is smallest.

Events, each an impact that loses kinetic energy (Carnot):
1. release: the cam turns freely through theta0 (Sec 2.2 Step 8) under the springs with
   J_cam alone, then meets the roller at rest: a plastic impact keeps the generalised
   momentum, omega+ = J_cam omega- / J(0);
2. touch: at s1 = contact gap the three moving contacts stop against the fixed ones; the
   rod goes on compressing the contact springs, omega is continuous and the contacts'
   kinetic energy 1/2 m_c v^2 is lost.
A design whose kinetic energy reaches zero before the cam has turned theta_end stalls:
the hook cannot latch (``latched`` False, closing time infinite).

The inertias are not printed in the paper (Table 1 gives densities only); they are
identified from the vendor design's dynamic data (``configs/vcb_identify_dynamics.toml``,
``docs/assumptions.md``). A scipy ODE integration of Lagrange's equation is the
cross-check in ``tests/cases/test_vcb_dynamics.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.model import Loads, VcbModel


@dataclass(frozen=True)
class Inertia:
    """Lumped inertias (SI). Each may be a float or an (n, 1) column, one per design.

    ``cam_kg_m2``: cam, shaft, spring crank and the closing springs' share, about O;
    ``rod_kg``: follower, four-bar and insulated rods as an equivalent mass moving with
    the rod travel s1; ``contacts_kg``: the three moving contacts, carried by the rod
    until they touch the fixed contacts."""

    cam_kg_m2: NDArray | float
    rod_kg: NDArray | float
    contacts_kg: NDArray | float

    def columns(self, n: int) -> Inertia:
        """The same inertias as (n, 1) columns (what the motions broadcast against)."""
        def col(v: NDArray | float) -> NDArray:
            return np.broadcast_to(np.ravel(np.asarray(v, dtype=float)), (n,))[:, None]
        return Inertia(col(self.cam_kg_m2), col(self.rod_kg), col(self.contacts_kg))


@dataclass(frozen=True)
class ClosingMotion:
    """The closing of each design, arrays (n, m) on the graded cam-angle grid and per-design
    metrics (n,). Time is measured from the release of the closing springs.

    ``theta_c`` cam angle from the cam meeting the roller (rad, (m,)); ``time`` (s);
    ``omega`` cam speed (rad/s); ``rod`` and ``rod_velocity`` rod travel s1 (m) and its
    velocity (m/s); ``contact`` and ``contact_velocity`` the movable contact's travel and
    velocity (it stops at touch); ``cam_torque`` the torque the cam passes to the roller
    (N m, negative: the follower would lift off). Per design: ``cam_contact_time`` (s),
    ``touch_time`` (s), ``touch_velocity`` (m/s), ``closing_velocity_avg`` (m/s, over the
    last third of the contact stroke, Sec 2.1), ``closing_time`` (s, to theta_end; inf if
    stalled), ``final_kinetic`` (J, at theta_end), ``touch_loss`` (J), ``latched`` and
    ``reach``, the fraction of theta_end the cam turns before it stalls (1 if latched)."""

    theta_c: NDArray
    time: NDArray
    omega: NDArray
    rod: NDArray
    rod_velocity: NDArray
    contact: NDArray
    contact_velocity: NDArray
    cam_torque: NDArray
    cam_contact_time: NDArray
    touch_time: NDArray
    touch_velocity: NDArray
    closing_velocity_avg: NDArray
    closing_time: NDArray
    final_kinetic: NDArray
    touch_loss: NDArray
    latched: NDArray
    reach: NDArray


@dataclass(frozen=True)
class OpeningMotion:
    """The opening of each design from the closed state at rest (n,): contact departure
    time (s, when the rod has travelled back to the contact gap) and the average opening
    velocity over 3/4 of the contact stroke from departure (m/s, Sec 2.1)."""

    departure_time: NDArray
    opening_velocity_avg: NDArray


def graded_grid(end: float, steps: int) -> tuple[NDArray, NDArray]:
    """theta = end (3 u^2 - 2 u^3) on u = 0..1 in ``steps`` intervals, and dtheta/du,
    (steps + 1,): fine at both ends, where the motion starts and may come almost to rest
    at the latch (dt = dtheta / omega stays integrable: omega ~ sqrt(distance) there)."""
    u = np.linspace(0.0, 1.0, steps + 1)
    return end * u * u * (3 - 2 * u), 6 * end * u * (1 - u)


def _cumulative_time(dtheta_du: NDArray, omega: NDArray, du: float) -> NDArray:
    """Cumulative integral of dtheta / omega over u by the trapezoid rule, (n, m). Where
    dtheta/du = 0 at an end the integrand is 0 if omega > 0 there, and its limit (taken as
    the neighbouring node's value) if the motion is at rest there."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = dtheta_du / omega
    for end, inner in ((0, 1), (-1, -2)):
        if np.all(np.broadcast_to(dtheta_du, g.shape)[:, end] == 0):
            g[:, end] = np.where(omega[:, end] > 0, 0.0, g[:, inner])
    out = np.zeros_like(g)
    np.cumsum(0.5 * (g[:, 1:] + g[:, :-1]) * du, axis=1, out=out[:, 1:])
    return out


def _crossing(values: NDArray, level: float | NDArray) -> tuple[NDArray, NDArray]:
    """First interval (index k, values[k-1] < level <= values[k]) where each row reaches
    ``level``, and the fraction w in it; k = 0 where it never does."""
    above = values >= level
    k = np.where(above.any(axis=1), np.argmax(above, axis=1), 0)
    rows = np.arange(len(values))
    lo, hi = values[rows, np.maximum(k - 1, 0)], values[rows, k]
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(k > 0, (level - lo) / (hi - lo), 0.0)
    return k, np.clip(np.nan_to_num(w), 0.0, 1.0)


def _at(a: NDArray, k: NDArray, w: NDArray) -> NDArray:
    """Linear interpolation of rows of ``a`` at fraction w of interval k."""
    rows = np.arange(len(a))
    return (1 - w) * a[rows, np.maximum(k - 1, 0)] + w * a[rows, k]


def free_rotation(model: VcbModel, kc: NDArray, inertia: Inertia, steps: int = 200
                  ) -> tuple[NDArray, NDArray]:
    """Cam speed (rad/s) and time (s) when the freely turning cam meets the roller, (n,):
    from rest through theta0 under the closing springs with J_cam alone."""
    inertia = inertia.columns(len(kc))
    theta0 = model.c.theta0_deg * np.pi / 180
    theta, dtheta_du = graded_grid(theta0, steps)
    extension, _ = model.closing_spring_geometry(theta, pre_rotation=0.0)
    energy = model.closing_energy(kc, extension)
    kinetic = model.c.efficiency * (energy[:, :1] - energy)
    omega = np.sqrt(np.maximum(2 * kinetic / inertia.cam_kg_m2, 0.0))
    time = _cumulative_time(dtheta_du[None, :], omega, 1.0 / steps)
    return omega[:, -1], time[:, -1]


def closing_motion(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, inertia: Inertia,
                   steps: int) -> ClosingMotion:
    """Closing of n designs (cubic ``A`` (n, 4), spring rates ``kc`` (n, 2) N/m, linkage
    ``link`` (n, 5)) by the work-energy equation on ``steps`` graded intervals."""
    c = model.c
    inertia = inertia.columns(len(A))
    end = model.theta_c[-1]
    theta, dtheta_du = graded_grid(end, steps)
    kin = model.kinematics(A, link, rod_offset, theta)
    s1, ds1 = kin.s1, kin.ds1
    extension, rate = model.closing_spring_geometry(theta)
    spring = model.closing_energy(kc, extension)
    eps = c.efficiency
    # 1. free rotation, then the plastic impact of the cam on the roller at rest
    omega_free, t_free = free_rotation(model, kc, inertia)
    moving = inertia.rod_kg + inertia.contacts_kg
    j_before = inertia.cam_kg_m2 + moving * ds1 * ds1
    omega0 = np.ravel(inertia.cam_kg_m2 * omega_free[:, None] / j_before[:, :1])
    kinetic = 0.5 * j_before[:, 0] * omega0**2
    # 2. work-energy equation up to the touch
    ke_before = kinetic[:, None] + eps * (spring[:, :1] - spring) - loads.resistant_energy(s1)
    with np.errstate(invalid="ignore"):
        omega_before = np.sqrt(np.maximum(2 * ke_before / j_before, 0.0))
    gap = loads.gap
    k, w = _crossing(s1, gap)
    touched = k > 0
    rows = np.arange(len(A))
    # the touch instant from smooth quantities only (Fr steps there, so omega_before at
    # the next node is no smooth continuation to interpolate)
    theta_touch = _at(np.broadcast_to(theta, s1.shape), k, w)
    ds1_touch = _at(ds1, k, w)
    ke_touch = (kinetic + eps * (spring[:, 0] - _at(spring, k, w))
                - loads.resistant_energy(np.full((len(A), 1), gap))[:, 0])
    with np.errstate(invalid="ignore"):
        omega_touch = np.sqrt(np.maximum(
            2 * ke_touch / (inertia.cam_kg_m2[:, 0] + moving[:, 0] * ds1_touch**2), 0.0))
    v_touch = np.where(touched, ds1_touch * omega_touch, np.nan)
    loss = np.where(touched, 0.5 * inertia.contacts_kg[:, 0] * np.nan_to_num(v_touch) ** 2,
                    0.0)
    # 3. after the touch the contacts rest; the rod goes on against the contact springs
    j_after = inertia.cam_kg_m2 + inertia.rod_kg * ds1 * ds1
    ke_after = ke_before - loss[:, None]
    with np.errstate(invalid="ignore"):
        omega_after = np.sqrt(np.maximum(2 * ke_after / j_after, 0.0))
    index = np.arange(theta.size)[None, :]
    after = touched[:, None] & (index >= k[:, None])
    omega = np.where(after, omega_after, omega_before)
    kinetic_now = np.where(after, ke_after, ke_before)
    stalled_at = np.where((kinetic_now[:, 1:] <= 0).any(axis=1),
                          np.argmax(kinetic_now[:, 1:] <= 0, axis=1) + 1, theta.size)
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
    t_k = t_touch + first_cell
    with np.errstate(divide="ignore", invalid="ignore"):
        g = dtheta_du / omega_after
    cells = 0.5 * (g[:, 1:] + g[:, :-1]) * du  # cell i - 1 .. i at column i - 1
    cells = np.where(index[:, 1:] > k[:, None], cells, 0.0)  # only whole cells after k
    t_after = t_k[:, None] + np.concatenate([np.zeros((len(A), 1)), np.cumsum(cells, axis=1)],
                                            axis=1)
    time = np.where(after, t_after, t_before)
    time = np.where(index >= stalled_at[:, None], np.inf, time)
    # 5. the paper's average closing velocity: the last third of the contact stroke
    k3, w3 = _crossing(s1, 2 * gap / 3)
    t_two_thirds = np.where(k3 > 0, _at(t_before, k3, w3), np.nan)
    latched = stalled_at == theta.size
    reached = touched & (stalled_at > k)
    with np.errstate(divide="ignore", invalid="ignore"):
        v_avg = np.where(reached, (gap / 3) / (t_touch - t_two_thirds), np.nan)
    rod_velocity = ds1 * omega
    contact_velocity = np.where(after, 0.0, rod_velocity)
    # torque the cam passes on: eps T - J_cam omega domega/dtheta (negative: lift-off)
    torque = eps * model.closing_torque(kc, (extension, rate))
    accel = 0.5 * np.gradient(omega * omega, theta, axis=1)
    cam_torque = torque - inertia.cam_kg_m2 * accel
    return ClosingMotion(
        theta_c=theta, time=time, omega=omega, rod=s1, rod_velocity=rod_velocity,
        contact=np.minimum(s1, gap), contact_velocity=contact_velocity,
        cam_torque=cam_torque, cam_contact_time=t_free,
        touch_time=np.where(reached, t_touch, np.inf), touch_velocity=v_touch,
        closing_velocity_avg=v_avg,
        closing_time=np.where(latched, time[:, -1], np.inf),
        final_kinetic=np.where(latched, kinetic_now[:, -1], 0.0), touch_loss=loss,
        latched=latched, reach=theta[stalled_at - 1] / end)


def opening_motion(travel: NDArray, loads: Loads, inertia: Inertia, efficiency: float,
                   steps: int = 400) -> OpeningMotion:
    """Opening from the closed state at rest (rod travel ``travel`` (n,) m) when the hook
    lets go: the contact and opening springs drive the rod back (eps of their work), the
    contacts stay closed until the rod reaches the gap, then a plastic impact picks them up
    (m_rod v = (m_rod + m_c) v+) and the opening spring carries both on."""
    travel = np.asarray(travel, dtype=float)[:, None]
    inertia = inertia.columns(len(travel))
    gap = loads.gap
    u = np.linspace(0.0, 1.0, steps + 1)[None, :]
    # phase 1: rod alone from the closed position to the gap, graded at the start
    s = travel - (travel - gap) * u * u
    ds_du = 2 * (travel - gap) * u
    ke = efficiency * (loads.resistant_energy(travel) - loads.resistant_energy(s))
    v = np.sqrt(np.maximum(2 * ke / inertia.rod_kg, 0.0))
    t1 = _cumulative_time(ds_du, v, 1.0 / steps)[:, -1]
    # phase 2: rod and contacts from the gap over 3/4 of the contact stroke
    v_plus = inertia.rod_kg * v[:, -1:] / (inertia.rod_kg + inertia.contacts_kg)
    s2 = gap - 0.75 * gap * u
    ke2 = (0.5 * (inertia.rod_kg + inertia.contacts_kg) * v_plus**2
           + efficiency * (loads.resistant_energy(np.full_like(s2, gap))
                           - loads.resistant_energy(s2)))
    v2 = np.sqrt(np.maximum(2 * ke2 / (inertia.rod_kg + inertia.contacts_kg), 0.0))
    t2 = _cumulative_time(np.full_like(s2, 0.75 * gap), v2, 1.0 / steps)[:, -1]
    with np.errstate(divide="ignore"):
        return OpeningMotion(departure_time=t1,
                             opening_velocity_avg=np.where(t2 > 0, 0.75 * gap / t2, np.nan))
