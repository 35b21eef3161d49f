"""The cam's free rotation from the release of the closing springs to the roller: whether
it starts (the springs' torque against the friction at the release) and its speed and
time at the roller (the work-energy equation on a sinh-graded grid, Simpson's rule)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.locate import first_zero
from camopt.cases.vcb.model import VcbModel
from camopt.cases.vcb.motion import MotionParameters, ParameterColumns, compiled, per_row
from camopt.units import MM


def release_angle(model: VcbModel, offset_rad: NDArray) -> NDArray:
    """The cam angle theta_c of the release (rad), negative: measured back from the
    roller contact, for latch seats ``offset_rad`` past the crank's dead centre (any
    shape). At or above 0 the seat holds the crank at or past the roller contact: no
    free rotation."""
    return model.dead_centre + offset_rad - model.contact_crank_angle


def start_shortfall(start: NDArray, ratio: NDArray, stroke: float) -> NDArray:
    """How far a release is from starting the cam, >= 0 (0 where it starts or stops on
    its way to the roller), (n,): the release angle ``start`` (rad, :func:`release_angle`)
    past the roller contact as a share of the cam's ``stroke`` (rad), plus the torque
    ratio's shortfall below 1 (:func:`release_torque_ratio`). The closing reads it as a
    negative reach, so that a search among cams that never start still sees which way
    they start (without it every such design had the same constraints: a plateau the
    robust VCB's searches ended on)."""
    return np.maximum(start, 0.0) / stroke + np.maximum(1.0 - ratio, 0.0)


def release_torque_ratio(model: VcbModel, kc: NDArray, p: ParameterColumns,
                         pre: NDArray | None = None) -> NDArray:
    """eps T_s / T_f at the release crank angle, (n,): the springs' torque on the cam at
    rest there, eps of it driving (Eq 26), against the friction torque of the free
    rotation. The cam starts iff this exceeds 1 (Coulomb friction holds it up to T_f; a
    torque ratio of exactly 1 does not start it). inf where there is no friction there
    (and the springs turn it), 0 where the springs hold it back (crank at or before its
    dead centre). ``pre`` (n, 2) m: each row's spring compressions (else the config's)."""
    start = release_angle(model, p.release_offset_rad[:, 0])
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
    start = release_angle(model, p.release_offset_rad)
    u = np.linspace(0.0, 1.0, steps + 1)
    weights = np.ones(steps + 1)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    if ratio is None:
        ratio = release_torque_ratio(model, kc, p, pre)
    starts = (p.release_offset_rad[:, 0] > 0) & (start[:, 0] < 0) & (ratio > 1)
    kernel = compiled() if not np.any(p.spring_kg) else None  # the kernel has no spring mass
    if kernel is not None:
        pair = (per_row(v, n) for v in model.precompressions(pre))
        out = np.empty((3, n))
        kernel.free_rotation(*(np.ascontiguousarray(v, dtype=float) for v in (
            start[:, 0], kc[:, 0], kc[:, 1], *pair, p.efficiency[:, 0],
            p.release_friction_nm[:, 0], p.cam_kg_m2[:, 0], u, weights)),
            *model.spring_crank(), ~starts, out)
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
