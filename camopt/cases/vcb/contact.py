"""Cam-roller contact of the VCB mechanism: the Hertz stresses along the stroke (Eqs 15,
19, 27-31) and the search's fast path to their peak."""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.law import follower_dwell
from camopt.mechanics import cam, hertz
from camopt.units import GPA, MM


class CamGeometry(Protocol):
    """What the contact stress reads of a :class:`~camopt.cases.vcb.model.VcbModel` (a
    Protocol, so that this module need not import the model that imports it)."""

    c: VcbConfig
    l2: float
    l6: float
    rf: float
    theta_c: NDArray


@dataclass(frozen=True)
class Contact:
    """Cam-roller contact along the stroke, (n, m): pitch curve and its derivatives (m,
    Eqs 9, 12), the profile's radius of curvature (m, Eq 15), normal force (N, Eq 19) and
    the Hertz peak pressure and maximum shear stress (Pa, Eqs 27-31)."""

    xp: NDArray
    yp: NDArray
    dxp: NDArray
    dyp: NDArray
    curvature: NDArray
    normal_force: NDArray
    sigma: NDArray
    tau: NDArray


def peak_stress(model: CamGeometry, A: NDArray, f: cam.Follower, torque: NDArray,
                zeros: NDArray | None = None, kernel: ModuleType | None = None) -> NDArray:
    """Peak Hertz pressure over the stroke per design (Eqs 15, 19, 27-30), the search's
    fast path: sigma_max = sqrt(max(Fn (1/rho + 1/rf)) E_e / (2 pi L)), one square
    root per design instead of per sample; no Hertz contact counts as infinite, and so
    does a follower that dwells inside the stroke (phi' = 0: Fn unbounded). The
    sampled extreme is refined by a parabola (:func:`refined_min`), so the value does
    not depend on the sample count. ``A`` (n, 4) are the cubic's coefficients; with
    ``kernel`` (:func:`camopt.cases.vcb.motion.compiled`) the per-node part compiled
    (:func:`contact_ratio`). (float32 was tried and rejected: cancellation near a dwell
    cost 5 % in sigma.)"""
    c = model.c
    l2, l6, rf = model.l2, model.l6, model.rf
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = contact_ratio(f, torque, l2, l6, rf, kernel)
        low = refined_min(r)
        # where p . dp = l6 l2 sin(xi + phi) phi' vanishes inside the stroke the common
        # normal passes through O: the arm of Fn is zero and Fn = T / arm unbounded
        # whatever the grid; phi' = 0 is found exactly, sin(xi + phi) = 0 by a sign
        # change between samples (the swing would have to pass pi twice in one step)
        dwell = np.isfinite(follower_dwell(A, model.theta_c[-1], zeros))
        dwell |= np.any(f.sin_a[:, 1:] * f.sin_a[:, :-1] <= 0, axis=1)
        low[dwell] = 0.0
        top = np.where(low > 0, 1 / (low * ((l6 * l2) * rf)), np.inf)  # NaN too
    e_eq = hertz.equivalent_modulus(c.cam_modulus_gpa * GPA, c.poisson,
                                    c.cam_modulus_gpa * GPA, c.poisson)
    return np.sqrt(top * e_eq / (2 * np.pi * c.contact_length_mm * MM))


def contact_ratio(f: cam.Follower, torque: NDArray, l2: float, l6: float, rf: float,
                  kernel: ModuleType | None = None) -> NDArray:
    """The reciprocal of Fn (1/rho + 1/rf) on every node, (n, m), that :func:`peak_stress`
    minimises: in ``kernel``'s compiled pass (:mod:`camopt.cases.vcb.kernel`: the numbers
    of :func:`_numpy_contact_ratio`, its operations in their order), else in numpy."""
    if kernel is None:
        return _numpy_contact_ratio(f, torque, l2, l6, rf)
    out = np.empty(np.shape(f.dphi))
    kernel.contact_ratio(f.dphi, f.ddphi, f.cos_a, f.sin_a,
                         np.broadcast_to(np.asarray(torque, dtype=float), out.shape),
                         float(l2), float(l6), float(rf), out)
    return out


def _numpy_contact_ratio(f: cam.Follower, torque: NDArray, l2: float, l6: float, rf: float
                         ) -> NDArray:
    """:func:`contact_ratio` in numpy (call under ``np.errstate``)."""
    # in place where possible (hot path: fewer bytes through the cache)
    w = np.multiply(f.dphi, -l2)
    w += l2  # l2 (1 - phi')
    lc = np.multiply(f.cos_a, l6)
    v = np.subtract(w, lc)  # w - l6 cos
    # |dp/dtheta|^2 of the pitch curve (Eq 12), Eq 15's numerator base
    speed_sq = np.subtract(v, lc, out=lc)
    speed_sq *= w
    speed_sq += l6 * l6
    # Eq 15's denominator, rewritten: speed_sq - phi' w v - l2 l6 phi'' sin
    den = np.multiply(f.ddphi, f.sin_a)
    den *= -(l2 * l6)
    den += speed_sq
    w *= f.dphi
    w *= v
    den -= w
    # with rho_p = |dp|^3 / den (Eq 15) and rho = rho_p - rf, Fn (1/rho + 1/rf)
    # (Eqs 19, 28, p . dp = l6 l2 sin phi') = |T| |dp|^4 / (|p . dp| rf gap),
    # gap = (rho_p - rf) den; Hertz contact needs 1/rho + 1/rf > 0: gap > 0.
    # Its reciprocal is minimised, so a gap <= 0 anywhere shows as a minimum <= 0
    gap = np.sqrt(speed_sq, out=v)
    gap *= speed_sq
    den *= rf
    gap -= den
    r = np.multiply(f.sin_a, f.dphi, out=den)
    np.abs(r, out=r)
    r *= gap
    np.square(speed_sq, out=speed_sq)
    speed_sq *= np.abs(torque, out=gap)
    r /= speed_sq
    return r


def refined_min(r: NDArray) -> NDArray:
    """Row minimum of samples on a uniform grid, refined by the parabola through the
    smallest sample and its neighbours (error O(h^3) for a smooth interior minimum, so the
    peak stress does not depend on the sample count); end samples are exact."""
    low = np.min(r, axis=1)
    m = r.shape[1]
    if m < 3:
        return low
    rows = np.arange(len(r))
    j = np.clip(np.argmin(r, axis=1), 1, m - 2)
    r0, r1, r2 = r[rows, j - 1], r[rows, j], r[rows, j + 1]
    curv = r0 - 2 * r1 + r2
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex = r1 - (r2 - r0) ** 2 / (8 * curv)
    interior = (curv > 0) & (r1 <= r0) & (r1 <= r2)
    return np.where(interior & np.isfinite(vertex), np.minimum(low, vertex), low)


def row_max(a: NDArray) -> NDArray:
    """Row maximum where NaN (no valid Hertz contact) counts as infinite."""
    top = np.max(a, axis=1)  # NaN propagates through max
    return np.where(np.isnan(top), np.inf, top)
