"""EMB negative-radius roller cam — Yan, Chen, Yan & Hang (2023), Actuators 12:329.

A particle is [r1 .. r(N-1), kappa, e] (Eq 26): the polar radii of the spline key
points after r0 = r_st, the initial tangent angle and the follower offset. The
working profile is the cubic spline through (theta0 + j dtheta, r_j), clamped to
the non-working arc at the start (Eqs 19-20) and natural at the end; theta0 and
theta_a follow from the boundary geometry (Eqs 22-24). The whole swarm is
analysed at once on a common normalised grid (``mechanics.spline``).

scipy.special is imported where used (only the fitness with the clamping ramp needs it;
scipy is slow to import).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from camopt.cases.emb_cam.config import EmbCamConfig
from camopt.core.capabilities import Repairable
from camopt.core.problem import Evaluation, Problem, Variable
from camopt.mechanics import Bools, Floats
from camopt.mechanics import polar_cam as pc
from camopt.mechanics.spline import ClampedNaturalSpline
from camopt.units import KN, MM, MPA, SQRT_MPA, TO_DEG

BIG_VIOLATION = 1e6  # normalised violation standing for a non-finite measure
CONSTRAINTS = ("valid", "contact_stress", "lift", "distortion", "monotonic")

REPAIR_DEFAULTS = {  # trigger probability (first iteration, last iteration), Sec 3.3.4
    "range": (1.0, 1.0),
    "adjacent": (1.0, 0.1),
    "smoothing": (0.2, 0.0),
    "lift": (1.0, 0.3),
}


def _interp_rows(x: Floats, y: Floats, level: float) -> Floats:
    """Per row, the x where the increasing y first reaches ``level`` (linear; NaN if never)."""
    above = y >= level
    k = np.argmax(above, axis=1)
    rows = np.arange(len(y))
    k0 = np.maximum(k - 1, 0)
    y0, y1 = y[rows, k0], y[rows, k]
    x0, x1 = x[rows, k0], x[rows, k]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(y1 > y0, (level - y0) / (y1 - y0), 0.0)
    out = x0 + frac * (x1 - x0)
    return np.where(above.any(axis=1), out, np.nan)


def knot_warp(x: Floats, density: tuple[float, float, float] | None
              ) -> tuple[Floats, Floats, Floats]:
    """Profile-angle fraction w(x) of spline parameter fraction x, with w' and w''.

    Uniform (w = x) reproduces Eq 25; otherwise the key points' density is
    1 + (peak - 1) exp(-((x - centre)/width)^2), integrated in closed form (erf).
    """
    x = np.asarray(x, dtype=float)
    if density is None:
        return x, np.ones_like(x), np.zeros_like(x)
    from scipy.special import erf  # scipy.special: 0.2 s, not for validate or show

    c, peak, s = density
    k = (peak - 1.0)
    total = 1.0 + k * s * np.sqrt(np.pi) / 2 * (erf((1 - c) / s) + erf(c / s))
    g = np.exp(-(((x - c) / s) ** 2))
    w = (x + k * s * np.sqrt(np.pi) / 2 * (erf((x - c) / s) + erf(c / s))) / total
    return w, (1 + k * g) / total, k * g * (-2 * (x - c) / s**2) / total


@dataclass(frozen=True)
class CamProfile:
    """Every quantity of Sec 2.3 along the working profile, (P, K) arrays in SI (angles in
    rad), plus the boundary values per particle (P,): polar radius ``r`` and dr/dtheta,
    profile angle ``theta``, normal arm ``l`` (Eq 8), |OA| ``oa`` (Eq 9), lift ``s``
    (Eq 11), pressure angle ``alpha`` (Eq 13), cam rotation from the first contact
    ``rotation`` (Eq 17), clamping force (Eq 18), drive torque (Eq 14), radius of curvature
    ``rho`` (Eq 16) and Hertz stress ``sigma`` (Eq 15); ``oa0``, ``theta0`` (Eqs 22, 24),
    the key-point angle step ``dtheta``, offset ``e``, tangent angle ``kappa`` and the key
    radii ``r_keys`` (P, N)."""

    r: Floats
    dr: Floats
    theta: Floats
    l: Floats
    oa: Floats
    s: Floats
    alpha: Floats
    rotation: Floats
    force: Floats
    torque: Floats
    rho: Floats
    sigma: Floats
    oa0: Floats
    theta0: Floats
    dtheta: Floats
    e: Floats
    kappa: Floats
    r_keys: Floats

    def row(self, i: int) -> CamProfile:
        """Particle ``i`` alone, every field indexed (1-D curves, scalars)."""
        return CamProfile(*(getattr(self, f.name)[i] for f in fields(self)))


@dataclass(frozen=True)
class CamMeasures:
    """The terms of Eq 27 and the quantities of Eq 28 per particle, (P,), SI: clearance
    angle phi_1 (rad), variance of the torque slope over the clamping section, peak torque
    (N m), curvature steps between key points (m), largest tan(alpha) before and after the
    clearance is taken up, final lift (m), largest rotation (rad), peak Hertz stress while
    clamping (Pa), largest radius of curvature (m), and the torque's RMS deviation from a
    straight line over the clamping section (% of the peak)."""

    clearance_angle: Floats
    slope_var: Floats
    peak_torque: Floats
    curvature_steps: Floats
    tan_clearance: Floats
    tan_clamping: Floats
    lift: Floats
    max_rotation: Floats
    sigma_max: Floats
    rho_max: Floats
    ramp_rms_pct: Floats


class EmbCamProblem(Problem, Repairable):
    """Cam profile of the EMB; minimise Eq 27 under Eq 28 with Eqs 29-30's penalty."""

    objective_name = "fitness"

    def __init__(self, config: EmbCamConfig) -> None:
        self.config = c = config
        self.rg, self.r_st = c.r_g_mm * MM, c.r_st_mm * MM
        self.x1, self.x2 = c.clearance_mm * MM, c.deformation_mm * MM
        self.s_max = self.x1 + self.x2
        self.K = c.k_kn_per_mm3 * KN / MM**3  # N/m^3
        self.n = n = c.key_points
        self.u = np.linspace(0, n - 1, (n - 1) * c.samples_per_segment + 1)
        self.knots = np.arange(0, self.u.size, c.samples_per_segment)
        self.spline = ClampedNaturalSpline(n, self.u)
        self.w, self.dw, self.ddw = knot_warp(self.u / (n - 1), c.knot_density)
        self.end_spline = ClampedNaturalSpline(n, self.u[[0, -1]])  # the lift's two samples
        self.end_dw = self.dw[[0, -1]]
        self.knot_w = knot_warp(np.arange(n) / (n - 1), c.knot_density)[0]
        self.kappa_max = float(np.arccos(self.r_st / (2 * self.rg)))  # Eq 21
        kb = c.kappa_bounds or None
        rb = c.radius_bounds_mm
        r_lo, r_hi = (rb.lower * MM, rb.upper * MM) if rb else (self.r_st, 2 * self.rg)
        self.variables = tuple(
            [Variable(f"r{j}_mm", r_lo, r_hi, 1 / MM) for j in range(1, n)]
            + [Variable("kappa_rad", kb.lower if kb else 0.0, kb.upper if kb else self.kappa_max),
               Variable("e_mm", c.offset_bounds_mm.lower * MM, c.offset_bounds_mm.upper * MM,
                        1 / MM)])
        self.phi_cap = (2 * np.pi * self.s_max / (c.screw_lead_mm * MM)
                        if c.screw_lead_mm else None)  # Eq 45 solved for phi_max
        names = list(CONSTRAINTS)
        if self.phi_cap is not None:
            names.append("rotation")
        if c.clearance_angle_max_rad is not None:
            names.append("clearance_angle")
        if c.torque_ramp_rms_max_pct is not None:
            names.append("torque_ramp")
        self.constraint_names = tuple(names)

    # ---- geometry --------------------------------------------------------------------
    def unpack(self, X: Floats) -> tuple[Floats, Floats, Floats]:
        """Key radii with r0 = r_st first (P, N), kappa (P,) and e (P,) of particles X (Eq 26)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        r = np.column_stack([np.full(len(X), self.r_st), X[:, : self.n - 1]])
        return r, X[:, self.n - 1], X[:, self.n]

    def boundary(self, r: Floats, kappa: Floats, e: Floats
                 ) -> tuple[Floats, Floats, Floats]:
        """|OA| at the start, theta0 and the total profile angle theta_a (Eqs 22-24)."""
        oa0 = pc.start_distance(self.r_st, self.rg, kappa)  # Eq 22
        theta_a = pc.total_profile_angle(oa0, self.r_st, r[:, -1], self.rg)  # Eq 23
        theta0 = pc.initial_profile_angle(oa0, self.r_st, e, self.rg)  # Eq 24
        return oa0, theta0, theta_a

    def knot_steps(self, theta_a: Floats) -> Floats:
        """Profile-angle steps between adjacent key points, (P, N - 1) (Eq 25)."""
        return theta_a[:, None] * np.diff(self.knot_w)[None, :]

    def _polar(self, X: Floats, spline: ClampedNaturalSpline, dw: Floats
               ) -> tuple[Floats, Floats, Floats, Floats, Floats, Floats, Floats, Floats,
                          tuple[Floats, Floats, Floats]]:
        """Key radii, kappa, e, Eqs 22-24's boundary and the spline S, dS/du, d2S/du2 with
        d theta / du at ``spline``'s samples (``dw`` the warp's slope there), (P, K)."""
        r_keys, kappa, e = self.unpack(X)
        oa0, theta0, theta_a = self.boundary(r_keys, kappa, e)
        span = theta_a[:, None] / (self.n - 1)
        th_u = span * dw[None, :]  # d theta / du along the samples
        slope0 = self.r_st * np.tan(kappa) * th_u[:, 0]  # Eq 20 in per-u units
        return r_keys, kappa, e, oa0, theta0, theta_a, span, th_u, spline(r_keys, slope0)

    def _height(self, r: Floats, dr: Floats, e: Floats) -> tuple[Floats, Floats, Floats]:
        """Normal arm (Eq 8), |OA| (Eq 9) and follower height (Eq 10), (P, K)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            l = pc.normal_arm(r, dr)  # Eq 8
            oa = pc.center_distance(r, l, self.rg)  # Eq 9
            return l, oa, pc.follower_height(oa, e[:, None])  # Eq 10

    def lift(self, X: Floats) -> Floats:
        """Final lift s at the last sample (Eq 11), (P,), m: the profile at its two end
        samples only (the lift reads nothing between them), the same numbers as
        ``profile(X).s[:, -1]`` at 2 of its samples' cost."""
        _, _, e, _, _, _, _, th_u, (S, dS, _) = self._polar(X, self.end_spline, self.end_dw)
        with np.errstate(invalid="ignore", divide="ignore"):
            h = self._height(S, dS / th_u, e)[2]
        return h[:, 0] - h[:, -1]

    def profile(self, X: Floats) -> CamProfile:
        """Every quantity of Sec 2.3 along the working profile, (P, K) arrays (SI)."""
        r_keys, kappa, e, oa0, theta0, theta_a, span, th_u, (S, dS, ddS) = self._polar(
            X, self.spline, self.dw)
        th_uu = span / (self.n - 1) * self.ddw[None, :]
        r, dr = S, dS / th_u
        ddr = (ddS - dS * th_uu / th_u) / (th_u * th_u)
        theta = theta0[:, None] + theta_a[:, None] * self.w[None, :]
        dtheta = theta_a / (self.n - 1)
        e_col = e[:, None]
        l, oa, h = self._height(r, dr, e)
        with np.errstate(invalid="ignore", divide="ignore"):
            s = h[:, :1] - h  # Eq 11
            alpha = pc.pressure_angle(oa, e_col, l, r, self.rg)  # Eq 13
            phi = pc.rotation_angle(theta, l, r, alpha)  # Eq 17
            rotation = np.abs(phi - phi[:, :1])
            force = self.K * np.clip(s - self.x1, 0, None) ** 3  # Eq 18
            f_b = force / np.cos(alpha)  # Eq 12
            torque = f_b * l  # Eq 14
            rho = pc.curvature_radius(r, dr, ddr)  # Eq 16
            sigma = pc.contact_stress(f_b, rho, self.rg, self.config.contact_length_mm * MM,
                                      self.config.z_e_sqrt_mpa * SQRT_MPA)  # Eq 15
        return CamProfile(r, dr, theta, l, oa, s, alpha, rotation, force, torque, rho, sigma,
                          oa0, theta0, dtheta, e, kappa, r_keys)

    # ---- measures --------------------------------------------------------------------
    def measures(self, p: CamProfile) -> CamMeasures:
        """The terms of Eq 27 and the quantities of Eq 28, per particle."""
        s, rot, T = p.s, p.rotation, p.torque
        clamping = s > self.x1
        with np.errstate(invalid="ignore", divide="ignore"):
            clearance_angle = _interp_rows(rot, s, self.x1)  # phi_1 = phi at s = x1
            dT = np.diff(T, axis=1) / np.diff(rot, axis=1)
            m = clamping[:, 1:] & np.isfinite(dT)
            count = np.maximum(m.sum(axis=1), 1)
            mean = np.where(m, dT, 0).sum(axis=1) / count
            slope_var = np.where(m, (dT - mean[:, None]) ** 2, 0).sum(axis=1) / count
            rho_keys = p.rho[:, self.knots]
            tan_a = np.tan(np.abs(p.alpha))
            ramp = self._ramp_rms(rot, T, clamping)
        peak = np.max(np.where(np.isfinite(T), T, np.inf), axis=1)
        return CamMeasures(
            clearance_angle=clearance_angle, slope_var=slope_var, peak_torque=peak,
            curvature_steps=np.abs(np.diff(rho_keys, axis=1)).sum(axis=1),
            tan_clearance=np.max(np.where(~clamping, tan_a, 0), axis=1),
            tan_clamping=np.max(np.where(clamping, tan_a, 0), axis=1),
            lift=s[:, -1], max_rotation=rot[:, -1],
            sigma_max=np.max(np.where(clamping, p.sigma, 0), axis=1),
            rho_max=np.max(p.rho, axis=1),
            ramp_rms_pct=ramp,
        )

    @staticmethod
    def _ramp_rms(rot: Floats, T: Floats, mask: Bools) -> Floats:
        """RMS deviation of T(phi) from its least-squares line over the clamping section,
        in % of the peak torque (per particle, vectorised)."""
        w = mask.astype(float)
        n = np.maximum(w.sum(axis=1), 2)
        x = np.where(mask, rot, 0.0)
        y = np.where(mask, T, 0.0)
        mx, my = x.sum(axis=1) / n, y.sum(axis=1) / n
        dx, dy = (rot - mx[:, None]) * w, (T - my[:, None]) * w
        slope = (dx * dy).sum(axis=1) / np.maximum((dx * dx).sum(axis=1), 1e-30)
        resid = (dy - slope[:, None] * dx) * w
        peak = np.max(np.where(mask, T, 0), axis=1)
        return 100 * np.sqrt((resid**2).sum(axis=1) / n) / np.where(peak > 0, peak, np.inf)

    def evaluate(self, X: Floats) -> Evaluation:
        """Fitness of Eq 29 (Eq 27 plus the penalties of Eq 30), the constraints of Eq 28 and
        the options (rotation cap, clearance angle, torque ramp), normalised; peak torque,
        clearance angle, rotation, lift and ramp deviation as extras."""
        c = self.config
        p = self.profile(X)
        m = self.measures(p)
        w = c.weights
        f = (w[0] * m.clearance_angle + w[1] * m.slope_var + w[2] * m.peak_torque
             + w[3] * m.curvature_steps / MM + w[4] * m.tan_clearance
             + w[5] * m.tan_clamping)  # Eq 27
        finite = np.isfinite(p.s).all(axis=1) & np.isfinite(p.rotation).all(axis=1)
        g = {
            "valid": np.where(finite & np.isfinite(f), -1.0, 1.0),  # never "active"
            "contact_stress": m.sigma_max / (c.allowable_stress_mpa * MPA) - 1,
            "lift": np.abs(m.lift - self.s_max) / (c.lift_tolerance_mm * MM) - 1,
            "distortion": m.rho_max / self.rg - 1,
            "monotonic": np.max(-np.diff(p.s, axis=1), axis=1) / MM,
        }
        if self.phi_cap is not None:
            g["rotation"] = m.max_rotation / self.phi_cap - 1
        if c.clearance_angle_max_rad is not None:
            g["clearance_angle"] = m.clearance_angle / c.clearance_angle_max_rad - 1
        if c.torque_ramp_rms_max_pct is not None:
            g["torque_ramp"] = m.ramp_rms_pct / c.torque_ramp_rms_max_pct - 1
        G = np.column_stack([g[k] for k in self.constraint_names])
        # a non-finite measure (e.g. stress at a cusp, rho = 0) counts as a large finite
        # violation, so the other constraints still rank such designs (Deb)
        G = np.where(np.isfinite(G), G, BIG_VIOLATION)
        err = np.clip(G, 0, None)
        penalty = np.where(err.sum(axis=1) > 0, c.penalty_p1, 0.0) + c.penalty_p2 * np.where(
            np.isfinite(err), err, 1e6).sum(axis=1)  # Eq 30
        fitness = np.where(np.isfinite(f), f, 1e6) + penalty  # Eq 29
        extras = {"peak_torque_nm": m.peak_torque, "clearance_angle_rad":
                  m.clearance_angle, "max_rotation_rad": m.max_rotation,
                  "lift_mm": m.lift / MM, "torque_ramp_rms_pct": m.ramp_rms_pct}
        return Evaluation(f=fitness, g=G, extras=extras)

    # ---- corrections (Sec 3.3.4, Appendix A.3) ------------------------------------------
    def repair_schedule(self) -> Mapping[str, tuple[float, float]]:
        """Trigger probability of each correction at the first and last iteration."""
        return REPAIR_DEFAULTS

    def repair(self, X: Floats, rng: np.random.Generator, probability: Mapping[str, float]
               ) -> Floats:
        """The paper's three corrections, each applied to a particle with the given
        probability: parameter ranges, adjacent key points (Eqs 31-36), lift stretch (Eq 37)."""
        X = np.array(X, dtype=float)
        P, n = len(X), self.n
        hit = {k: rng.random(P) < probability.get(k, 0.0) for k in REPAIR_DEFAULTS}
        # (1) ranges: 0 <= kappa <= kappa_max (Eq 21), 0 < e < rg, r_st < r_j < rg + e
        kap, e = X[:, n - 1], X[:, n]
        bad = hit["range"] & ((kap < 0) | (kap > self.kappa_max))
        X[bad, n - 1] = rng.uniform(0, self.kappa_max, bad.sum())
        bad = hit["range"] & ((e <= 0) | (e >= self.rg))
        X[bad, n] = rng.uniform(0, self.rg, bad.sum())
        r_hi = self.rg + X[:, n]
        R = X[:, : n - 1]
        bad = hit["range"][:, None] & ((R <= self.r_st) | (R >= r_hi[:, None]))
        R[bad] = (self.r_st + rng.random(bad.sum())
                  * (np.broadcast_to(r_hi[:, None], R.shape)[bad] - self.r_st))
        # (2) adjacent key points: increasing radii below the curvature cap (Eqs 31-35)
        rows = np.flatnonzero(hit["adjacent"])
        if rows.size:
            X[rows] = self._adjacent(X[rows], rng)
        # (2') rate of change of the radii (Eq 36)
        rows = np.flatnonzero(hit["smoothing"])
        if rows.size:
            r = np.column_stack([np.full(rows.size, self.r_st), X[rows, : n - 1]])
            r[:, 1:-1] = 0.5 * (r[:, 1:-1] + 0.5 * (r[:, :-2] + r[:, 2:]))
            X[rows, : n - 1] = r[:, 1:]
        # (3) global stretch toward the design lift (Eq 37)
        rows = np.flatnonzero(hit["lift"])
        if rows.size:
            lift = self.lift(X[rows])
            ok = np.isfinite(lift) & (lift > 0)
            rr = rows[ok]
            X[rr, : n - 1] = (X[rr, : n - 1] - self.r_st) * (self.s_max / lift[ok])[:, None] \
                + self.r_st
        return X

    def _adjacent(self, X: Floats, rng: np.random.Generator) -> Floats:
        """Reinitialise, with bias, each key radius that breaks r_{j-1} < r_j < |OB_jmax|
        and shift the following ones by the same amount (Eq 35)."""
        n = self.n
        r, kappa, e = self.unpack(X)
        oa0, _, theta_a = self.boundary(r, kappa, e)
        steps = self.knot_steps(theta_a)
        for j in range(1, n):
            cap = self._cap(r, j, oa0, steps)
            lo = r[:, j - 1]
            hi = np.minimum(np.where(np.isfinite(cap), cap, self.rg + e), self.rg + e)
            bad = (r[:, j] <= lo) | (r[:, j] >= hi)
            if not bad.any():
                continue
            new = lo + rng.uniform(0.3, 0.9, len(r)) * np.maximum(hi - lo, 0)  # biased inside
            delta = np.where(bad, new - r[:, j], 0.0)
            r[:, j:] += delta[:, None]  # Eq 35
        X = X.copy()
        X[:, : n - 1] = r[:, 1:]
        return X

    def _cap(self, r: Floats, j: int, oa0: Floats, steps: Floats) -> Floats:
        """|OB_jmax| (Eq 32 for j = 1, Appendix A.3 for j >= 2); ``steps`` (P, N-1) are
        the profile-angle steps between key points (all equal with uniform key points)."""
        rg = self.rg
        with np.errstate(invalid="ignore", divide="ignore"):
            if j == 1:
                angle = pc.angle_to_center(oa0, self.r_st, rg) - steps[:, 0]  # Eq 31
                return pc.max_radius_on_ring(oa0, angle, rg)  # Eq 32
            a, b = r[:, j - 2], r[:, j - 1]
            chord = np.sqrt(a * a + b * b - 2 * a * b * np.cos(steps[:, j - 2]))
            ob_b = np.arccos(np.clip((chord**2 + b * b - a * a) / (2 * chord * b), -1, 1))
            ab_m = np.arccos(np.clip(chord / (2 * rg), -1, 1))
            ob_a = ab_m - ob_b
            oa = np.sqrt(b * b + rg * rg - 2 * b * rg * np.cos(ob_a))
            angle = pc.angle_to_center(oa, b, rg) - steps[:, j - 1]
            return pc.max_radius_on_ring(oa, angle, rg)

    # ---- single-design output ------------------------------------------------------
    def _clamping_curves(self, x: Floats) -> tuple[CamProfile, Bools]:
        p = self.profile(x[None, :]).row(0)
        return p, p.s > self.x1

    def metrics(self, x: Floats) -> dict[str, float]:
        """Headline numbers, the ideal-screw comparison (Eqs 45-46) and the physical floor."""
        x = np.asarray(x, dtype=float)
        measured = self.measures(self.profile(x[None, :]))
        m = {f.name: float(getattr(measured, f.name)[0]) for f in fields(measured)}
        p, clamp = self._clamping_curves(x)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.gradient(p.s, p.rotation)  # ds/dphi
            ok = clamp & np.isfinite(ratio) & (p.force > 0)
            t_over_f = p.torque[ok] / p.force[ok]
            # a design that never clamps (an infeasible best of a short run) has no check
            consistency = (100 * np.max(np.abs(t_over_f - ratio[ok])) / np.max(ratio[ok])
                           if ok.any() else float("nan"))
        lead = 2 * np.pi * self.s_max / m["max_rotation"]  # Eq 45
        f_max = self.K * self.x2**3
        screw_torque = f_max * lead / (2 * np.pi)  # Eq 46
        screw_clearance = 2 * np.pi * self.x1 / lead
        work = self.K * self.x2**4 / 4  # caliper work over the clamping section
        left = m["max_rotation"] - m["clearance_angle"]
        out = {
            "peak_torque_nm": m["peak_torque"], "clearance_angle_rad": m["clearance_angle"],
            "max_rotation_rad": m["max_rotation"], "lift_mm": m["lift"] / MM,
            "contact_stress_max_mpa": m["sigma_max"] / MPA,
            "curvature_max_mm": m["rho_max"] / MM,
            "torque_ramp_rms_pct": m["ramp_rms_pct"],
            "consistency_error_pct": float(consistency),
            "screw_lead_mm": lead / MM, "screw_torque_nm": screw_torque,
            "screw_clearance_angle_rad": screw_clearance,
            "torque_ratio_to_screw": m["peak_torque"] / screw_torque,
            "clearance_ratio_to_screw": m["clearance_angle"] / screw_clearance,
            "torque_floor_flat_nm": work / left, "torque_floor_ramp_nm": 2 * work / left,
            "kappa_rad": float(p.kappa), "e_mm": float(p.e) / MM,
        }
        return out

    def analysis(self, x: Floats) -> dict[str, Floats]:
        """Profile (working and non-working segments) and the curves against rotation."""
        x = np.asarray(x, dtype=float)
        p, _ = self._clamping_curves(x)
        r, th = p.r, p.theta
        gamma = pc.angle_to_center(p.oa0, self.r_st, self.rg)
        a0 = float(p.oa0) * np.array([np.cos(p.theta0 + gamma), np.sin(p.theta0 + gamma)])
        # the non-working arc is the ring at the start: from B_end round to B_st
        b_st = self.r_st * np.array([np.cos(th[0]), np.sin(th[0])])
        b_end = r[-1] * np.array([np.cos(th[-1]), np.sin(th[-1])])
        a_st = np.arctan2(*(b_st - a0)[::-1])
        a_end = np.arctan2(*(b_end - a0)[::-1])
        sweep = np.linspace(a_end, a_st + 2 * np.pi * (a_st <= a_end), 181)
        rot = p.rotation
        lead = 2 * np.pi * self.s_max / rot[-1]
        s_screw = rot * lead / (2 * np.pi)
        screw_torque = self.K * np.clip(s_screw - self.x1, 0, None) ** 3 * lead / (2 * np.pi)
        return {
            "profile_x_mm": r * np.cos(th) / MM, "profile_y_mm": r * np.sin(th) / MM,
            "nonworking_x_mm": (a0[0] + self.rg * np.cos(sweep)) / MM,
            "nonworking_y_mm": (a0[1] + self.rg * np.sin(sweep)) / MM,
            "rotation_rad": rot, "lift_mm": p.s / MM,
            "pressure_angle_deg": p.alpha * TO_DEG, "torque_nm": p.torque,
            "clamping_force_kn": p.force / KN, "curvature_mm": p.rho / MM,
            "contact_stress_mpa": p.sigma / MPA, "profile_angle_rad": th,
            "screw_torque_nm": screw_torque,
        }
