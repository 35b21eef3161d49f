"""The closing compiled: one call per evaluation, one fused loop per row (numba).

:func:`closing_rows` computes what :func:`camopt.cases.vcb.dynamics.closing_state`
followed by :func:`~camopt.cases.vcb.dynamics.events_of` does, with the same equations:
the node geometry of each design (:func:`~camopt.cases.vcb.kernel_geometry.closing_geometry`,
its own module: the follower law by Horner's
rule, the four-bar and rod of :meth:`VcbModel.kinematics`, the springs' energies and
torques, Eqs 6, 3, 23-24), then per row the release torque ratio, the free rotation
(:func:`free_rotation`, the sinh grid and Simpson sum), the pick-up impact, the
work-energy equation before and after the contacts' touch with the touch's plastic loss,
the first zero of the kinetic energy (:func:`_first_zero`, Hermite scan and bisection),
the trapezoid times, the average closing velocity over the last third of the contact
stroke and, where asked, the least torque the cam passes on (:func:`_torque_min`).
No (rows, nodes) temporaries: a row is read in one pass over its nodes. The numpy path
stays the reference; ``tests/cases/test_vcb_kernel.py`` compares the two (events to
1e-12 relative on random designs and at the near-balance release, the geometry within
rounding, the least torque to 1e-9 of the driving torque).

Why numba (``docs/design.md``): the loops are plain float arithmetic over arrays, which
numba compiles from this Python source with no build step; ``cache=True`` keeps the
machine code beside the module (or in the user's cache folder), so the compile is paid
once per install, and only by a command that evaluates a VCB
(:func:`camopt.cases.vcb.motion.compiled` imports this module at the first evaluation;
``validate`` and ``show`` never do). Importing this module raises ImportError where numba
is not installed: the caller then takes the numpy path.

Rows are set-major: row ``r = set * nd + design`` reads design ``r % nd``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from camopt.cases.vcb.kernel_geometry import (  # re-exported
    closing_geometry,
    contact_ratio,
    node_kinematics,
)

__all__ = ["band_events", "closing_geometry", "closing_rows", "first_zero_rows",
           "free_rotation", "contact_ratio", "node_kinematics"]

HERMITE_POINTS = 16  # as camopt.cases.vcb.dynamics.HERMITE_POINTS
BISECTIONS = 30  # as camopt.cases.vcb.dynamics.BISECTIONS


@njit(cache=True, error_model="numpy")
def _hermite(t: float, h: float, e0: float, d0: float, e1: float, d1: float) -> float:
    t2 = t * t
    t3 = t * t * t
    return ((2 * t3 - 3 * t2 + 1) * e0 + (t3 - 2 * t2 + t) * h * d0
            + (-2 * t3 + 3 * t2) * e1 + (t3 - t2) * h * d1)


@njit(cache=True, error_model="numpy")
def _first_zero(x: NDArray, e: NDArray, d: NDArray) -> float:
    """:func:`camopt.cases.vcb.dynamics.first_zero` for one row (nan: no zero)."""
    m = len(e)
    last = m - 1
    for j in range(m - 1):
        if e[j + 1] <= 0:
            last = j
            break
    for c in range(min(last, m - 2) + 1):
        h = x[c + 1] - x[c]
        e0, d0, e1, d1 = e[c], d[c], e[c + 1], d[c + 1]
        if not min(e0, e1) - 4 / 27 * h * (abs(d0) + abs(d1)) <= 0:
            continue
        point = -1
        for i in range(HERMITE_POINTS):
            if i == HERMITE_POINTS - 1:
                value = e1
            else:
                value = _hermite((i + 1) / HERMITE_POINTS, h, e0, d0, e1, d1)
            if value <= 0:
                point = i
                break
        if point < 0:
            continue
        lo = point / HERMITE_POINTS
        hi = (point + 1) / HERMITE_POINTS
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            if _hermite(mid, h, e0, d0, e1, d1) > 0:
                lo = mid
            else:
                hi = mid
        return x[c] + hi * h
    return math.nan


@njit(cache=True, error_model="numpy")
def _crossing(values: NDArray, level: float) -> tuple[int, float]:
    """:func:`camopt.cases.vcb.dynamics._crossing` for one row."""
    k = 0
    for j in range(len(values)):
        if values[j] >= level:
            k = j
            break
    if k == 0:
        return 0, 0.0
    lo, hi = values[k - 1], values[k]
    w = (level - lo) / (hi - lo)
    if math.isnan(w):
        w = 0.0
    elif math.isinf(w):
        w = 1.0 if w > 0 else 0.0  # nan_to_num's largest float, then the clip
    return k, min(max(w, 0.0), 1.0)


@njit(cache=True, error_model="numpy")
def _at(a: NDArray, k: int, w: float) -> float:
    return (1 - w) * a[max(k - 1, 0)] + w * a[k]


@njit(cache=True, error_model="numpy")
def band_events(theta: NDArray, dtheta_du: NDArray, du: float, gap: float,
                dphi: NDArray, s1: NDArray, ds1: NDArray, spring: NDArray,
                springs_torque: NDArray, resisting: NDArray, resisting_torque: NDArray,
                cam: NDArray, follower_kg: NDArray, rod: NDArray, contacts: NDArray,
                friction: NDArray, eps: NDArray, omega_free: NDArray, t_free: NDArray,
                resisting_gap: NDArray, torque_min: bool, out: NDArray) -> None:
    """The closing's events of every row into ``out`` (10, rows): cam contact time, touch
    time, touch velocity, average closing velocity, closing time, final kinetic energy,
    touch loss, latched (1/0), reach and, where ``torque_min``, the least torque the cam
    passes on over the nodes it reaches (:func:`_torque_min`; else nan). Geometry (nd, m)
    per design, the rest (rows,)."""
    nd, m = s1.shape
    rows = len(cam)
    end = theta[m - 1]
    ke_b = np.empty(m)
    om_b = np.empty(m)
    kin = np.empty(m)
    slope = np.empty(m)
    t_b = np.empty(m)
    t_a = np.empty(m)
    om_a = np.empty(m)
    for r in range(rows):
        i = r % nd
        moving = rod[r] + contacts[r]
        f_kg, c_kg = follower_kg[r], cam[r]
        e, fr = eps[r], friction[r]
        j0 = c_kg + f_kg * dphi[i, 0] * dphi[i, 0] + moving * ds1[i, 0] * ds1[i, 0]
        omega0 = c_kg * omega_free[r] / j0
        kinetic0 = 0.5 * j0 * omega0 ** 2
        k, w = _crossing(s1[i], gap)
        touched = k > 0
        # the speed and time before the touch are read up to its interval (k): beyond it
        # the after-touch speed takes over
        limit = k + 1 if touched else m
        theta_touch = _at(theta, k, w)
        ds1_touch = _at(ds1[i], k, w)
        dphi_touch = _at(dphi[i], k, w)
        ke_touch = (kinetic0 + e * (spring[i, 0] - _at(spring[i], k, w)) - resisting_gap[r]
                    - fr * theta_touch)
        j_touch = c_kg + f_kg * dphi_touch ** 2 + moving * ds1_touch ** 2
        omega_touch = math.sqrt(max(2 * ke_touch / j_touch, 0.0))
        v_touch = ds1_touch * omega_touch if touched else math.nan
        loss = 0.0
        if touched:
            vt = v_touch if math.isfinite(v_touch) else (
                0.0 if math.isnan(v_touch) else math.copysign(1.7976931348623157e308,
                                                              v_touch))
            loss = 0.5 * contacts[r] * vt ** 2
        for j in range(m):
            ke = kinetic0 + e * (spring[i, 0] - spring[i, j]) - resisting[i, j]
            ke -= fr * theta[j]
            ke_b[j] = ke
            kin[j] = ke - loss if touched and j >= k else ke
            slope[j] = (e * springs_torque[i, j] - fr) - resisting_torque[i, j]
            if j < limit:  # t_b's integrand; its ends below
                jb = c_kg + f_kg * dphi[i, j] * dphi[i, j] + moving * ds1[i, j] * ds1[i, j]
                om_b[j] = math.sqrt(max(2 * ke / jb, 0.0))
                t_b[j] = dtheta_du[j] / om_b[j]
        stall = _first_zero(theta, kin, slope)
        if not math.isfinite(t_free[r]):
            stall = 0.0
        # time before the touch (dynamics._cumulative_time, then + t_free)
        if dtheta_du[0] == 0:
            t_b[0] = 0.0 if om_b[0] > 0 else t_b[1]
        if limit == m and dtheta_du[m - 1] == 0:
            t_b[m - 1] = 0.0 if om_b[m - 1] > 0 else t_b[m - 2]
        g_prev = t_b[0]
        acc = 0.0
        t_b[0] = t_free[r] + 0.0
        for j in range(1, limit):
            g = t_b[j]
            acc += 0.5 * (g + g_prev) * du
            g_prev = g
            t_b[j] = t_free[r] + acc
        km = max(k - 1, 0)
        last_cell = (theta_touch - theta[km]) * 0.5 * (1 / om_b[km] + 1 / omega_touch)
        t_touch = t_b[km] + last_cell if touched else math.nan
        latched = math.isnan(stall)
        reached = touched and not (stall <= theta_touch)
        if touched:
            ja_k = c_kg + f_kg * dphi[i, k] * dphi[i, k] + rod[r] * ds1[i, k] * ds1[i, k]
            om_a[k] = math.sqrt(max(2 * (ke_b[k] - loss) / ja_k, 0.0))
            first_cell = (theta[k] - theta_touch) * 0.5 * (1 / omega_touch + 1 / om_a[k])
            t_k = t_touch + first_cell
            t_a[k] = t_k
            total = 0.0
            g_prev = dtheta_du[k] / om_a[k]
            for j in range(k + 1, m):
                ja = c_kg + f_kg * dphi[i, j] * dphi[i, j] + rod[r] * ds1[i, j] * ds1[i, j]
                om_a[j] = math.sqrt(max(2 * (ke_b[j] - loss) / ja, 0.0))
                g = dtheta_du[j] / om_a[j]
                total += 0.5 * (g + g_prev) * du
                g_prev = g
                t_a[j] = t_k + total
            t_end = t_k + total
        else:
            t_end = t_b[m - 1]
        k3, w3 = _crossing(s1[i], 2 * gap / 3)
        t23 = _at(t_b, k3, w3) if k3 > 0 else math.nan
        out[0, r] = t_free[r]
        out[1, r] = t_touch if reached else math.inf
        out[2, r] = v_touch
        out[3, r] = (gap / 3) / (t_touch - t23) if reached else math.nan
        out[4, r] = t_end if latched else math.inf
        out[5, r] = kin[m - 1] if latched else 0.0
        out[6, r] = loss
        out[7, r] = 1.0 if latched else 0.0
        out[8, r] = 1.0 if latched else (0.0 if math.isnan(stall) else stall) / end
        if torque_min:
            # omega and time per node as curves_of has them, in om_b and t_b
            start = k if touched else m
            for j in range(start, m):
                om_b[j] = om_a[j]
                t_b[j] = t_a[j]
            if math.isnan(stall):
                stalled_at = m
            else:  # numpy.searchsorted (left): the first node at or beyond the stall
                stalled_at = 0
                while stalled_at < m and theta[stalled_at] < stall:
                    stalled_at += 1
            if not math.isfinite(t_free[r]):
                stalled_at = 1
            stalled_at = max(stalled_at, 1)
            out[9, r] = _torque_min(theta, om_b, t_b, springs_torque[i], e, fr, c_kg,
                                    stalled_at)
        else:
            out[9, r] = math.nan


@njit(cache=True, error_model="numpy")
def _torque_min(theta: NDArray, omega: NDArray, time: NDArray, springs_torque: NDArray,
                eps: float, friction: float, cam: float, stalled_at: int) -> float:
    """The least torque the cam passes to the roller, eps T_s - T_f - J_cam omega
    domega/dtheta, over the nodes before ``stalled_at`` with a finite time (inf if none;
    nan if any is nan, as numpy's min): omega domega/dtheta = 1/2 d(omega^2)/dtheta by
    :func:`numpy.gradient`'s formulas on the uneven nodes (second order inside, one-sided
    at the ends)."""
    m = len(theta)
    low = math.inf
    for j in range(min(stalled_at, m)):
        if not math.isfinite(time[j]):
            continue
        if j == 0:
            slope = (omega[1] ** 2 - omega[0] ** 2) / (theta[1] - theta[0])
        elif j == m - 1:
            slope = (omega[j] ** 2 - omega[j - 1] ** 2) / (theta[j] - theta[j - 1])
        else:
            h1 = theta[j] - theta[j - 1]
            h2 = theta[j + 1] - theta[j]
            slope = (-h2 / (h1 * (h1 + h2)) * omega[j - 1] ** 2
                     + (h2 - h1) / (h1 * h2) * omega[j] ** 2
                     + h1 / (h2 * (h1 + h2)) * omega[j + 1] ** 2)
        value = (eps * springs_torque[j] - friction) - cam * (0.5 * slope)
        if math.isnan(value):
            return math.nan
        low = min(low, value)
    return low


@njit(cache=True, error_model="numpy")
def first_zero_rows(x: NDArray, energy: NDArray, slope: NDArray, out: NDArray) -> None:
    """:func:`camopt.cases.vcb.dynamics.first_zero` of every row into ``out`` (n,):
    ``x`` (1, m) shared or (n, m) per row."""
    shared = x.shape[0] == 1
    for r in range(energy.shape[0]):
        out[r] = _first_zero(x[0] if shared else x[r], energy[r], slope[r])


@njit(cache=True, error_model="numpy")
def _net(turn: float, cos0: float, sin0: float, length0: float, l8: float, gx: float,
         gy: float, kc1: float, kc2: float, f1: float, f2: float, eps: float,
         friction: float) -> tuple[float, float]:
    """The free rotation's net torque and kinetic energy ``turn`` past the release (crank
    angle a0, its cosine and sine ``cos0``, ``sin0``), as
    :meth:`VcbModel.closing_spring_travel` and ``dynamics.free_rotation`` compute them,
    the angles a0 + turn / 2 and a0 + turn by the addition theorems from one sine and
    cosine of turn / 2 (two trigonometric calls a node, not eight)."""
    sh = math.sin(0.5 * turn)
    ch = math.cos(0.5 * turn)
    sin_mid = sin0 * ch + cos0 * sh
    cos_mid = cos0 * ch - sin0 * sh
    sin_a = sin_mid * ch + cos_mid * sh
    cos_a = cos_mid * ch - sin_mid * sh
    length = math.hypot(gx - l8 * cos_a, gy - l8 * sin_a)
    squares = 4 * l8 * sh * (gx * sin_mid - gy * cos_mid)
    gained = squares / (length + length0)
    rate = l8 * (gx * sin_a - gy * cos_a) / length
    torque = (kc1 * (f1 - gained) + kc2 * (f2 - gained)) * rate
    work = gained * (kc1 * (f1 - 0.5 * gained) + kc2 * (f2 - 0.5 * gained))
    return eps * torque - friction, eps * work - friction * turn


@njit(cache=True, error_model="numpy")
def free_rotation(start: NDArray, kc1: NDArray, kc2: NDArray, p1: NDArray, p2: NDArray,
                  eps: NDArray, friction: NDArray, inertia: NDArray, u: NDArray,
                  weights: NDArray, l8: float, gx: float, gy: float, base: float,
                  open_length: float, skip: NDArray, out: NDArray) -> None:
    """:func:`camopt.cases.vcb.dynamics.free_rotation`'s speed at the roller, time and
    whether the energy reaches zero on the way, per row into ``out`` (3, rows): the same
    sinh grid and Simpson sum, one row at a time (rows (rows,) each, the grid ``u`` and
    Simpson's ``weights`` (steps + 1,)); a row where ``skip`` (the cam does not start)
    gets no speed and an infinite time."""
    m = len(u)
    steps = m - 1
    turn = np.empty(m)
    kinetic = np.empty(m)
    torque = np.empty(m)
    for r in range(len(start)):
        if skip[r]:
            out[0, r], out[1, r], out[2, r] = 0.0, math.inf, 1.0
            continue
        span = -start[r]
        a0 = base + start[r]
        cos0, sin0 = math.cos(a0), math.sin(a0)
        length0 = math.hypot(gx - l8 * cos0, gy - l8 * sin0)
        ext0 = length0 - open_length
        f1, f2 = p1[r] - ext0, p2[r] - ext0
        args = (cos0, sin0, length0, l8, gx, gy, kc1[r], kc2[r], f1, f2, eps[r],
                friction[r])
        h = 1e-3 * span
        a = _net(0.0, *args)[0]
        curve = (_net(h, *args)[0] - a) / h
        c = 2 * a / curve if (a > 0 and curve > 0 and 2 * a < curve * span) else span
        s_end = math.asinh(math.sqrt(span / c))
        total = 0.0
        for j in range(m):
            sinh = math.sinh(s_end * u[j])
            x = span if j == m - 1 else c * sinh ** 2
            turn[j] = x
            torque[j], kinetic[j] = _net(x, *args)
            omega = math.sqrt(max(2 * kinetic[j] / inertia[r], 0.0))
            if j == 0:
                g = 2 * s_end * math.sqrt(c * inertia[r] / (2 * a))
            else:  # sinh(2 s) = 2 sinh(s) cosh(s)
                g = c * 2 * sinh * math.sqrt(1 + sinh * sinh) * s_end / omega
            total += g * weights[j]
        out[0, r] = math.sqrt(max(2 * kinetic[m - 1] / inertia[r], 0.0))
        out[1, r] = total / (3 * steps)
        out[2, r] = 1.0 if math.isfinite(_first_zero(turn, kinetic, torque)) else 0.0


@njit(cache=True, error_model="numpy")
def closing_rows(theta: NDArray, dtheta_du: NDArray, du: float, geometry: NDArray,
                 kc: NDArray, pre: NDArray, loads: NDArray, gap: float, params: NDArray,
                 crank: NDArray, u: NDArray, weights: NDArray, torque_min: bool,
                 out: NDArray) -> None:
    """The whole closing of every row into ``out`` (12, rows): :func:`band_events`'s ten
    rows, then the release torque ratio and the pick-up impact's loss. From each design's
    ``geometry`` (7, nd, m: :func:`closing_geometry`, with its ``kc``, ``pre`` and
    ``loads`` as there), per row (set-major, design ``r % nd``) with the parameters
    ``params`` (8, rows: J_cam, J_f, m_rod, m_c, T_f, eps, the free rotation's T_f, the
    release offset): the release torque ratio eps T_s / T_f at the release (as
    ``rotation.release_torque_ratio``), the free rotation (:func:`free_rotation` on the
    sinh grid ``u`` with Simpson's ``weights``; ``crank`` (7,): l8, G's x and y, the crank
    angle at theta_c = 0, the springs' open length, the dead centre and the crank angle
    at the roller), the plastic pick-up of the roller at rest (generalised momentum kept)
    and the resisting springs' energy at the contacts' gap, then the driven closing."""
    nd = geometry.shape[1]
    rows = params.shape[1]
    l8, gx, gy, base, open_length, dead, contact = (crank[0], crank[1], crank[2], crank[3],
                                                    crank[4], crank[5], crank[6])
    start = np.empty(rows)
    row_kc = np.empty((2, rows))
    row_pre = np.empty((2, rows))
    resisting_gap = np.empty(rows)
    for r in range(rows):
        i = r % nd
        start[r] = dead + params[7, r] - contact
        row_kc[0, r], row_kc[1, r] = kc[i, 0], kc[i, 1]
        row_pre[0, r], row_pre[1, r] = pre[i, 0], pre[i, 1]
        x0 = loads[2, i]
        stretch = x0 + loads[1, i] * gap
        wp = loads[4, i]
        resisting_gap[r] = (0.5 * loads[0, i] * (stretch * stretch - x0 * x0)
                            + 0.5 * loads[3, i] * (wp * wp - wp * wp) - loads[5, i] * gap)
    ratio = np.empty(rows)
    skip = np.empty(rows, dtype=np.bool_)
    for r in range(rows):
        i = r % nd
        # the springs' torque on the cam at rest at the release (closing_spring_geometry)
        angle = base + start[r]
        cos, sin = math.cos(angle), math.sin(angle)
        qx, qy = gx - l8 * cos, gy - l8 * sin
        length = math.hypot(qx, qy)
        ext = length - open_length
        rate = -(qx * (-l8 * sin) + qy * (l8 * cos)) / length
        torque = (kc[i, 0] * (pre[i, 0] - ext) + kc[i, 1] * (pre[i, 1] - ext)) * rate
        driving = params[5, r] * max(torque, 0.0)
        friction = params[6, r]
        if friction > 0:
            ratio[r] = driving / friction
        else:
            ratio[r] = math.inf if driving > 0 else 0.0
        skip[r] = not (params[7, r] > 0 and start[r] < 0 and ratio[r] > 1)
    rotation = np.empty((3, rows))
    free_rotation(start, row_kc[0], row_kc[1], row_pre[0], row_pre[1], params[5], params[6],
                  params[0], u, weights, l8, gx, gy, base, open_length, skip, rotation)
    omega_free = np.empty(rows)
    t_free = np.empty(rows)
    for r in range(rows):
        i = r % nd
        stuck = skip[r] or rotation[2, r] > 0 or not math.isfinite(rotation[1, r])
        omega_free[r] = 0.0 if stuck else rotation[0, r]
        t_free[r] = math.inf if stuck else rotation[1, r]
        cam = params[0, r]
        dphi0, ds1_0 = geometry[0, i, 0], geometry[2, i, 0]
        j0 = cam + params[1, r] * dphi0 * dphi0 + (params[2, r] + params[3, r]) * ds1_0 * ds1_0
        omega0 = cam * omega_free[r] / j0
        out[10, r] = ratio[r]
        out[11, r] = 0.5 * cam * omega_free[r] ** 2 - 0.5 * j0 * omega0 ** 2
    band_events(theta, dtheta_du, du, gap, geometry[0], geometry[1], geometry[2], geometry[3],
                geometry[4], geometry[5], geometry[6], params[0], params[1], params[2],
                params[3], params[4], params[5], omega_free, t_free, resisting_gap,
                torque_min, out)
