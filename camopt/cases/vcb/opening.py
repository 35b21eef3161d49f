"""The opening from the closed state at rest: the contact and opening springs drive the
linkage back (Sec 3.2; :mod:`camopt.cases.vcb.dynamics` states the equations)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.locate import _at, _crossing
from camopt.cases.vcb.model import Loads, VcbModel
from camopt.cases.vcb.motion import MotionParameters, OpeningMotion


def _path(model: VcbModel, link: NDArray, rod_offset: NDArray | float, start: NDArray,
          stop: NDArray, u: NDArray, graded: bool) -> tuple[NDArray, NDArray, NDArray]:
    """The linkage moved by its follower angle alone (no cam): phi from ``start`` to
    ``stop`` (n,) rad, quadratically in u (graded at the start) or linearly. Returns the
    rod travel from the start (m), ds1/du and dphi/du, (n, m)."""
    span = stop - start
    zero = np.zeros_like(start)
    # a "cubic" in u with phi(u) = start + span u^2 (or span u): the four-bar and rod of
    # :meth:`VcbModel.kinematics` evaluated along any follower path
    A = (np.column_stack([start, zero, span, zero]) if graded
         else np.column_stack([start, span, zero, zero]))
    kin = model.kinematics(A, link, rod_offset, u)
    return kin.s1, kin.ds1, kin.dphi


def opening_motion(model: VcbModel, A: NDArray, link: NDArray, rod_offset: NDArray | float,
                   loads: Loads, params: MotionParameters, steps: int = 400) -> OpeningMotion:
    """Opening of n designs from the closed state at rest (the follower at the cubic's end
    value) when the hook lets go: eps of the contact and opening springs' work drives the
    linkage back with J(phi) = J_f + m_rod (ds1/dphi)^2; the contacts stay closed until the
    rod is back at the gap, where a plastic impact picks them up (generalised momentum
    kept), and the opening spring carries all to s1 = 0."""
    n = len(A)
    p = params.columns(n, model.c.efficiency)
    eps = p.efficiency
    end = model.theta_c[-1]
    phi_open = A[:, 0]
    phi_closed = A @ end ** np.arange(A.shape[1])
    u = np.linspace(0.0, 1.0, steps + 1)
    # phase 1: from the closed state (phi_closed, at rest) toward the opened one
    s_rel, ds_du, dphi_du = _path(model, link, rod_offset, phi_closed, phi_open, u, True)
    travel = -s_rel[:, -1:]  # rod travel of the closed state, from the opened one
    s = travel + s_rel
    j1 = p.follower_kg_m2 * dphi_du**2 + p.rod_kg * ds_du**2
    ke1 = eps * (loads.resistant_energy(travel) - loads.resistant_energy(s))
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.sqrt(j1 / (2 * ke1))  # du / dt inverted
    g[:, 0] = g[:, 1]  # 0/0 at rest; the limit is finite (both vanish as u^2)
    t1 = np.zeros_like(g)
    np.cumsum(0.5 * (g[:, 1:] + g[:, :-1]) / steps, axis=1, out=t1[:, 1:])
    k, w = _crossing(-s, -loads.gap)
    departure = np.where(k > 0, _at(t1, k, w), np.inf)
    phi_gap = _at(phi_closed[:, None] + (phi_open - phi_closed)[:, None] * u * u, k, w)
    ke_gap = eps[:, 0] * (loads.resistant_energy(travel[:, 0]) - loads.resistant_energy(
        np.full(n, loads.gap)))
    # phase 2: contacts picked up at the gap; from phi_gap to the opened state, linearly
    s2_rel, ds2_du, dphi2_du = _path(model, link, rod_offset, phi_gap, phi_open, u, False)
    s2 = loads.gap + s2_rel
    # the plastic pick-up keeps the generalised momentum on phase 2's coordinate:
    # KE+ = KE- J- / J+ with J- without, J+ with the contacts, both at the gap
    j_pick = (p.follower_kg_m2 * dphi2_du**2 + p.rod_kg * ds2_du**2)[:, 0]
    j2 = p.follower_kg_m2 * dphi2_du**2 + (p.rod_kg + p.contacts_kg) * ds2_du**2
    ke_plus = ke_gap * j_pick / j2[:, 0]
    ke2 = ke_plus[:, None] + eps * (loads.resistant_energy(np.full((n, 1), loads.gap))
                                    - loads.resistant_energy(s2))
    with np.errstate(divide="ignore", invalid="ignore"):
        g2 = np.sqrt(j2 / (2 * np.maximum(ke2, 0.0)))
    t2 = np.zeros_like(g2)
    np.cumsum(0.5 * (g2[:, 1:] + g2[:, :-1]) / steps, axis=1, out=t2[:, 1:])
    quarter = _crossing(-s2, -0.25 * loads.gap)
    t_quarter = np.where(quarter[0] > 0, _at(t2, *quarter), np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        v_open = np.where(np.isfinite(t_quarter) & (t_quarter > 0),
                          0.75 * loads.gap / t_quarter, np.nan)
    return OpeningMotion(departure_time=departure, open_time=departure + t2[:, -1],
                         opening_velocity_avg=v_open)
