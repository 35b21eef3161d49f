"""Opening and closing dynamics of the VCB mechanism, from the closed state as in ADAMS.

Kang, Huang & Yang (2023) simulate the vendor design in ADAMS (Sec 3.2, Table 4, Figs 23-25)
from the closed state: at t = 0 the hook lets go and the opening, contact and closing springs
release together; the contacts separate at 3.2 ms, the opening ends at 7 ms, the freely
turning cam meets the roller at 13.1 ms, the contacts collide at 27.8 ms and the simulation
ends, closed, at 45 ms; the average opening velocity is 2.5 m/s and the average closing
velocity 1.71 m/s (Sec 2.1: over the last third of the contact stroke; opening over 3/4
of it from departure). This module reproduces that sequence with one generalised
coordinate per phase:

* **closing spring release** (Sec 2.2 Step 8): the charged crank is held ``release_offset``
  past its dead centre (the crank pointing at the springs' fixed end G), where the springs'
  torque is small; the cam turns freely, inertia J_cam, until it meets the roller at
  theta_c = 0 (crank angle QOX + theta0). The time to get away from near the dead centre
  grows as the offset shrinks (logarithmically), which is what sets the 13.1 ms.
* **cam drives roller** (cam angle theta_c): kinetic energy 1/2 J(theta) omega^2 with

      J(theta) = J_cam + J_f phi'(theta)^2 + (m_rod + m_c) s1'(theta)^2   before the touch
      J(theta) = J_cam + J_f phi'(theta)^2 + m_rod s1'(theta)^2           after it

  J_f the follower and four-bar input about B (turning with the follower swing phi,
  Eq 6), m_rod the output link, arm and insulated rods as a mass at the rod, m_c the three
  moving contacts. The follower's share J_f phi'^2 shrinks along the stroke as phi'
  does (the cubic's rate falls from a1 toward 0), so the early motion is heavier than a
  constant lumped mass makes it. The work-energy equation gives omega(theta) without an
  ODE:

      1/2 J omega^2 = KE_0 + eps (E_cs(0) - E_cs(theta)) - V_r(s1(theta)) - impact losses

  E_cs the closing springs' energy, V_r the resistant potential (opening and contact
  springs, free-contact force: :class:`camopt.cases.vcb.model.Loads`), eps the paper's
  mechanical efficiency (Eq 26) as the friction loss on the driving springs' work. Events
  are plastic impacts (Carnot): the cam meets the roller at rest (generalised momentum
  kept, J_cam omega- = J(0) omega+), and the contacts stop on the fixed ones at s1 = gap
  (their kinetic energy 1/2 m_c v^2 is lost, omega continuous). A design whose kinetic
  energy reaches zero first stalls and never latches (closing time infinite).
* **opening** (follower angle phi from the closed to the opened state): the contact and
  opening springs drive the linkage back, eps of their work, with
  J(phi) = J_f + m_rod (ds1/dphi)^2; the contacts stay closed until the rod is back at the
  gap (separation), a plastic impact picks them up and the opening spring carries all to
  s1 = 0 (opening complete).

Time follows as t = integral d(coordinate) / rate on grids graded toward the states of rest.
The parameters are not printed in the paper; they are identified by least squares on every
ADAMS datum (``configs/vcb_identify_dynamics.toml``, :mod:`camopt.cases.vcb.identify`,
``docs/assumptions.md``). A scipy ODE integration of Lagrange's equation is the cross-check
in ``tests/cases/test_vcb_dynamics.py``. Own equations rather than a multibody library: the
mechanism is one degree of freedom in every phase, so the work-energy form is exact,
vectorises over a population and needs no time stepping (``docs/design.md``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.model import Loads, VcbModel
from camopt.units import MM


@dataclass(frozen=True)
class MotionParameters:
    """The dynamic parameters the paper omits (SI). Each is a float or an (n,) array, one
    per design or per parameter set.

    ``cam_kg_m2`` cam, shaft, spring crank and the closing springs' share, about O;
    ``follower_kg_m2`` follower BD, roller and the four-bar's input about B;
    ``rod_kg`` output link, arm and insulated rods as a mass moving with the rod travel s1;
    ``contacts_kg`` the three moving contacts, carried by the rod until they touch;
    ``release_offset_rad`` the charged spring crank's angle past its dead centre when the
    closing latch lets go; ``friction_nm`` a Coulomb friction torque referred to the cam
    shaft, against the cam's rotation while it drives the roller (N m);
    ``release_friction_nm`` the same in the free rotation from the release (None: the
    driven closing's ``friction_nm``; 0 for a model form with friction only in the
    driven closing); ``efficiency`` the share of the springs' work that drives (Eq 26's
    eps; None: the case's ``efficiency``; 1 for a form with Coulomb friction alone).
    ``spring_kg`` the closing springs' own mass moving with their free ends, effective
    (a uniform coil with one end fixed: a third of its mass), an inertia
    ``spring_kg`` (dL/dtheta)^2 on the cam from the release on; ``rod_damping_n_s_per_m``
    a viscous force on the rod (a dashpot or buffer), c ds1/dt against its motion (0:
    the rigid, Coulomb-only model; either non-zero runs the numpy path, not the kernel).
    The model forms (:mod:`camopt.cases.vcb.forms`) map their fitted vectors to these."""

    cam_kg_m2: NDArray | float
    follower_kg_m2: NDArray | float
    rod_kg: NDArray | float
    contacts_kg: NDArray | float
    release_offset_rad: NDArray | float
    friction_nm: NDArray | float = 0.0
    release_friction_nm: NDArray | float | None = None
    efficiency: NDArray | float | None = None
    spring_kg: NDArray | float = 0.0
    rod_damping_n_s_per_m: NDArray | float = 0.0

    def columns(self, n: int, efficiency: float) -> ParameterColumns:
        """The same parameters as (n, 1) columns (what the motions broadcast against);
        ``efficiency`` fills an unset ``efficiency`` (the case's eps)."""
        def col(v: NDArray | float) -> NDArray:
            return np.broadcast_to(np.ravel(np.asarray(v, dtype=float)), (n,))[:, None]
        resolved = replace(
            self, efficiency=efficiency if self.efficiency is None else self.efficiency,
            release_friction_nm=(self.friction_nm if self.release_friction_nm is None
                                 else self.release_friction_nm))
        return ParameterColumns(**{f.name: col(getattr(resolved, f.name))
                                   for f in fields(self)})

    def repeat(self, n: int) -> MotionParameters:
        """Each of k parameter sets repeated for n designs in a row: (k n,) arrays ordered
        set-major (set 0 for every design, then set 1, ...); unset fields stay unset, and
        a plain number (one value for every set) stays one."""
        return replace(self, **{f.name: np.repeat(np.ravel(np.asarray(getattr(self, f.name),
                                                                      dtype=float)), n)
                                for f in fields(self) if getattr(self, f.name) is not None
                                and np.ndim(getattr(self, f.name)) > 0})


@dataclass(frozen=True)
class ParameterColumns:
    """:class:`MotionParameters` as (n, 1) columns, one row per design (SI), every field
    resolved."""

    cam_kg_m2: NDArray
    follower_kg_m2: NDArray
    rod_kg: NDArray
    contacts_kg: NDArray
    release_offset_rad: NDArray
    friction_nm: NDArray
    release_friction_nm: NDArray
    efficiency: NDArray
    spring_kg: NDArray
    rod_damping_n_s_per_m: NDArray


@dataclass(frozen=True)
class ClosingEvents:
    """The closing's events per design (n,), time from the release of the closing springs:
    ``cam_contact_time`` (s), ``touch_time`` (s), ``touch_velocity`` (m/s),
    ``closing_velocity_avg`` (m/s, over the last third of the contact stroke, Sec 2.1),
    ``closing_time`` (s, to theta_end; inf if stalled), ``final_kinetic`` (J, at
    theta_end), ``touch_loss`` (J), ``latched``, ``reach``, the fraction of theta_end
    the cam turns before its kinetic energy first reaches zero (1 if latched; 0 if it
    never meets the roller), ``release_torque_ratio``, eps T_s / T_f at the release
    crank angle (the cam starts iff it exceeds 1; inf without friction in the free
    rotation), and ``pickup_loss`` (J), the kinetic energy the plastic impact of the cam on
    the resting roller takes (1/2 J* omega^2 of the relative motion, what the contact
    stores at its peak; 0 if the cam never gets there). What a band member contributes
    (:func:`closing_events`)."""

    cam_contact_time: NDArray
    touch_time: NDArray
    touch_velocity: NDArray
    closing_velocity_avg: NDArray
    closing_time: NDArray
    final_kinetic: NDArray
    touch_loss: NDArray
    latched: NDArray
    reach: NDArray
    release_torque_ratio: NDArray
    pickup_loss: NDArray


@dataclass(frozen=True)
class ClosingMotion(ClosingEvents):
    """The closing of each design: its :class:`ClosingEvents` and the curves, arrays
    (n, m) on the graded cam-angle grid. ``theta_c`` cam angle from the cam meeting the
    roller (rad, (m,)); ``time`` (s, inf after a stall); ``omega`` cam speed (rad/s);
    ``rod`` and ``rod_velocity`` rod travel s1 (m) and its velocity (m/s); ``contact``
    and ``contact_velocity`` the movable contact's travel and velocity (it stops at
    touch); ``cam_torque`` the torque the cam passes to the roller (N m, negative: the
    follower would lift off)."""

    theta_c: NDArray
    time: NDArray
    omega: NDArray
    rod: NDArray
    rod_velocity: NDArray
    contact: NDArray
    contact_velocity: NDArray
    cam_torque: NDArray


@dataclass(frozen=True)
class OpeningMotion:
    """The opening of each design from the closed state at rest, (n,): contact separation
    (``departure_time``, s: the rod is back at the contact gap), the end of the opening
    (``open_time``, s: the rod at s1 = 0) and the average opening velocity over 3/4 of the
    contact stroke from departure (``opening_velocity_avg``, m/s, Sec 2.1)."""

    departure_time: NDArray
    open_time: NDArray
    opening_velocity_avg: NDArray


def compiled() -> ModuleType | None:
    """:mod:`camopt.cases.vcb.kernel` where numba is installed and ``CAMOPT_NUMBA`` is not
    ``0`` (imported here, at the first evaluation, never by a command that evaluates no
    VCB); else None: the numpy path, the reference, with no error."""
    if os.environ.get("CAMOPT_NUMBA", "1") == "0":
        return None
    try:
        from camopt.cases.vcb import kernel
    except ImportError:  # numba not installed
        return None
    return kernel


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
    g = np.array(np.broadcast_to(g, omega.shape))
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
    a = np.broadcast_to(a, (len(k), a.shape[-1]))
    with np.errstate(invalid="ignore"):  # inf x 0 where a row never gets there
        return (1 - w) * a[rows, np.maximum(k - 1, 0)] + w * a[rows, k]


DAMPING_PASSES = 4
"""Fixed-point passes for a rod dashpot's work (:func:`closing_state`): each pass's
speed error is the previous one's times the dashpot's share of the energy lost
(250 N s/m, a sixth: 4 passes leave ~1e-3 of it; a test compares the ODE)."""
HERMITE_POINTS = 16
"""Points per interval at which :func:`first_zero` looks for the energy's first sign
change on its cubic Hermite interpolant between two nodes."""
BISECTIONS = 30
"""Bisections of that sub-interval: the root to 2^-30 of it."""


def _hermite(t: NDArray, h: NDArray, e0: NDArray, d0: NDArray, e1: NDArray, d1: NDArray
             ) -> NDArray:
    """The cubic Hermite interpolant at fraction t of an interval of length h with values
    e0, e1 and slopes d0, d1 at its ends (arrays broadcast)."""
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * e0 + (t3 - 2 * t2 + t) * h * d0
            + (-2 * t3 + 3 * t2) * e1 + (t3 - t2) * h * d1)


def first_zero(x: NDArray, energy: NDArray, slope: NDArray) -> NDArray:
    """The first coordinate where the kinetic energy reaches zero, per row (n,), nan where
    it stays positive: ``energy`` (n, m) and its exact derivative ``slope`` (n, m, the net
    torque) at the nodes ``x`` ((m,) or (n, m), increasing). Between two nodes the energy is
    its cubic Hermite interpolant (values and slopes at both ends: error O(h^4)), scanned
    at :data:`HERMITE_POINTS` points, so a zero between nodes is found even where both
    nodes are positive (the cam comes to rest and would be pushed on again: it stays);
    the root is then bisected on the cubic. A start at rest with a positive slope (the
    release) is not a zero. Compiled (``kernel.first_zero_rows``, the same scan and
    bisection row by row) where :func:`compiled` gives the kernel."""
    kernel = compiled()
    if kernel is not None and len(energy):
        root = np.empty(len(energy))
        kernel.first_zero_rows(np.ascontiguousarray(np.atleast_2d(x), dtype=float),
                               np.ascontiguousarray(energy, dtype=float),
                               np.ascontiguousarray(slope, dtype=float), root)
        return root
    x = np.broadcast_to(x, energy.shape)
    h = x[:, 1:] - x[:, :-1]
    e0, d0, e1, d1 = energy[:, :-1], slope[:, :-1], energy[:, 1:], slope[:, 1:]
    # the interpolant is at least min(e0, e1) - 4/27 h (|d0| + |d1|) (the bounds of its
    # basis functions): only intervals where that is not positive can hold a zero, and
    # none after the first node at or below zero (its interval holds one)
    low = energy[:, 1:] <= 0
    last = np.where(low.any(axis=1), np.argmax(low, axis=1), e0.shape[1])
    rows, cells = np.nonzero(
        (np.minimum(e0, e1) - 4 / 27 * h * (np.abs(d0) + np.abs(d1)) <= 0)
        & (np.arange(e0.shape[1])[None, :] <= last[:, None]))
    ends = (h[rows, cells], e0[rows, cells], d0[rows, cells], e1[rows, cells],
            d1[rows, cells])
    t = np.arange(1, HERMITE_POINTS + 1)[None, :] / HERMITE_POINTS
    e = _hermite(t, *(a[:, None] for a in ends))
    e[:, -1] = ends[3]  # the right node itself exactly
    below = e <= 0
    zero = below.any(axis=1)
    root = np.full(len(energy), np.nan)
    if not zero.any():  # no row comes to rest (the usual case): nothing to bisect
        return root
    # each row's first candidate interval that holds a zero (candidates are row-major)
    first_rows, first = np.unique(rows[zero], return_index=True)
    pick = np.flatnonzero(zero)[first]
    point = np.argmax(below[pick], axis=1)
    args = tuple(a[pick] for a in ends)
    lo, hi = point / HERMITE_POINTS, (point + 1) / HERMITE_POINTS  # e(lo) > 0 >= e(hi)
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        positive = _hermite(mid, *args) > 0
        lo, hi = np.where(positive, mid, lo), np.where(positive, hi, mid)
    root[first_rows] = x[first_rows, cells[pick]] + hi * args[0]
    return root


def release_torque_ratio(model: VcbModel, kc: NDArray, p: ParameterColumns,
                         pre: NDArray | None = None) -> NDArray:
    """eps T_s / T_f at the release crank angle, (n,): the springs' torque on the cam at
    rest there, eps of it driving (Eq 26), against the friction torque of the free
    rotation. The cam starts iff this exceeds 1 (Coulomb friction holds it up to T_f; a
    torque ratio of exactly 1 does not start it). inf where there is no friction there
    (and the springs turn it), 0 where the springs hold it back (crank at or before its
    dead centre). ``pre`` (n, 2) m: each row's spring compressions (else the config's)."""
    start = model.dead_centre + p.release_offset_rad[:, 0] - model.contact_crank_angle
    ext, rate = model.closing_spring_geometry(start)
    torque = _row_torque(model, kc, ext, rate, pre)
    driving = p.efficiency[:, 0] * np.maximum(torque, 0.0)
    friction = p.release_friction_nm[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(friction > 0, driving / friction, np.where(driving > 0, np.inf, 0.0))


def _row_torque(model: VcbModel, kc: NDArray, ext: NDArray, rate: NDArray,
                pre: NDArray | None = None) -> NDArray:
    """Closing springs' torque (N m) with one spring geometry per row: ``ext``, ``rate``
    (n,) or (n, m) for ``kc`` (n, 2); ``pre`` (n, 2) m each row's compressions."""
    c = model.c
    shape = (-1,) + (1,) * (np.ndim(ext) - 1)
    k1, k2 = (kc[:, i].reshape(shape) for i in range(2))
    p1: NDArray | float
    p2: NDArray | float
    if pre is None:
        p1, p2 = c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM
    else:
        p1, p2 = (pre[:, i].reshape(shape) for i in range(2))
    return (k1 * (p1 - ext) + k2 * (p2 - ext)) * rate


def free_steps(steps: int) -> int:
    """The free rotation's intervals for a closing on ``steps``: a sixteenth of them (26
    at the default 400, made even), at least 16, so ``dynamics_steps`` refines both. Its
    time is then within 1e-6 of an ODE's at torque ratios 1.00001-1.2, against the
    driven closing's 4e-5 (``free_rotation``, docs/design.md)."""
    return max(16, steps // 16)


def free_rotation(model: VcbModel, kc: NDArray, params: MotionParameters, steps: int = 26,
                  pre: NDArray | None = None) -> tuple[NDArray, NDArray]:
    """Cam speed (rad/s) and time (s) when the freely turning cam meets the roller, (n,):
    from rest, the crank ``release_offset`` past its dead centre, to the crank angle
    QOX + theta0 (theta_c = 0), under eps of the closing springs' work and the free
    rotation's friction torque with J_cam alone. Whether the cam starts is decided at the
    release itself (:func:`release_torque_ratio` > 1, not at a node); it stops on the way
    (infinite time) if its kinetic energy reaches zero between the release and the roller
    (:func:`first_zero`, between nodes too). The speed is exact (the energy at the
    contact). The time t = integral dx / omega(x) over the turn x from the release is
    taken on x = c sinh^2(s), s uniform on ``steps`` (even) intervals, by Simpson's rule:
    near the release the energy is a x + b x^2 / 2 (a = eps T - T_f the net torque there,
    b its slope), on which dt/ds is constant for c = 2 a / b, so the integrand stays
    smooth however close the torque ratio is to 1 (the time grows as log(1 / a); a grid
    in x alone misses it: 12 % short at a ratio of 1.00001). c is the whole turn where
    2 a / b exceeds it or b <= 0 (a plain square-root grading). Compiled
    (``kernel.free_rotation``) where :func:`compiled` gives the kernel. ``pre`` (n, 2) m:
    each row's spring compressions in the opened state (else the config's)."""
    return rotation_of(model, kc, params.columns(len(kc), model.c.efficiency), steps, pre)


def rotation_of(model: VcbModel, kc: NDArray, p: ParameterColumns, steps: int,
                pre: NDArray | None = None, ratio: NDArray | None = None
                ) -> tuple[NDArray, NDArray]:
    """:func:`free_rotation` with the parameters already as columns and, if given, the
    :func:`release_torque_ratio` (what the closing has at hand)."""
    n = len(kc)
    steps += steps % 2  # Simpson's rule: an even number of intervals
    # cam angle theta_c of the release: negative, measured back from the roller contact
    start = model.dead_centre + p.release_offset_rad - model.contact_crank_angle
    u = np.linspace(0.0, 1.0, steps + 1)
    weights = np.ones(steps + 1)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    if ratio is None:
        ratio = release_torque_ratio(model, kc, p, pre)
    starts = (p.release_offset_rad[:, 0] > 0) & (start[:, 0] < 0) & (ratio > 1)
    kernel = compiled() if not np.any(p.spring_kg) else None  # the kernel has no spring mass
    if kernel is not None:
        pair = (np.broadcast_to(v, (n, 1))[:, 0] for v in model.precompressions(pre))
        out = np.empty((3, n))
        kernel.free_rotation(*(np.ascontiguousarray(v, dtype=float) for v in (
            start[:, 0], kc[:, 0], kc[:, 1], *pair, p.efficiency[:, 0],
            p.release_friction_nm[:, 0], p.cam_kg_m2[:, 0], u, weights)),
            *model.spring_crank(), out)
        omega_end, time, stops = out[0], out[1], out[2] > 0
    else:
        omega_end, time, stops = _free_rotation(model, kc, p, start, u, weights, pre)
    stuck = ~starts | stops | ~np.isfinite(time)
    return np.where(stuck, 0.0, omega_end), np.where(stuck, np.inf, time)


def _free_rotation(model: VcbModel, kc: NDArray, p: ParameterColumns, start: NDArray,
                   u: NDArray, weights: NDArray, pre: NDArray | None
                   ) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`free_rotation` in numpy (the reference): the speed at the roller, the time
    and whether the energy reaches zero on the way, (n,) each, before the start decision."""
    eps, friction, inertia = p.efficiency, p.release_friction_nm, p.cam_kg_m2
    span = -start  # the turn to the roller (n, 1)
    p1, p2 = model.precompressions(pre)

    def net_torque(turn: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """eps T - T_f, the energy eps W - T_f x and the springs' extension rate
        dL/dtheta at ``turn``."""
        ext0, gained, rate = model.closing_spring_travel(start, turn)
        free1, free2 = p1 - ext0, p2 - ext0  # the springs' compressions at the release
        torque = (kc[:, :1] * (free1 - gained) + kc[:, 1:2] * (free2 - gained)) * rate
        # the work given up, 1/2 ((f - 0)^2 - (f - g)^2) = g (f - g / 2) per N/m: no
        # difference of two energies, so it is exact for a turn however small
        work = gained * (kc[:, :1] * (free1 - 0.5 * gained) + kc[:, 1:2] * (free2 - 0.5 * gained))
        return eps * torque - friction, eps * work - friction * turn, rate

    # the net torque at the release and its slope set the grid's scale c = 2 a / b
    h = 1e-3 * span
    ends, _, _ = net_torque(np.hstack([np.zeros_like(h), h]))
    a = ends[:, :1]
    with np.errstate(divide="ignore", invalid="ignore"):
        curve = (ends[:, 1:] - a) / h
        c = np.where((a > 0) & (curve > 0) & (2 * a < curve * span), 2 * a / curve, span)
    s_end = np.arcsinh(np.sqrt(span / c))
    s = s_end * u[None, :]
    turn = c * np.sinh(s) ** 2
    turn[:, -1:] = span  # the roller exactly
    torque, kinetic, rate = net_torque(turn)
    moving = inertia + p.spring_kg * rate ** 2  # the springs' own mass moves too
    with np.errstate(invalid="ignore", divide="ignore"):
        omega = np.sqrt(np.maximum(2 * kinetic / moving, 0.0))
        g = c * np.sinh(2 * s) * s_end / omega  # dt/du
        # at the release x ~ c s^2 and K ~ a x: dt/du -> 2 s_end sqrt(c J / (2 a))
        g[:, :1] = 2 * s_end * np.sqrt(c * moving[:, :1] / (2 * a))
    time = g @ weights / (3 * (len(u) - 1))
    return omega[:, -1], time, np.isfinite(first_zero(turn, kinetic, torque))


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
    at or beyond it (m if none); ``pickup_loss`` the pick-up impact's loss (J, (n,)).
    Built by :func:`closing_state`; read by the pure
    :func:`events_of` and :func:`curves_of`."""

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
        stalled_at=stalled_at, pickup_loss=pickup_loss)


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
        latched=latched, reach=np.where(latched, 1.0, np.nan_to_num(s.stall_theta) / end),
        release_torque_ratio=s.release_ratio, pickup_loss=s.pickup_loss)


def curves_of(s: ClosingState) -> ClosingMotion:
    """The closing's events and curves (n, m) read from its state."""
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
    return ClosingMotion(
        theta_c=s.theta, time=time, omega=omega, rod=s.s1, rod_velocity=rod_velocity,
        contact=np.minimum(s.s1, s.gap), contact_velocity=contact_velocity,
        cam_torque=cam_torque, closing_time=np.where(s.latched, time[:, -1], np.inf),
        **_events(s))


def closing_motion(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
                   steps: int, pre: NDArray | None = None) -> ClosingMotion:
    """Closing of n designs from the release of the closing springs: the events and the
    curves (:func:`closing_state`, :func:`curves_of`)."""
    return curves_of(closing_state(model, A, kc, link, rod_offset, loads, params, steps,
                                   pre=pre))


def closing_events(model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                   rod_offset: NDArray | float, loads: Loads, params: MotionParameters,
                   steps: int, sets: int = 1, pre: NDArray | None = None) -> ClosingEvents:
    """The events of :func:`closing_motion` alone for ``sets`` parameter sets per design:
    sets x n rows (``pre`` as :func:`closing_state`'s). Compiled
    (:mod:`camopt.cases.vcb.kernel`, the same arithmetic in one loop per row) where numba
    is installed and ``CAMOPT_NUMBA`` is not ``0``; else, and as the reference,
    :func:`closing_state` then :func:`events_of`."""
    kernel = compiled()
    extra = np.any(params.spring_kg) or np.any(params.rod_damping_n_s_per_m)
    if kernel is not None and not extra:  # the kernel has neither term
        return compiled_events(kernel.band_events, model, A, kc, link, rod_offset, loads,
                               params, steps, sets, pre)
    return events_of(closing_state(model, A, kc, link, rod_offset, loads, params, steps,
                                   sets, pre))


def compiled_events(band_events: Callable[..., None], model: VcbModel, A: NDArray,
                    kc: NDArray, link: NDArray, rod_offset: NDArray | float, loads: Loads,
                    params: MotionParameters, steps: int, sets: int = 1,
                    pre: NDArray | None = None) -> ClosingEvents:
    """:func:`closing_events` through the compiled ``band_events``
    (:func:`camopt.cases.vcb.kernel.band_events`): the geometry once per design and the
    free rotation and the pick-up impact in numpy, the rest in the kernel."""
    n = len(A) * sets
    p = params.columns(n, model.c.efficiency)
    theta, dtheta_du = graded_grid(model.theta_c[-1], steps)
    inputs = closing_inputs(model, A, kc, link, rod_offset, loads, theta, pre)
    kc_rows = np.tile(kc, (sets, 1)) if sets > 1 else kc
    pre_rows = None if pre is None else np.tile(pre, (sets, 1)) if sets > 1 else pre
    release_ratio = release_torque_ratio(model, kc_rows, p, pre_rows)
    omega_free, t_free = rotation_of(model, kc_rows, p, free_steps(steps), pre_rows,
                                     release_ratio)
    # the pick-up impact as closing_state has it (the same operations: the same bits)
    dphi0, ds1_0 = (np.tile(inputs[i][:, 0], sets) for i in (0, 2))
    j0 = (p.cam_kg_m2[:, 0] + p.follower_kg_m2[:, 0] * dphi0 * dphi0
          + (p.rod_kg + p.contacts_kg)[:, 0] * ds1_0 * ds1_0)
    omega0 = p.cam_kg_m2[:, 0] * omega_free / j0
    pickup_loss = 0.5 * p.cam_kg_m2[:, 0] * omega_free**2 - 0.5 * j0 * omega0**2
    rows_loads = loads.tiled(sets) if sets > 1 else loads  # a part's springs per design
    resisting_gap = np.broadcast_to(
        rows_loads.resistant_energy(np.full((n, 1), loads.gap))[:, 0], (n,))
    out = np.empty((9, n))
    columns = (p.cam_kg_m2, p.follower_kg_m2, p.rod_kg, p.contacts_kg, p.friction_nm,
               p.efficiency)
    band_events(theta, dtheta_du, 1.0 / steps, float(loads.gap),
                *(np.ascontiguousarray(a, dtype=float) for a in inputs),
                *(np.ascontiguousarray(c[:, 0], dtype=float) for c in columns),
                np.ascontiguousarray(omega_free, dtype=float),
                np.ascontiguousarray(t_free, dtype=float),
                np.ascontiguousarray(resisting_gap, dtype=float), out)
    return ClosingEvents(
        cam_contact_time=out[0], touch_time=out[1], touch_velocity=out[2],
        closing_velocity_avg=out[3], closing_time=out[4], final_kinetic=out[5],
        touch_loss=out[6], latched=out[7] > 0, reach=out[8],
        release_torque_ratio=release_ratio,
        pickup_loss=pickup_loss)


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

