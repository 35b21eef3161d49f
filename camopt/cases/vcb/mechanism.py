"""The VCB design as the data a multibody model is built from: points, lengths, the cam's
follower law, springs, masses, inertias and friction, all SI and plain floats.

Read from the run's problem (its stored config and the design's variables): the geometry
and parameters only, never camopt's closing dynamics, so the multibody model is an
independent check of them.

:class:`~camopt.cases.vcb.problem.VcbProblem` is imported where used: a mechanism read from
an archive needs no problem."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from camopt.mechanics import Floats
from camopt.units import DEG, MM

if TYPE_CHECKING:  # the parameters' container only, not the dynamics
    from camopt.cases.vcb.dynamics import MotionParameters


@dataclass(frozen=True)
class Mechanism:
    """The closing mechanism of one design (SI; angles in rad, counter-clockwise).

    Cam centre O at the origin. Follower BD pivots at ``pivot_b``; its swing angle
    xi + phi is measured clockwise from BO (``bo_angle``), phi(theta_c) the polynomial
    ``law`` (coefficients a0.., rad per rad^k) of the cam angle theta_c, 0 where the cam
    meets the roller, ``cam_end`` at the end of travel. Four-bar B-D-L-E: ground BE
    (``l1`` at ``theta1``), coupler DL ``l3``, output EL ``l4``; the arm EM (``l5``) at
    ``rod_offset`` + pi from EL; the rod follows M's height. Closing springs between the
    fixed point ``spring_g`` and the crank point Q at ``crank_l8`` from O, at angle
    ``crank_angle0`` + theta_c; each is compressed ``precompression`` (m) in the opened
    state (crank angle ``crank_angle0`` - ``theta0``); ``release_angle`` the cam angle
    where the latch lets the charged cam go (negative)."""

    pivot_b: tuple[float, float]
    l2: float
    xi: float
    bo_angle: float
    law: tuple[float, ...]
    cam_end: float
    l1: float
    l3: float
    l4: float
    l5: float
    theta1: float
    rod_offset: float
    spring_g: tuple[float, float]
    crank_l8: float
    crank_angle0: float
    theta0: float
    spring_rates: tuple[float, float]
    precompression: tuple[float, float]
    release_angle: float
    efficiency: float
    cam_inertia: float
    follower_inertia: float
    rod_mass: float
    contacts_mass: float
    friction: float
    release_friction: float
    opening_k: float
    opening_arm: float
    opening_stretch_open: float
    wipe_k: float
    wipe_preload: float
    gap: float
    free_contact: float
    coupler_mass: float = 0.0
    """Beyond camopt's model: the coupler DL's own mass (kg, a uniform bar), 0 = massless."""

    def phi(self, theta: Floats) -> Floats:
        """Follower swing phi (rad) at cam angles ``theta``."""
        return np.polynomial.polynomial.polyval(theta, np.asarray(self.law))

    def roller(self, phi: Floats) -> Floats:
        """Roller centre D (m), (..., 2), at follower swing ``phi``: link BD turned
        clockwise from BO by xi + phi."""
        angle = self.bo_angle - (self.xi + np.asarray(phi))
        b = np.asarray(self.pivot_b)
        return b + self.l2 * np.stack([np.cos(angle), np.sin(angle)], axis=-1)

    def pitch_curve(self, points: int) -> Floats:
        """The roller centre's path in the cam's frame (the frame at theta_c = 0), (points,
        2) m, over theta_c = 0 .. cam_end: the pitch curve the cam profile is offset from
        by the roller radius."""
        theta = np.linspace(0.0, self.cam_end, points)
        d = self.roller(self.phi(theta))
        c, s = np.cos(theta), np.sin(theta)  # rotate back by -theta
        return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)

    def ground_e(self) -> Floats:
        """The output link's pivot E (m)."""
        return np.asarray(self.pivot_b) + self.l1 * np.array([np.cos(self.theta1),
                                                               np.sin(self.theta1)])

    def coupler_point(self, d: Floats) -> Floats:
        """L, the coupler-output joint, for roller centre ``d``: where the circles about D
        (l3) and E (l4) meet, on the assembly branch with L to the left of D -> E
        (the opened vendor linkage's; a branch change would need the links to pass
        through a dead point)."""
        e = self.ground_e()
        de = e - d
        dist = float(np.hypot(*de))
        a = (self.l3**2 - self.l4**2 + dist**2) / (2 * dist)
        h = np.sqrt(max(self.l3**2 - a * a, 0.0))
        u = de / dist
        normal = np.array([-u[1], u[0]])  # left of D -> E
        return d + a * u + h * normal

    def rod_point(self, l_point: Floats) -> Floats:
        """M, the arm's end that lifts the rod, for the coupler point L."""
        e = self.ground_e()
        th4 = np.arctan2(l_point[1] - e[1], l_point[0] - e[0])
        angle = th4 + np.pi + self.rod_offset
        return e + self.l5 * np.array([np.cos(angle), np.sin(angle)])

    def rod_travel(self, theta: float) -> float:
        """Rod travel s1 from the opened position (m) at cam angle ``theta`` (rigid
        kinematics; what the multibody model's contact compliance adds to is measured
        against this)."""
        def height(t: float) -> float:
            d = self.roller(self.phi(np.asarray(t)))
            return float(self.rod_point(self.coupler_point(d))[1])
        return height(theta) - height(0.0)


def mechanism_of(problem: object, x: Floats, params: MotionParameters | None = None,
                 pre: Floats | None = None) -> Mechanism:
    """The mechanism of design ``x`` (SI variables) of a VCB run's problem: its decoded
    cam law, springs and linkage, the config's fixed geometry and loads, the identified
    motion parameters (the release moved with a design's latch) and, for a breaker set at
    the factory, the set springs' compressions; or one parameter set ``params``
    (MotionParameters, its release already the design's) with the closing springs'
    compressions ``pre`` (2,) m (None: the case's or the factory setting's)."""
    from camopt.cases.vcb.problem import VcbProblem
    from camopt.cases.vcb.rotation import release_angle

    if not isinstance(problem, VcbProblem):
        raise TypeError("a VCB problem")
    c, m = problem.config, problem.model
    x = np.atleast_2d(np.asarray(x, dtype=float))
    A, kc, link = problem.designs(x)
    A = problem.profiled(A, None)
    parts, _ = problem.as_set(x, None)
    compression = (c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM)
    if pre is not None:
        compression = (float(pre[0]), float(pre[1]))
    elif parts is not None and parts.pre is not None:
        compression = (float(parts.pre[0, 0]), float(parts.pre[0, 1]))
    if params is None:
        params = replace(problem.dynamics,
                         release_offset_rad=np.ravel(problem.release_offset(x))[0])
    cols = params.columns(1, c.efficiency)
    loads = problem.load
    release = float(release_angle(m, cols.release_offset_rad[0, 0]))
    return Mechanism(
        pivot_b=(float(m.B[0]), float(m.B[1])), l2=float(m.l2), xi=float(m.xi),
        bo_angle=float(m.theta_bo), law=tuple(float(a) for a in A[0]),
        cam_end=float(m.theta_c[-1]),
        l1=float(link[0, 0]), l3=float(link[0, 1]), l4=float(link[0, 2]),
        l5=float(link[0, 3]), theta1=float(link[0, 4]), rod_offset=float(problem.rod_offset),
        spring_g=(float(m.G[0]), float(m.G[1])), crank_l8=c.crank_l8_mm * MM,
        crank_angle0=float(m.contact_crank_angle), theta0=c.theta0_deg * DEG,
        spring_rates=(float(kc[0, 0]), float(kc[0, 1])), precompression=compression,
        release_angle=release, efficiency=float(cols.efficiency[0, 0]),
        cam_inertia=float(cols.cam_kg_m2[0, 0]),
        follower_inertia=float(cols.follower_kg_m2[0, 0]),
        rod_mass=float(cols.rod_kg[0, 0]), contacts_mass=float(cols.contacts_kg[0, 0]),
        friction=float(cols.friction_nm[0, 0]),
        release_friction=float(cols.release_friction_nm[0, 0]),
        opening_k=float(loads.opening_k), opening_arm=float(np.ravel(loads.opening_arm)[0]),
        opening_stretch_open=float(np.ravel(loads.opening_stretch_open)[0]),
        wipe_k=float(np.ravel(loads.wipe_k)[0]),
        wipe_preload=float(np.ravel(loads.wipe_preload)[0]), gap=float(loads.gap),
        free_contact=float(np.ravel(loads.free_contact)[0]))
