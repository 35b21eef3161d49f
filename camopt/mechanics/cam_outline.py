"""The full turn of a disc cam with an oscillating roller follower: the design's actuated
law (the rise) closed into one outline the workshop can cut.

Kang 2023 designs the follower law phi(theta_c) only over the actuated angle 0..E, and it
starts a node clearance above the base circle (Eq 8) with a non-zero slope. The outline
adds, in cam angle (docs/design.md, "The cam outline"):

* **approach** ``[-b_a, 0]``: from the base circle (phi = phi' = phi'' = 0) to the rise's
  start (phi, phi', phi'' of the design at 0), a quintic Hermite;
* **rise** ``[0, E]``: the design's law, evaluated by the same functions as the case, so
  its points, pressure angle and curvature are those the requirements judged;
* **run-out** ``[E, E + b_o]``: a quintic Hermite from the rise's end to zero velocity at
  phi_E + phi'_E b_o / 2 (the overtravel of a constant deceleration);
* **top dwell**, **return** (the 3-4-5 polynomial, zero velocity and acceleration at both
  ends) and **base dwell**: the angle the others leave, a quarter, a half and a quarter.

Every joint matches phi, phi' and phi'' (C2), so the pitch curve and the profile are
tangent- and curvature-continuous. ``b_a`` and ``b_o`` are the shortest whole degrees
(1..120) whose segment moves one way only (it never dips under the base circle nor, on
the approach, reaches the roller resting at the rise's start before theta_c = 0) with a
pressure angle no larger than the rise's peak and a curvature radius no smaller than the
case's limit; without such a length, the one with the least excess (the notes say so).
All lengths in metres and angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from camopt.mechanics import Floats, cam
from camopt.units import DEG, TO_DEG, TO_MM

TRIAL_SPANS = np.arange(1.0, 121.0) * DEG
"""Candidate lengths of the approach and the run-out (rad): whole degrees 1..120."""
_TRIAL_SAMPLES = 97  # samples per candidate segment when judging it


@dataclass(frozen=True)
class Segment:
    """One part of the outline: cam angles ``start``..``end`` (rad), its law in words and
    the follower's (phi, phi', phi'') at its two ends as its own law gives them, (2, 3)."""

    name: str
    start: float
    end: float
    law: str
    ends: Floats


@dataclass(frozen=True)
class CamOutline:
    """The closed outline sampled over one turn (m points; the point after the last is the
    first, a turn later). ``theta`` cam angle (rad, increasing from the approach's start),
    ``phi``/``dphi``/``ddphi`` the follower law (rad, per rad, per rad^2), ``pitch`` and
    ``profile`` (m, 2) in the cam's frame (x from the cam pivot O towards the follower
    pivot B at theta_c = 0; m), ``pressure_angle`` (rad) and ``curvature`` (the profile's
    radius of curvature, m, Eq 15) at each point; ``rise`` the indices of the actuated
    points, which are the case's own grid; ``limits`` (pressure angle rad, curvature m)
    the closure was held to; ``roller`` the roller radius, ``arm`` the follower arm l2
    and ``pivot`` the distance l6 of the follower pivot B (m), at (l6, 0) in this frame;
    ``xi`` the arm's angle from BO on the base circle (rad, Eq 10)."""

    theta: Floats
    phi: Floats
    dphi: Floats
    ddphi: Floats
    pitch: Floats
    profile: Floats
    pressure_angle: Floats
    curvature: Floats
    segments: tuple[Segment, ...]
    rise: slice
    limits: tuple[float, float]
    roller: float
    arm: float
    pivot: float
    xi: float

    def closure(self) -> NDArray[np.bool_]:
        """Mask of the points outside the actuated angle."""
        mask = np.ones(self.theta.size, dtype=bool)
        mask[self.rise] = False
        return mask

    def radii(self, where: NDArray[np.bool_]) -> tuple[float, float]:
        """Least convex and least concave radius of curvature of the profile at the points
        ``where`` (m; inf when there is none). Eq 15's radius is the pitch curve's less
        rf: convex where it exceeds -rf (undercut between -rf and 0), concave below."""
        rho = self.curvature[where]
        rf = self.roller
        convex, concave = rho[rho > -rf], -rho[rho <= -rf]
        return (float(np.min(convex)) if convex.size else math.inf,
                float(np.min(concave)) if concave.size else math.inf)

    def notes(self) -> list[str]:
        """The law and angles in words, one line each, for a drawing's notes (degrees)."""
        lines = [f"{s.name}: {s.start * TO_DEG:.1f} to {s.end * TO_DEG:.1f} deg, "
                 f"{s.law}" for s in self.segments]
        closed = self.closure()
        psi, rho = self.limits
        convex, concave = self.radii(closed)
        lines.append(
            "closure: peak pressure angle "
            f"{float(np.max(np.abs(self.pressure_angle[closed]))) * TO_DEG:.2f} deg "
            f"(rise's peak {psi * TO_DEG:.2f}), least convex radius "
            f"{convex * TO_MM:.2f} mm (limit {rho * TO_MM:.2f})")
        convex, concave = self.radii(np.ones(self.theta.size, dtype=bool))
        lines.append(f"outline: least convex radius {convex * TO_MM:.2f} mm, least concave "
                     f"radius {concave * TO_MM:.2f} mm (a cutter or wheel must be smaller)"
                     if np.isfinite(concave) else
                     f"outline: convex throughout, least radius {convex * TO_MM:.2f} mm")
        lines.append("follower swing: "
                     f"{round(float(np.min(self.phi)) * TO_DEG, 3) + 0.0:.3f} to "
                     f"{float(np.max(self.phi)) * TO_DEG:.3f} deg from the base circle")
        return lines


def hermite5(u: Floats, start: Floats, end: Floats, span: Floats | float
             ) -> tuple[Floats, Floats, Floats]:
    """The quintic with value, slope and curvature ``start`` and ``end`` (..., 3) at the
    two ends of an interval of length ``span`` (..., ), on ``u`` (m,) in [0, 1]; returns
    the value and its first and second derivatives per unit of the interval's variable,
    each (..., m). With zero end derivatives it is the 3-4-5 polynomial."""
    s = np.asarray(span, dtype=float)[..., None]
    p0, v0, w0 = (np.asarray(start, dtype=float)[..., k, None] for k in range(3))
    p1, v1, w1 = (np.asarray(end, dtype=float)[..., k, None] for k in range(3))
    # coefficients of sum_k c_k u^k from the six end conditions (solved by hand once)
    d = p1 - p0 - v0 * s - w0 * s * s / 2
    e = (v1 - v0 - w0 * s) * s
    f = (w1 - w0) * s * s
    c = (p0, v0 * s, w0 * s * s / 2, 10 * d - 4 * e + f / 2, -15 * d + 7 * e - f,
         6 * d - 3 * e + f / 2)
    u = np.asarray(u, dtype=float)
    value = c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5]))))
    slope = c[1] + u * (2 * c[2] + u * (3 * c[3] + u * (4 * c[4] + u * 5 * c[5])))
    accel = 2 * c[2] + u * (6 * c[3] + u * (12 * c[4] + u * 20 * c[5]))
    return value, slope / s, accel / (s * s)


def _follower(theta: Floats, phi: Floats, dphi: Floats, ddphi: Floats, xi: float
              ) -> cam.Follower:
    angle = phi + xi
    return cam.Follower(theta, xi, angle, dphi, ddphi, np.cos(angle), np.sin(angle))


def _geometry(l2: float, l6: float, rf: float, f: cam.Follower
              ) -> tuple[Floats, Floats, Floats, Floats]:
    """Pitch (…, m, 2), profile (…, m, 2), pressure angle and curvature radius (…, m)."""
    xp, yp, dxp, dyp = cam.pitch_curve(l2, l6, f)
    xc, yc = cam.profile(xp, yp, dxp, dyp, rf)
    return (np.stack([xp, yp], axis=-1), np.stack([xc, yc], axis=-1),
            cam.pressure_angle(l2, l6, f), cam.curvature_radius(l2, l6, f, rf))


def _shortest(start: Floats, end_of: Floats, at: float, backwards: bool,
              geometry: tuple[float, float, float, float], limits: tuple[float, float]
              ) -> float:
    """The shortest trial span (rad) of a Hermite segment meeting the limits: it starts
    at ``at`` (or ends there when ``backwards``); ``start`` (3,) and ``end_of`` (k, 3) its
    end conditions per trial span (the free end's value may depend on the span)."""
    xi, l2, l6, rf = geometry
    spans = TRIAL_SPANS
    u = np.linspace(0.0, 1.0, _TRIAL_SAMPLES)
    if backwards:
        phi, dphi, ddphi = hermite5(u, end_of, np.broadcast_to(start, end_of.shape), spans)
        theta = at - spans[:, None] * (1 - u)
    else:
        phi, dphi, ddphi = hermite5(u, np.broadcast_to(start, end_of.shape), end_of, spans)
        theta = at + spans[:, None] * u
    with np.errstate(invalid="ignore", divide="ignore"):
        _, _, psi, rho = _geometry(l2, l6, rf, _follower(theta, phi, dphi, ddphi, xi))
    psi_max, rho_min = limits
    # one-way motion, pressure angle and curvature as fractions beyond their limits
    tol = 1e-12
    convex = np.where(rho > -rf, rho, np.inf)  # concave (rho <= -rf) never undercuts
    excess = np.stack([np.max(np.maximum(-dphi, 0.0), axis=1) / (np.max(np.abs(dphi),
                                                                          axis=1) + tol),
                       np.max(np.abs(psi), axis=1) / psi_max - 1,
                       1 - np.min(convex, axis=1) / rho_min]).max(axis=0)
    excess = np.where(np.isfinite(excess), np.maximum(excess, 0.0), np.inf)
    ok = np.flatnonzero(excess <= 0)
    return float(spans[ok[0]] if ok.size else spans[int(np.argmin(excess))])


def closed_outline(a: Floats, end: float, rise_steps: int, xi: float, l2: float,
                   l6: float, rf: float, curvature_min: float, step: float | None = None
                   ) -> CamOutline:
    """The full-turn outline of the polynomial law ``a`` (d + 1,) over 0..``end`` (rad)
    sampled like the case (``rise_steps`` intervals), with the follower pivot ``l6`` from
    the cam pivot, arm ``l2``, roller ``rf`` and base-circle angle ``xi`` (Eq 10).
    ``curvature_min`` (m) bounds the closure's radius of curvature; ``step`` (rad) the
    sampling of the closure and, when finer than the case's, of the rise too (None: the
    case's step, so the rise holds exactly the case's points)."""
    a = np.asarray(a, dtype=float)
    n_rise = rise_steps if step is None else max(rise_steps, math.ceil(end / step - 1e-9))
    h = end / n_rise if step is None else step
    k = np.arange(a.size, dtype=float)

    def law(t: float) -> Floats:  # phi, phi', phi'' of the design at t
        p = t ** k
        return np.array([a @ p, a[1:] @ (k[1:] * t ** (k[1:] - 1)),
                         a[2:] @ (k[2:] * (k[2:] - 1) * t ** (k[2:] - 2))])

    geometry = (xi, l2, l6, rf)
    rise_theta = np.linspace(0.0, end, n_rise + 1)
    f_rise = cam.Follower.polynomial(a[None, :], rise_theta, xi)
    rise_geom = _geometry(l2, l6, rf, f_rise)
    limits = (float(np.max(np.abs(rise_geom[2]))), curvature_min)
    first, last = law(0.0), law(end)
    zero = np.zeros(3)
    b_a = _shortest(first, np.zeros((TRIAL_SPANS.size, 3)), 0.0, True, geometry, limits)
    tops = np.column_stack([last[0] + last[1] * TRIAL_SPANS / 2,
                            np.zeros((TRIAL_SPANS.size, 2))])
    b_o = _shortest(last, tops, end, False, geometry, limits)
    top = np.array([last[0] + last[1] * b_o / 2, 0.0, 0.0])
    left = 2 * math.pi - (b_a + end + b_o)
    if left <= 0:
        raise ValueError(f"the rise and its closure need {(2 * math.pi - left) * TO_DEG:.1f}"
                         " deg: more than a turn")
    dwell, fall = left / 4, left / 2
    coeffs = ", ".join(f"{v:.6g}" for v in a)
    segs = [("approach", -b_a, 0.0, zero, first, "quintic Hermite from the base circle "
             "(C2 joints)"),
            ("rise", 0.0, end, None, None,
             f"the design's law phi = sum a_k t**k, a_0.. = {coeffs} (rad)"),
            ("run-out", end, end + b_o, last, top, "quintic Hermite to zero velocity "
             f"(overtravel {(top[0] - last[0]) * TO_DEG:.3f} deg)"),
            ("top dwell", end + b_o, end + b_o + dwell, top, top, "dwell"),
            ("return", end + b_o + dwell, end + b_o + dwell + fall, top, zero,
             "3-4-5 polynomial"),
            ("base dwell", end + b_o + dwell + fall, 2 * math.pi - b_a, zero, zero,
             "base circle")]
    parts = []
    states = []
    for _, t0, t1, p0, p1, _ in segs:
        if p0 is None or p1 is None:
            parts.append((rise_theta, f_rise, rise_geom))
            f = cam.Follower.polynomial(a[None, :], np.array([t0, t1]), xi)
            states.append(np.column_stack([f.phi[0], f.dphi[0], f.ddphi[0]]))
            continue
        states.append(np.column_stack(hermite5(np.array([0.0, 1.0]), p0, p1, t1 - t0)))
        n = max(1, math.ceil((t1 - t0) / h - 1e-9))
        u = np.linspace(0.0, 1.0, n + 1)
        phi, dphi, ddphi = hermite5(u, p0, p1, t1 - t0)
        theta = t0 + (t1 - t0) * u
        f = _follower(theta, phi, dphi, ddphi, xi)
        parts.append((theta, f, _geometry(l2, l6, rf, f)))
    # a joint's point is the rise's where it meets the rise, else the later segment's; the
    # last segment's end is the first point a turn later
    rise_at = 1
    keep = []
    for i in range(len(parts)):
        lo = 1 if i > 0 and i != rise_at else 0
        hi = -1 if i == rise_at - 1 or i == len(parts) - 1 else None
        keep.append(slice(lo, hi))

    def joined(get: Callable[[tuple], Floats]) -> Floats:
        return np.concatenate([np.ravel(get(p))[s] for p, s in zip(parts, keep)])

    pitch = np.concatenate([p[2][0].reshape(-1, 2)[s] for p, s in zip(parts, keep)])
    profile = np.concatenate([p[2][1].reshape(-1, 2)[s] for p, s in zip(parts, keep)])
    start_rise = sum(len(range(*s.indices(np.ravel(p[0]).size)))
                     for p, s in zip(parts[:rise_at], keep[:rise_at]))
    return CamOutline(
        theta=joined(lambda p: p[0]), phi=joined(lambda p: p[1].phi),
        dphi=joined(lambda p: p[1].dphi), ddphi=joined(lambda p: p[1].ddphi),
        pitch=pitch, profile=profile,
        pressure_angle=joined(lambda p: p[2][2]), curvature=joined(lambda p: p[2][3]),
        segments=tuple(Segment(name, t0, t1, text, ends)
                       for (name, t0, t1, _, _, text), ends in zip(segs, states)),
        rise=slice(start_rise, start_rise + n_rise + 1), limits=limits, roller=rf,
        arm=l2, pivot=l6, xi=xi)
