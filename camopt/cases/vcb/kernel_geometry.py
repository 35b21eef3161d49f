"""The node geometry of the compiled closing (numba): for each design, on the closing's
graded cam-angle nodes, the follower law by Horner's rule, the four-bar and rod of
:meth:`camopt.cases.vcb.model.VcbModel.kinematics` (Eqs 6, 3), the closing springs'
energy and torque and the resisting springs' (Eqs 23-24). Its own module because it is
the one part of :mod:`camopt.cases.vcb.kernel` that reads a design rather than a row;
:mod:`camopt.cases.vcb.kernel` re-exports it (``kernel.closing_geometry``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from camopt.mechanics import trig

__all__ = ["closing_geometry", "contact_ratio", "node_kinematics", "sincos"]

_COS, _SIN = trig._COS, trig._SIN  # the tables of camopt.mechanics.trig (constants here)
_STEP, _LIMIT = trig._STEP, trig._LIMIT
_INVERSE = 1 / trig._STEP
_SIZE = len(trig._COS)


@njit(cache=True, error_model="numpy")
def sincos(angle: float) -> tuple[float, float]:
    """cos and sin of ``angle`` as :func:`camopt.mechanics.trig.sincos` computes them
    (the nearest table angle k h, a three-term series of the remainder, one rotation;
    within 1e-15 of libm), libm's beyond its table (|angle| >= ~25 rad, NaN, inf): a
    tenth of libm's cos and sin together, the largest share of a node's geometry."""
    if not abs(angle) < _LIMIT:
        return math.cos(angle), math.sin(angle)
    k = round(angle * _INVERSE)
    d = angle - k * _STEP
    i = k % _SIZE  # negative k from the end, as stored
    cb, sb = _COS[i], _SIN[i]
    d2 = d * d
    cd = (d2 * (1 / 24) - 0.5) * d2 + 1.0
    sd = d - d2 * d * (1 / 6)
    return cb * cd - sb * sd, sb * cd + cb * sd


@njit(cache=True, error_model="numpy")
def closing_geometry(theta: NDArray, A: NDArray, link: NDArray, rod_offset: NDArray,
                     kc: NDArray, pre: NDArray, extension: NDArray, spring_rate: NDArray,
                     loads: NDArray, gap: float, xi: float, l2: float, theta_bo: float,
                     out: NDArray) -> None:
    """:func:`camopt.cases.vcb.dynamics.closing_inputs` of every design into ``out``
    (7, nd, m): phi', s1, ds1/dtheta, the closing springs' energy and torque, the
    resisting springs' energy V_r(s1) and torque Fr ds1/dtheta, on the nodes ``theta``
    (m,). Per design: the law's coefficients ``A`` (nd, d + 1, by Horner's rule), the
    linkage ``link`` (nd, 5) and ``rod_offset`` (nd,) (the four-bar of
    :func:`camopt.mechanics.fourbar.output_motion` on its mirrored branch, the rod of
    :meth:`VcbModel.kinematics`), spring rates ``kc`` and compressions ``pre`` (nd, 2) and
    the loads' opening k, arm, stretch, contact k, preload and free-contact force
    ``loads`` (6, nd) (:class:`~camopt.cases.vcb.model.Loads`); the springs' extension and
    rate on the nodes (m,) are shared."""
    nd, d1 = A.shape
    m = len(theta)
    phi = np.empty(m)
    dphi = np.empty(m)
    cos2 = np.empty(m)
    sin2 = np.empty(m)
    for i in range(nd):
        l1, l4, c1, s1f, k24, k12, lengths, p, q = _linkage(link[i], rod_offset[i], l2,
                                                            theta_bo)
        k1, k2, p1, p2 = kc[i, 0], kc[i, 1], pre[i, 0], pre[i, 1]
        ok, arm, x0 = loads[0, i], loads[1, i], loads[2, i]
        wk, wp, fc = loads[3, i], loads[4, i], loads[5, i]
        # the law in passes over the nodes (the innermost loops run over nodes, so the
        # compiler can vectorise them), by Horner's rule as before
        phi[:] = A[i, d1 - 1]
        dphi[:] = (d1 - 1) * A[i, d1 - 1]
        for k in range(d1 - 2, -1, -1):
            a_k = A[i, k]
            for j in range(m):
                phi[j] = a_k + theta[j] * phi[j]
            if k > 0:
                ka_k = k * a_k
                for j in range(m):
                    dphi[j] = ka_k + theta[j] * dphi[j]
        for j in range(m):
            cos2[j], sin2[j] = sincos(phi[j] + xi)
        # the rod's height at the first node, then every node in one branch-free pass
        y0 = 0.0
        for j in range(min(m, 1)):
            y0 = _rod(cos2[j], sin2[j], k24, k12, l1, l4, c1, s1f, lengths, p, q)
        for j in range(m):
            c2, s2 = cos2[j], sin2[j]
            c4, s4, root = _four_bar(c2, s2, k24, k12, l1, l4, c1, s1f, lengths)
            rate = (-k24 * (s2 * c4 - c2 * s4) - k12 * c1 * s2 + k12 * s1f * c2) / root
            s1 = (s4 * p - c4 * q) - y0
            ds1 = (s4 * q + c4 * p) * rate * dphi[j]
            ext = extension[j]
            out[0, i, j] = dphi[j]
            out[1, i, j] = s1
            out[2, i, j] = ds1
            out[3, i, j] = 0.5 * (k1 * (p1 - ext) ** 2 + k2 * (p2 - ext) ** 2)
            out[4, i, j] = (k1 * (p1 - ext) + k2 * (p2 - ext)) * spring_rate[j]
            stretch = x0 + arm * s1
            # numpy's maximum and minimum: a NaN (no assembly) stays NaN
            wipe = (s1 - gap if s1 - gap > 0.0 or math.isnan(s1) else 0.0) + wp
            closed = gap if s1 > gap else s1
            out[5, i, j] = (0.5 * ok * (stretch * stretch - x0 * x0)
                            + 0.5 * wk * (wipe * wipe - wp * wp) - fc * closed)
            force = s1 * wk + wk * (wp - gap) if s1 >= gap else -fc
            out[6, i, j] = (force + s1 * (arm * ok * arm) + arm * ok * x0) * ds1


@njit(cache=True, error_model="numpy", inline="always")
def _linkage(link: NDArray, rod_offset: float, l2: float, theta_bo: float
             ) -> tuple[float, float, float, float, float, float, float, float, float]:
    """One design's four-bar constants for :func:`_four_bar` and the rod arm's (p, q), from
    its linkage (l1, l3, l4, l5, theta1) (5,) and rod offset: l1, l4, cos and sin of theta1
    in the mirrored frame, 2 l2 l4, 2 l1 l2, l3^2 - l1^2 - l4^2 - l2^2, p and q."""
    l1, l3, l4, l5, th1 = link[0], link[1], link[2], link[3], link[4]
    frame = theta_bo - th1
    c1, s1f = math.cos(frame), math.sin(frame)
    lengths = l3 ** 2 - l1 ** 2 - l4 ** 2 - l2 ** 2
    beta = rod_offset + theta_bo
    return (l1, l4, c1, s1f, 2 * l2 * l4, 2 * l1 * l2, lengths, l5 * math.cos(beta),
            l5 * math.sin(beta))


@njit(cache=True, error_model="numpy")
def _rod(c2: float, s2: float, k24: float, k12: float, l1: float, l4: float, c1: float,
         s1f: float, lengths: float, p: float, q: float) -> float:
    """The rod's height y_m at one node (the four-bar of :func:`closing_geometry`)."""
    c4, s4, _ = _four_bar(c2, s2, k24, k12, l1, l4, c1, s1f, lengths)
    return s4 * p - c4 * q


@njit(cache=True, error_model="numpy", inline="always")
def _four_bar(c2: float, s2: float, k24: float, k12: float, l1: float, l4: float,
              c1: float, s1f: float, lengths: float) -> tuple[float, float, float]:
    """cos and sin of the output angle theta4 on the branch -1 and the root
    sqrt(A^2 + B^2 - C^2) of A cos4 + B sin4 = C (Eq 3 in the frame turned to BO), for
    the follower's cos2, sin2 (inlined where it is called: the node loop stays one
    branch-free pass the compiler vectorises)."""
    a = -k24 * c2 + 2 * l1 * l4 * c1
    b = -k24 * s2 + 2 * l1 * l4 * s1f
    c = k12 * c1 * c2 + k12 * s1f * s2 + lengths
    norm = a * a + b * b
    root = math.sqrt(norm - c * c)
    inv = 1.0 / norm
    return (a * c + b * root) * inv, (b * c - a * root) * inv, root


@njit(cache=True, error_model="numpy")
def node_kinematics(angle: NDArray, dphi: NDArray, link: NDArray, rod_offset: NDArray,
                    l2: float, theta_bo: float, out: NDArray) -> None:
    """The follower's cos and sin and the four-bar and rod of
    :meth:`camopt.cases.vcb.model.VcbModel.kinematics` (Eqs 6, 3) on a grid, into ``out``
    (6, n, m): cos(xi + phi), sin(xi + phi), cos4, sin4 (the mirrored frame), the rod's
    travel s1 from the first node (m) and ds1/dtheta_c (m/rad). ``angle`` = xi + phi and
    ``dphi`` (n, m); ``link`` (n, 5) or (1, 5) shared, ``rod_offset`` (n,) or (1,) rad.
    The numpy path's operations in its order (:func:`camopt.mechanics.fourbar.
    output_motion` on the branch -1, :func:`camopt.mechanics.trig.sincos`), in one pass
    per row instead of ~30 full-size temporaries: the statics on a case's nodes for a
    chunk of tolerance draws were a tenth of the robust VCB's search."""
    n, m = angle.shape
    for i in range(n):
        l1, l4, c1, s1f, k24, k12, lengths, p, q = _linkage(
            link[0 if link.shape[0] == 1 else i],
            rod_offset[0 if rod_offset.shape[0] == 1 else i], l2, theta_bo)
        for j in range(m):
            c2, s2 = sincos(angle[i, j])
            out[0, i, j] = c2
            out[1, i, j] = s2
        y0 = 0.0
        for j in range(m):
            c2, s2 = out[0, i, j], out[1, i, j]
            c4, s4, root = _four_bar(c2, s2, k24, k12, l1, l4, c1, s1f, lengths)
            rate = (-k24 * (s2 * c4 - c2 * s4) - k12 * c1 * s2 + k12 * s1f * c2) / root
            y = s4 * p - c4 * q
            if j == 0:
                y0 = y
            out[2, i, j] = c4
            out[3, i, j] = s4
            out[4, i, j] = y - y0
            out[5, i, j] = (s4 * q + c4 * p) * rate * dphi[i, j]


@njit(cache=True, error_model="numpy")
def contact_ratio(dphi: NDArray, ddphi: NDArray, cos_a: NDArray, sin_a: NDArray,
                  torque: NDArray, l2: float, l6: float, rf: float, out: NDArray) -> None:
    """The reciprocal ``r`` of Fn (1/rho + 1/rf) on every node, (n, m) into ``out``, that
    :func:`camopt.cases.vcb.contact.peak_stress` minimises (Eqs 15, 19, 27-30): its numpy
    operations in their order, one pass instead of a dozen full-size arrays."""
    n, m = dphi.shape
    for i in range(n):
        for j in range(m):
            d1, ca, sa = dphi[i, j], cos_a[i, j], sin_a[i, j]
            w = d1 * -l2 + l2
            lc = ca * l6
            v = w - lc
            speed_sq = (v - lc) * w + l6 * l6
            den = ddphi[i, j] * sa * -(l2 * l6) + speed_sq
            den -= w * d1 * v
            gap = math.sqrt(speed_sq) * speed_sq - den * rf
            r = abs(sa * d1) * gap
            out[i, j] = r / (speed_sq * speed_sq * abs(torque[i, j]))

