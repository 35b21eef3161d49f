"""12 kV VCB closing mechanism, the physics: geometry, kinematics and forces (the loads at
the rod: :mod:`camopt.cases.vcb.loads`; the cam-roller contact:
:mod:`camopt.cases.vcb.contact`; the follower law's zeros and extremes:
:mod:`camopt.cases.vcb.law`).

Kang, Huang & Yang (2023), Machines 11:150 (``shared/papers/000_*.txt``).

Kinematic chain: the closing springs (fixed end G, crank Q on the cam shaft at
l8 from O) turn the cam; the cam pushes the roller of follower BD (input link 2 of
the four-bar B-D-L-E); output link LE carries the arm EM that lifts the insulated
rod. Step 1 varies the follower's cubic motion (a1, a2, a3) and the spring rates;
step 2 varies the linkage (l1, l3, l4, l5, theta1) under the step-1 cam.

The paper's force arms r1..r6 (Eqs 19-24) come from figures we do not have; the
general output force is computed by virtual work instead: Fo = T / (ds1/dtheta),
with T the closing springs' torque on the cam. That is exactly Eq 24's arm ratio.
Every array is (population, cam position); nothing loops over individuals.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.contact import Contact, peak_stress, refined_min, row_max
from camopt.cases.vcb.law import (
    follower_dwell,
    phi_max,
    polynomial_value,
    rate_zeros,
)
from camopt.cases.vcb.loads import Loads
from camopt.errors import ConfigError
from camopt.mechanics import cam, fourbar, hertz
from camopt.units import DEG, GPA, MM, N_PER_MM

__all__ = [
    "Contact", "ForceBalance", "Kinematics", "Loads", "VcbModel", "follower_dwell",
    "phi_max", "polynomial_value", "rate_zeros", "refined_min", "row_max", "unassembled",
]

REFERENCE_A0_TOLERANCE_DEG = 0.05
"""Largest difference (deg) between a reference cam's follower angle at theta_c = 0 (its
points' law) and the case geometry's (Eq 8): five times the points' fitting tolerance."""


@dataclass(frozen=True)
class Kinematics:
    """Follower, linkage and rod motion on the cam-angle grid, (n, m) arrays.

    ``cos4``/``sin4`` are the output link's angle in the frame turned to BO and mirrored
    (:meth:`VcbModel.output_angle` turns them back); ``s1`` is the rod travel from the
    opened position (m) and ``ds1`` its rate ds1/dtheta_c (m/rad)."""

    follower: cam.Follower
    cos4: NDArray
    sin4: NDArray
    s1: NDArray
    ds1: NDArray

    @property
    def dphi(self) -> NDArray:
        """Follower rate dphi/dtheta_c, (n, m)."""
        return self.follower.dphi

    def ends(self) -> Kinematics:
        """The first and last positions only (n, 2): the opened and closed states."""
        f = self.follower
        k = [0, -1]
        follower = cam.Follower(f.theta_c[:, k], f.xi, f.angle[:, k], f.dphi[:, k],
                                f.ddphi[:, k], f.cos_a[:, k], f.sin_a[:, k])
        return Kinematics(follower, self.cos4[:, k], self.sin4[:, k], self.s1[:, k],
                          self.ds1[:, k])


@dataclass(frozen=True)
class ForceBalance:
    """Forces along the stroke at positions i = 1..Ns, (n, Ns), and the works of Eqs 23-26
    per design (n,) in J: closing-spring torque ``torque`` (N m), rod travel ``s1`` (m)
    and rate ``ds1`` (m/rad), general resistant force ``fr`` (N, computed when asked),
    driving and resistant work, and the surplus driving - resistant / efficiency (Eq 26).
    The works are exact potential differences (Eq 23's integrals), independent of the
    number of positions; only the forces are sampled."""

    torque: NDArray
    s1: NDArray
    ds1: NDArray
    loads: Loads
    driving: NDArray
    resistant: NDArray
    surplus: NDArray

    @property
    def fr(self) -> NDArray:
        """General resistant force Fr (Eq 24) at positions 1..Ns (N), (n, Ns)."""
        return self.loads.resistant_force(self.s1)


class VcbModel:
    """Geometry and loads of the VCB mechanism in SI, vectorised over designs."""

    def __init__(self, c: VcbConfig) -> None:
        self.c = c
        self.B = np.array(c.pivot_b_mm) * MM
        self.G = np.array(c.pivot_g_mm) * MM
        self.l2, self.l6 = c.l2_mm * MM, float(np.hypot(*self.B))
        self.rb, self.rf = c.rb_mm * MM, c.rf_mm * MM
        self.xi = float(cam.base_angle(self.l2, self.l6, self.rb + self.rf))  # Eq 10
        self.theta_bo = float(np.arctan2(-self.B[1], -self.B[0]))  # direction B -> O
        end = c.node_cam_deg[-1] * DEG
        self.theta_c = np.linspace(0.0, end, c.positions + 1)  # Ns intervals (Eq 39)
        self.dtheta = end / c.positions
        self.spring_ext, self.spring_rate = self.closing_spring_geometry(self.theta_c)
        # driving work per N/m of each spring over the stroke (J per N/m): exact, linear
        ends = self.closing_energy(np.eye(2), self.spring_ext[[0, -1]])
        self.unit_work = ends[:, 0] - ends[:, 1]
        self.vendor_link = np.array([c.l1_mm * MM, c.l3_mm * MM, c.l4_mm * MM,
                                     c.l5_mm * MM, c.theta1_deg * DEG])
        self.vendor_a = self.node_cubic(self.vendor_link)
        if c.reference_law is not None:  # the reference cam as built (its points' law)
            self.vendor_a = np.asarray(c.reference_law, dtype=float)
            miss = abs(self.vendor_a[0] - self.phi0()) / DEG
            if miss > REFERENCE_A0_TOLERANCE_DEG:
                raise ConfigError("case", "reference_law", f"the reference cam's follower "
                                  f"angle at theta_c = 0 is {self.vendor_a[0] / DEG:.3f} deg; "
                                  f"the case's geometry (Eq 8) puts it at "
                                  f"{self.phi0() / DEG:.3f} deg: a cam of another geometry?")
        # spring crank angles (rad): dead centre (Q on OG, springs most compressed) and
        # where the cam meets the roller, QOX + theta0 (Sec 2.2 Step 8)
        self.dead_centre = float(np.arctan2(self.G[1], self.G[0]))
        self.contact_crank_angle = (c.preset_qox_deg + c.theta0_deg) * DEG
        self._graded: dict[int, tuple[NDArray, NDArray, NDArray]] = {}

    # ---- geometry ---------------------------------------------------------------
    def closing_spring_geometry(self, theta_c: NDArray, pre_rotation: float | None = None
                                ) -> tuple[NDArray, NDArray]:
        """Spring extension from the opened state (m) and its rate dL/dtheta (m/rad) at
        cam angles ``theta_c`` (any shape).

        The springs act along GQ, Q on the cam shaft at l8 and angle QOX + theta,
        theta = theta0 + theta_c (Sec 2.2 Step 8); counter-clockwise turns Q away
        from its dead centre toward G, so the charged springs extend. ``pre_rotation``
        replaces theta0 (0 gives the free rotation before the cam meets the roller).
        """
        c = self.c
        l8 = c.crank_l8_mm * MM
        theta0 = c.theta0_deg * DEG if pre_rotation is None else pre_rotation
        theta_c = np.asarray(theta_c, dtype=float)
        angle = c.preset_qox_deg * DEG + theta0 + theta_c
        cos, sin = np.cos(angle), np.sin(angle)
        gx, gy = self.G[0] - l8 * cos, self.G[1] - l8 * sin
        length = np.hypot(gx, gy)
        q_open = l8 * np.array([np.cos(c.preset_qox_deg * DEG), np.sin(c.preset_qox_deg * DEG)])
        rate = -(gx * (-l8 * sin) + gy * (l8 * cos)) / length
        return length - np.hypot(*(self.G - q_open)), rate

    def graded_springs(self, steps: int) -> tuple[NDArray, NDArray, NDArray]:
        """The closing's graded cam-angle grid on ``steps`` intervals
        (:func:`camopt.cases.vcb.locate.graded_grid`) with the springs' extension and
        rate there (:meth:`closing_spring_geometry`), (steps + 1,) each; computed once
        per step count."""
        if steps not in self._graded:
            from camopt.cases.vcb.locate import graded_grid  # locate imports no model

            theta = graded_grid(self.theta_c[-1], steps)[0]
            self._graded[steps] = (theta, *self.closing_spring_geometry(theta))
        return self._graded[steps]

    @functools.cached_property
    def release_crank(self) -> NDArray:
        """:meth:`spring_crank`'s five numbers, then the dead centre's and the roller
        contact's crank angles (rad): what the compiled free rotation reads, (7,)."""
        return np.array([*self.spring_crank(), self.dead_centre, self.contact_crank_angle])

    def spring_crank(self) -> tuple[float, float, float, float, float]:
        """The closing springs' crank as numbers: l8 (m), G's x and y (m), the crank angle
        QOX + theta0 at theta_c = 0 (rad) and the springs' length in the opened state (m)
        (what :meth:`closing_spring_travel` and its compiled twin compute from)."""
        c = self.c
        l8 = c.crank_l8_mm * MM
        q_open = l8 * np.array([np.cos(c.preset_qox_deg * DEG),
                                np.sin(c.preset_qox_deg * DEG)])
        return (l8, float(self.G[0]), float(self.G[1]),
                c.preset_qox_deg * DEG + c.theta0_deg * DEG, float(np.hypot(*(self.G - q_open))))

    def closing_spring_travel(self, start: NDArray, turn: NDArray
                              ) -> tuple[NDArray, NDArray, NDArray]:
        """The closing springs from cam angle ``start`` (n, 1) turned on by ``turn``
        (n, m) rad: their extension at ``start`` from the opened state (n, 1) m, the
        extension gained since ``start`` (n, m) m and the rate dL/dtheta (n, m) m/rad at
        ``start + turn`` (as :meth:`closing_spring_geometry`). The gain is computed
        without subtracting two lengths (L^2 - L0^2 from the half-angle products, over
        L + L0), so it keeps its relative precision however small the turn: what the
        energy of a cam that barely leaves its release needs."""
        l8, gx, gy, base, open_length = self.spring_crank()
        a0 = base + start
        angle = a0 + turn
        length0 = np.hypot(gx - l8 * np.cos(a0), gy - l8 * np.sin(a0))
        length = np.hypot(gx - l8 * np.cos(angle), gy - l8 * np.sin(angle))
        mid = a0 + 0.5 * turn
        # L^2 = |G|^2 + l8^2 - 2 l8 (Gx cos a + Gy sin a); cos a - cos a0 and
        # sin a - sin a0 as products with sin(turn / 2)
        squares = 4 * l8 * np.sin(0.5 * turn) * (gx * np.sin(mid) - gy * np.cos(mid))
        gained = squares / (length + length0)
        rate = l8 * (gx * np.sin(angle) - gy * np.cos(angle)) / length
        return length0 - open_length, gained, rate

    def phi0(self) -> float:
        """Follower angle at theta_c = 0 with the node clearance (Eq 8)."""
        rp = self.rb + self.rf + self.c.node_clearance_mm * MM
        return float(cam.base_angle(self.l2, self.l6, rp) - self.xi)

    def node_cubic(self, link: NDArray) -> NDArray:
        """a0..a3 from the vendor data (Eqs 1-8, Step 9) in the reading that reproduces
        the printed coefficients: node clearance 1 mm in Eqs 2 and 8, theta1 from Table 7,
        theta_4i = 2 asin(f_i s2bar / 2 l4) (Eq 4 applied to each node's displacement),
        the output link turning clockwise, and phi_i = |theta_2i - theta_20| (Eq 7)."""
        c = self.c
        l1, l3, l4, l5, th1 = link
        s2bar = (l4 / l5) * c.s1_bar_mm * MM / c.alpha + (c.beta_mm + c.gamma_mm) * MM  # Eq 1
        rp = self.rb + self.rf + c.node_clearance_mm * MM
        th20 = np.arctan(self.B[1] / self.B[0]) - cam.base_angle(self.l2, self.l6, rp)  # Eq 2
        th40 = fourbar.output_angle(l1, self.l2, l3, l4, th1, th20, 1.0)  # Eq 3
        frac = np.asarray(c.node_fractions[1:])
        th4i = 2 * np.arcsin(frac * s2bar / (2 * l4))  # Eq 4
        th2i = fourbar.input_angle(l1, self.l2, l3, l4, th1, th40 - th4i, -1.0)  # Eq 5
        phi = np.r_[self.phi0(), np.abs(th2i - th20)]  # Eqs 7-8
        nodes = np.asarray(c.node_cam_deg) * DEG
        return np.linalg.solve(np.vander(nodes, 4, increasing=True), phi)  # Step 9

    # ---- kinematics and forces ----------------------------------------------------
    def kinematics(self, A: NDArray, link: NDArray, rod_offset: NDArray | float,
                   theta_c: NDArray | None = None, kernel: ModuleType | None = None
                   ) -> Kinematics:
        """Follower, linkage and rod motion, (n, m) arrays; ``A`` (n, 4), ``link`` (n, 5),
        on the case's grid of Ns + 1 cam angles or on ``theta_c`` (m,) starting at 0.

        The follower swing turns link 2 clockwise: theta2 = angle(BO) - (xi + phi). The
        four-bar is solved in the frame turned by angle(BO) and mirrored (y -> -y),
        where theta2 is xi + phi itself: no trigonometry, rotation or sign change is
        spent on the grid, and mirroring swaps the assembly branch. ``cos4``/``sin4``
        are in that frame (:meth:`output_angle` turns them back). With ``kernel``
        (:func:`camopt.cases.vcb.motion.compiled`, which loads numba: an evaluation's
        path, not a config check's) in one compiled pass per row, the numpy path's
        operations in its order.
        """
        grid = self.theta_c if theta_c is None else theta_c
        if kernel is None:
            return self._numpy_kinematics(A, link, rod_offset, grid)
        t, angle, dphi, ddphi = cam.polynomial_law(A, grid, self.xi)
        link = np.asarray(link, dtype=float)
        # shared linkage (step 1): one row the compiled pass reads for every design
        link = link[:1] if np.all(link == link[0]) else link
        offset = np.asarray(rod_offset, dtype=float).reshape(-1)
        out = np.empty((6, *angle.shape))
        kernel.node_kinematics(angle, dphi, link, offset, float(self.l2),
                               float(self.theta_bo), out)
        f = cam.Follower(t[None, :], self.xi, angle, dphi, ddphi, out[0], out[1])
        return Kinematics(f, out[2], out[3], out[4], out[5])

    def _numpy_kinematics(self, A: NDArray, link: NDArray, rod_offset: NDArray | float,
                          grid: NDArray) -> Kinematics:
        """:meth:`kinematics` in numpy: the reference, and the path without numba."""
        f = cam.Follower.polynomial(A, grid, self.xi)
        # shared linkage (step 1): scalars broadcast fastest; else one column per design
        parts: list[float] | list[NDArray] = (
            [float(v) for v in link[0]] if np.all(link == link[0])
            else [link[:, i : i + 1] for i in range(5)])
        l1, l3, l4, l5, th1 = parts
        frame = self.theta_bo - th1  # theta1 in the mirrored frame
        c4, s4, rate = fourbar.output_motion(l1, self.l2, l3, l4, np.cos(frame),
                                             np.sin(frame), f.cos_a, f.sin_a, -1.0)  # Eq 3
        # arm EM at theta4 + pi + offset: it points away from L; rod height
        # y_m = -l5 sin(theta4 + offset) with theta4 = angle(BO) - theta4', and
        # d theta4 / d theta_c = -rate phi'
        beta = rod_offset + self.theta_bo
        p, q = l5 * np.cos(beta), l5 * np.sin(beta)
        tmp = np.multiply(c4, q)
        s1 = np.multiply(s4, p)
        s1 -= tmp  # y_m, in place (hot path)
        s1 -= s1[:, :1].copy()  # travel from the opened position
        ds1 = np.multiply(s4, q)
        ds1 += np.multiply(c4, p, out=tmp)
        ds1 *= rate
        ds1 *= f.dphi
        return Kinematics(f, c4, s4, s1, ds1)

    def output_angle(self, kin: Kinematics) -> NDArray:
        """Output-link angle theta4 (rad, in (-pi, pi]) in the mechanism's frame, (n, m)."""
        th4 = self.theta_bo - np.arctan2(kin.sin4, kin.cos4)
        return np.arctan2(np.sin(th4), np.cos(th4))

    def closing_energy(self, kc: NDArray, extension: NDArray, pre: NDArray | None = None
                       ) -> NDArray:
        """Elastic energy of both closing springs (J), (n, m), at spring ``extension`` (m,)
        from the opened state; kc (n, 2) N/m; compressions in the opened state from Table 2,
        or ``pre`` (n, 2) m, one pair per design (springs made to a free-length tolerance)."""
        c = self.c
        if pre is not None:
            return self.closing_energy_rows(kc, np.atleast_2d(extension), pre)
        left = np.stack([(c.kc1_precompression_mm * MM - extension) ** 2,
                         (c.kc2_precompression_mm * MM - extension) ** 2])
        return 0.5 * (kc @ left.reshape(2, -1)).reshape((len(kc), *np.shape(extension)))

    def closing_energy_rows(self, kc: NDArray, extension: NDArray, pre: NDArray | None = None
                            ) -> NDArray:
        """As :meth:`closing_energy` with one grid per design: ``extension`` (n, m) (or
        (1, m) shared), ``pre`` (n, 2) m or the config's compressions."""
        p1, p2 = self.precompressions(pre)
        return 0.5 * (kc[:, :1] * (p1 - extension) ** 2 + kc[:, 1:2] * (p2 - extension) ** 2)

    def precompressions(self, pre: NDArray | None) -> tuple[NDArray | float, NDArray | float]:
        """The closing springs' compressions in the opened state (m): the config's, or
        the columns (n, 1) of ``pre`` (n, 2)."""
        c = self.c
        if pre is None:
            return c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM
        return pre[:, :1], pre[:, 1:2]

    def closing_torque(self, kc: NDArray, geometry: tuple[NDArray, NDArray] | None = None,
                       pre: NDArray | None = None) -> NDArray:
        """Torque of both closing springs on the cam, (n, m) N m; kc (n, 2) N/m; on the
        case's grid or at the (extension, rate) of :meth:`closing_spring_geometry`;
        ``pre`` (n, 2) m: each design's compressions (else the config's)."""
        c = self.c
        ext, rate = (self.spring_ext, self.spring_rate) if geometry is None else geometry
        if pre is not None:
            p1, p2 = self.precompressions(pre)
            return (kc[:, :1] * (p1 - ext) + kc[:, 1:2] * (p2 - ext)) * rate
        per_rate = np.stack([(c.kc1_precompression_mm * MM - ext),
                             (c.kc2_precompression_mm * MM - ext)]) * rate
        return kc @ per_rate

    def loads(self, rod_travel_vendor: NDArray | float, opening_arm: NDArray | float,
              free_contact: NDArray | float) -> Loads:
        """Resisting loads; spring preloads follow from Table 2's closed-state values on
        the vendor design, so they are properties of the breaker, not of a design."""
        c = self.c
        return Loads(
            opening_k=c.opening_k_n_per_mm * N_PER_MM, opening_arm=opening_arm,
            opening_stretch_open=c.opening_stretch_closed_mm * MM
            - opening_arm * rod_travel_vendor,
            wipe_k=c.wipe_count * c.wipe_k_n_per_mm * N_PER_MM,
            wipe_preload=c.wipe_compression_closed_mm * MM
            - (rod_travel_vendor - c.contact_gap_mm * MM),
            gap=c.contact_gap_mm * MM, free_contact=free_contact, efficiency=c.efficiency)

    def driving_work(self, kc: NDArray, pre: NDArray | None = None) -> NDArray:
        """Work of the closing springs over the stroke theta_c = 0 .. 140 deg (J), (n,):
        their elastic energy at the start less that at the end (Eq 23's first integral,
        exactly: the springs are conservative); ``pre`` as :meth:`closing_energy`."""
        if pre is None:
            return kc @ self.unit_work
        ends = self.closing_energy(kc, self.spring_ext[[0, -1]], pre)
        return ends[:, 0] - ends[:, 1]

    def balance(self, kin: Kinematics, kc: NDArray, torque: NDArray, loads: Loads,
                pre: NDArray | None = None) -> ForceBalance:
        """Fo, Fr along the stroke at positions i = 1..Ns and the works of Eqs 23-26 (J).

        The works are potential differences between the opened and closed states, so
        they do not depend on Ns (the right-endpoint sum of Eq 25 charges the whole
        interval that contains the contacts' touch with the contact springs' 2.5 kN
        step and converges only as 1/Ns).
        """
        driving = self.driving_work(kc, pre)
        # an (n, 1) column: loads may hold one value per design (identification)
        resistant = loads.resistant_energy(kin.s1[:, -1:])[:, 0]
        return ForceBalance(torque=torque[:, 1:], s1=kin.s1[:, 1:], ds1=kin.ds1[:, 1:],
                            loads=loads, driving=driving, resistant=resistant,
                            surplus=driving - resistant / loads.efficiency)  # Eq 26

    @staticmethod
    def output_force(bal: ForceBalance) -> NDArray:
        """General output force Fo (Eq 24) by virtual work, T / (ds1 / dtheta) (N)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return bal.torque / bal.ds1

    def abs_sum(self, bal: ForceBalance) -> NDArray:
        """Eq 39 as printed: the sum over the Ns positions of |Fo - Fr / eps| (N). It grows
        with Ns (a sum, not a force): divide by Ns for the mean gap per position."""
        return np.abs(self.output_force(bal) - bal.fr / self.c.efficiency).sum(axis=1)

    def contact(self, f: cam.Follower, torque: NDArray) -> Contact:
        """Pitch curve, curvature, normal force and Hertz stresses along the stroke."""
        c = self.c
        xp, yp, dxp, dyp = cam.pitch_curve(self.l2, self.l6, f)
        rho = cam.curvature_radius(self.l2, self.l6, f, self.rf)
        with np.errstate(divide="ignore", invalid="ignore"):
            # arm of the common normal about O: |r x n| for the pitch point (Eq 19 by moments)
            arm = np.abs(xp * dxp + yp * dyp) / np.sqrt(dxp * dxp + dyp * dyp)
            fn = np.abs(torque) / arm
        e_eq = hertz.equivalent_modulus(c.cam_modulus_gpa * GPA, c.poisson,
                                        c.cam_modulus_gpa * GPA, c.poisson)
        _, sigma, tau = hertz.line_contact(fn, rho, self.rf, c.contact_length_mm * MM, e_eq)
        return Contact(xp, yp, dxp, dyp, rho, fn, sigma, tau)
    def peak_stress(self, A: NDArray, f: cam.Follower, torque: NDArray,
                    zeros: NDArray | None = None, kernel: ModuleType | None = None
                    ) -> NDArray:
        """Peak Hertz pressure over the stroke per design, the search's fast path
        (:func:`camopt.cases.vcb.contact.peak_stress`; ``kernel`` as in
        :meth:`kinematics`)."""
        return peak_stress(self, A, f, torque, zeros, kernel)


def unassembled(cos4: NDArray, rate: NDArray) -> NDArray:
    """Assembly constraint per design: the fraction of the stroke where the four-bar
    cannot be assembled, or -1 where it assembles everywhere (satisfied, never "active");
    only rows whose rod rate ``rate`` (n, m) has a NaN can fail (one row sum finds them)."""
    g = np.full(len(cos4), -1.0)
    rows = ~np.isfinite(rate.sum(axis=1))
    if rows.any():
        frac = np.isnan(cos4[rows]).mean(axis=1)
        g[rows] = np.where(frac > 0, frac, -1.0)
    return g
