"""12 kV VCB closing mechanism, the physics: geometry, kinematics, forces and contact.

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

from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.errors import ConfigError
from camopt.mechanics import cam, fourbar, hertz
from camopt.units import DEG, GPA, MM, N_PER_MM

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


@dataclass(frozen=True)
class Loads:
    """Load model at the rod: resisting springs, free-contact force, efficiency (SI). The
    springs' rates may be (n, 1) columns, one per design (springs made to a tolerance),
    the efficiency (n,) (Eq 26's surplus)."""

    opening_k: NDArray | float
    opening_arm: NDArray | float
    opening_stretch_open: NDArray | float  # opening-spring stretch in the opened state
    wipe_k: NDArray | float  # all contact springs together
    wipe_preload: NDArray | float  # contact-spring compression at touch
    gap: float
    free_contact: NDArray | float
    efficiency: NDArray | float

    def tiled(self, sets: int) -> Loads:
        """The loads of n designs for ``sets`` parameter sets per design (sets x n rows,
        set-major, as :meth:`~camopt.cases.vcb.dynamics.MotionParameters.repeat`): the
        per-design columns repeated; shared values unchanged."""
        def tile(v: NDArray | float) -> NDArray | float:
            return np.tile(v, (sets,) + (1,) * (np.ndim(v) - 1)) if np.ndim(v) else v
        return replace(self, **{f.name: tile(getattr(self, f.name))  # type: ignore[arg-type]
                                for f in fields(self)})

    def resistant_force(self, s1: NDArray) -> NDArray:
        """General resistant force Fr (Eq 24) at rod travel s1 (N)."""
        arm_k = self.opening_arm * self.opening_k  # coefficients first: few full-size ops
        # contact springs once the contacts touch, the free-contact force before
        touching = np.multiply(s1, self.wipe_k)
        touching += self.wipe_k * (self.wipe_preload - self.gap)
        force = np.where(s1 >= self.gap, touching, -self.free_contact)
        opening = np.multiply(s1, arm_k * self.opening_arm, out=touching)
        opening += arm_k * self.opening_stretch_open
        force += opening
        return force

    def resistant_energy(self, s1: NDArray) -> NDArray:
        """Work done against Fr from the opened position to rod travel s1 (J), exactly:
        Fr depends on s1 alone, so its work is a potential difference (Eqs 23, 24) and
        needs no sampling. Opening spring 1/2 k ((x0 + r s1)^2 - x0^2) with r = r7/r6;
        contact springs 1/2 k_w ((s1 - gap + p)^2 - p^2) after touch; the free-contact
        force -F_fc min(s1, gap) before it."""
        s1 = np.asarray(s1, dtype=float)
        x0 = self.opening_stretch_open
        stretch = x0 + self.opening_arm * s1
        energy = 0.5 * self.opening_k * (stretch * stretch - x0 * x0)
        wipe = np.maximum(s1 - self.gap, 0.0) + self.wipe_preload
        energy = energy + 0.5 * self.wipe_k * (wipe * wipe - self.wipe_preload**2)
        return energy - self.free_contact * np.minimum(s1, self.gap)


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
                   theta_c: NDArray | None = None) -> Kinematics:
        """Follower, linkage and rod motion, (n, m) arrays; ``A`` (n, 4), ``link`` (n, 5),
        on the case's grid of Ns + 1 cam angles or on ``theta_c`` (m,) starting at 0.

        The follower swing turns link 2 clockwise: theta2 = angle(BO) - (xi + phi). The
        four-bar is solved in the frame turned by angle(BO) and mirrored (y -> -y),
        where theta2 is xi + phi itself: no trigonometry, rotation or sign change is
        spent on the grid, and mirroring swaps the assembly branch. ``cos4``/``sin4``
        are in that frame (:meth:`output_angle` turns them back).
        """
        grid = self.theta_c if theta_c is None else theta_c
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
                    zeros: NDArray | None = None) -> NDArray:
        """Peak Hertz pressure over the stroke per design (Eqs 15, 19, 27-30), the search's
        fast path: sigma_max = sqrt(max(Fn (1/rho + 1/rf)) E_e / (2 pi L)), one square
        root per design instead of per sample; no Hertz contact counts as infinite, and so
        does a follower that dwells inside the stroke (phi' = 0: Fn unbounded). The
        sampled extreme is refined by a parabola (:func:`refined_min`), so the value does
        not depend on the sample count. ``A`` (n, 4) are the cubic's coefficients.
        (float32 was tried and rejected: cancellation near a dwell cost 5 % in sigma.)"""
        c = self.c
        l2, l6, rf = self.l2, self.l6, self.rf
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
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
            low = refined_min(r)
            # where p . dp = l6 l2 sin(xi + phi) phi' vanishes inside the stroke the common
            # normal passes through O: the arm of Fn is zero and Fn = T / arm unbounded
            # whatever the grid; phi' = 0 is found exactly, sin(xi + phi) = 0 by a sign
            # change between samples (the swing would have to pass pi twice in one step)
            dwell = np.isfinite(follower_dwell(A, self.theta_c[-1], zeros))
            dwell |= np.any(f.sin_a[:, 1:] * f.sin_a[:, :-1] <= 0, axis=1)
            low[dwell] = 0.0
            top = np.where(low > 0, 1 / (low * ((l6 * l2) * rf)), np.inf)  # NaN too
        e_eq = hertz.equivalent_modulus(c.cam_modulus_gpa * GPA, c.poisson,
                                        c.cam_modulus_gpa * GPA, c.poisson)
        return np.sqrt(top * e_eq / (2 * np.pi * c.contact_length_mm * MM))


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


def rate_zeros(A: NDArray, end: float) -> NDArray:
    """Zeros in [0, end] of the follower's rate phi' = a1 + 2 a2 t + 3 a3 t^2 (+ 4 a4 t^3
    + ...; Eq 12), (n, d - 1) in ascending order for coefficient rows ``A`` (n, d + 1),
    NaN where there is none. The cubic's (d = 3) are exact, from the quadratic formula;
    a higher degree's are the real eigenvalues of phi''s companion matrices (one stacked
    ``numpy.linalg.eigvals`` call; a root counts as real within 1e-9 of its size)."""
    if A.shape[1] > 4:
        return _polynomial_rate_zeros(A, end)
    c0, c1, c2 = A[:, 1], 2 * A[:, 2], 3 * A[:, 3]
    roots = np.empty((len(A), 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = np.sqrt(c1 * c1 - 4 * c2 * c0)
        inv = 0.5 / c2
        np.multiply(-c1 - disc, inv, out=roots[:, 0])
        np.multiply(-c1 + disc, inv, out=roots[:, 1])
        flat = np.abs(c2) <= 1e-12 * (np.abs(c1) + np.abs(c0))  # phi' linear
        if flat.any():
            roots[flat] = (-c0[flat] / c1[flat])[:, None]
    roots[~((roots >= 0) & (roots <= end))] = np.nan
    roots.sort(axis=1)  # NaN last
    return roots


def _polynomial_rate_zeros(A: NDArray, end: float) -> NDArray:
    """:func:`rate_zeros` for degree d >= 4: phi' has degree d - 1. Its coefficients are
    scaled to theta / end (roots in [0, 1]) so the companion matrix is well conditioned;
    a row whose leading coefficient vanishes (relative 1e-12) is solved at the degree
    below it by the same route, down to the linear case."""
    n, d = len(A), A.shape[1] - 1
    k = np.arange(1, d + 1)
    c = A[:, 1:] * k * end ** (k - 1)  # phi' in u = theta / end: sum c_j u^j, j = 0..d-1
    roots = np.full((n, d - 1), np.nan)
    scale = np.abs(c).max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        for deg in range(d - 1, 0, -1):  # degree of phi' actually present
            lead = np.abs(c[:, deg]) > 1e-12 * scale
            rows = lead & np.all(np.abs(c[:, deg + 1:]) <= 1e-12 * scale[:, None], axis=1)
            if not rows.any():
                continue
            comp = np.zeros((int(rows.sum()), deg, deg))
            comp[:, 0, :] = -c[rows, deg - 1::-1] / c[rows, deg:deg + 1]
            comp[:, np.arange(1, deg), np.arange(deg - 1)] = 1.0
            z = np.linalg.eigvals(comp) if deg > 1 else comp[:, :, 0]
            real = np.abs(z.imag) <= 1e-9 * np.maximum(1.0, np.abs(z))
            u = np.where(real & (z.real >= 0) & (z.real <= 1), z.real, np.nan)
            roots[rows, :deg] = u * end
    roots.sort(axis=1)  # NaN last
    return roots


def follower_dwell(A: NDArray, end: float, zeros: NDArray | None = None) -> NDArray:
    """First cam angle in [0, end] where phi' vanishes (rad), NaN where it does not."""
    return (rate_zeros(A, end) if zeros is None else zeros)[:, 0]


def phi_max(A: NDArray, end: float, zeros: NDArray | None = None) -> NDArray:
    """Largest follower swing over 0 <= theta_c <= end (rad), exactly: the law's value at
    the ends and at the zeros of phi' (from :func:`rate_zeros`, computed if not given)."""
    zeros = rate_zeros(A, end) if zeros is None else zeros
    t = np.empty((len(A), 2 + zeros.shape[1]))
    t[:, 0], t[:, 1], t[:, 2:] = 0.0, end, zeros
    return np.nanmax(polynomial_value(A, t), axis=1)


def polynomial_value(A: NDArray, t: NDArray) -> NDArray:
    """The follower law's value phi(t) (rad) for coefficient rows ``A`` (n, d + 1) at
    cam angles ``t`` (n, j) or (j,) rad, by Horner's rule."""
    values = np.broadcast_to(A[:, -1:], np.broadcast_shapes((len(A), 1), np.shape(t)))
    for k in range(A.shape[1] - 2, -1, -1):
        values = A[:, k:k + 1] + t * values
    return values


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


def row_max(a: NDArray) -> NDArray:
    """Row maximum where NaN (no valid Hertz contact) counts as infinite."""
    top = np.max(a, axis=1)  # NaN propagates through max
    return np.where(np.isnan(top), np.inf, top)
