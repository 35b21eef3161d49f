"""40 kA VCB opening spring by the energy method — Ahn, Cho, Park & Kim.

``shared/papers/001_*.txt``. The follower turns by theta about O; two symmetric
springs (stiffness k each, free length l0) join ground point A(U, V) to link
point B(s, t); three moving contacts ride on a lever d. The desired opening
motion is Eq 7; the design equations are the work-energy balance Eq 5 between
precision points; the check is the equation of motion from the same energies.

Eq 8 as printed disagrees with Eq 5 (see docs/assumptions.md); the equation of
motion here is Lagrange's equation for exactly the energies of Eq 5:

    J(th) th'' + J'(th) th'^2 / 2 = -dV/dth + Q,   J = I_o + n_c m_c (d cos th)^2,
    V = (n_s/2) k (L - l0)^2 + m_f g C_f sin(psi + th) - n_c m_c g d sin th,
    Q = -n_c F_r d cos th  (the self-closing force resists opening).

scipy.integrate is imported where used (only the exact motion of one design needs it; scipy
is slow to import).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camopt.cases.opening_spring.config import OpeningSpringConfig
from camopt.core.capabilities import HasResiduals
from camopt.core.problem import Evaluation, Problem, Variable
from camopt.mechanics import Floats
from camopt.units import DEG, MM, MS, N_PER_MM

# parameter -> (config bounds field, factor from the TOML unit to SI)
PARAMETERS = {
    "k_n_per_mm": ("k_bounds_n_per_mm", N_PER_MM),
    "l0_mm": ("l0_bounds_mm", MM),
    "u_mm": ("u_bounds_mm", MM),
    "v_mm": ("v_bounds_mm", MM),
    "s_mm": ("s_bounds_mm", MM),
    "inertia_kg_m2": ("inertia_bounds_kg_m2", 1.0),
    "self_closing_force_n": ("self_closing_bounds_n", 1.0),
}


@dataclass(frozen=True)
class Motion:
    """A simulated opening: time (s), angle, rate, and the travel event times."""

    t: Floats
    theta: Floats
    rate: Floats
    time_9mm: float
    time_10mm: float


class OpeningSpringProblem(Problem, HasResiduals):
    """Spring design (or lumped-parameter identification) for a specified opening motion."""

    def __init__(self, config: OpeningSpringConfig) -> None:
        self.config = c = config
        self.c3 = np.asarray(c.desired_coefficients, dtype=float)
        self.t0, self.ts = c.t0_ms * MS, c.ts_ms * MS
        self.theta0, self.rate0 = self.desired(self.t0)
        theta_s = self.desired(self.ts)[0]
        # Eq 6: the contacts travel the gap D between t0 and ts; travel = d (sin th - sin th0)
        self.d = (c.lever_arm_mm * MM if c.lever_arm_mm is not None
                  else c.gap_mm * MM / (np.sin(theta_s) - np.sin(self.theta0)))
        self.points_t = np.asarray(c.precision_points_ms, dtype=float) * MS
        self.points_theta, self.points_rate = self.desired(self.points_t)
        self.variables = tuple(
            Variable(name, getattr(c, PARAMETERS[name][0]).lower * PARAMETERS[name][1],
                     getattr(c, PARAMETERS[name][0]).upper * PARAMETERS[name][1],
                     1 / PARAMETERS[name][1]) for name in c.free)
        self.constraint_names = ("tension", "reachable")
        self.objective_name = ("velocity_error_sq" if c.mode == "design"
                               else "energy_misfit_sq")
        self.energy_scale = 0.5 * c.inertia_kg_m2 * self.rate0**2
        self._precompute()

    def _precompute(self) -> None:
        """What :meth:`evaluate` needs that no design changes, computed once: the angles it
        visits (theta0, the precision points, a 25-point stroke for the tension check) with
        their cosines and sines, the gravity potential and the contacts' share of the
        inertia there, the shape of the self-closing work, and the fixed parameters."""
        c = self.config
        stroke = np.linspace(self.theta0, self.points_theta.max(), 25)
        self._theta = np.concatenate([[self.theta0], self.points_theta, stroke])
        self._n_points = len(self.points_theta)
        self._cos, self._sin = np.cos(self._theta), np.sin(self._theta)
        self._gravity = (c.follower_mass_kg * c.gravity * c.follower_centroid_mm * MM
                         * np.sin(c.follower_centroid_deg * DEG + self._theta)
                         - c.contact_count * c.contact_mass_kg * c.gravity * self.d * self._sin)
        self._contact_inertia = c.contact_count * c.contact_mass_kg * (self.d * self._cos) ** 2
        self._closing_shape = -c.contact_count * self.d * (self._sin - np.sin(self.theta0))
        self._fixed = {name: getattr(c, name) * f for name, (_, f) in PARAMETERS.items()}
        self._fixed["t_mm"] = c.t_mm * MM
        self._free = {name: i for i, name in enumerate(c.free)}
        self._reference = self.x_of(c.original) if c.regularization > 0 else None

    # ---- desired motion ---------------------------------------------------------------
    def desired(self, t: Floats | float) -> tuple[Floats, Floats]:
        """theta and theta' of Eq 7."""
        c0, c1, c2, c3 = self.c3
        t = np.asarray(t, dtype=float)
        return c0 + t * (c1 + t * (c2 + t * c3)), c1 + t * (2 * c2 + 3 * c3 * t)

    # ---- parameters -------------------------------------------------------------------
    def params(self, X: Floats) -> dict[str, Floats]:
        """Every parameter in SI as (n, 1) columns: the free ones from X, the rest fixed."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        c = self.config
        out = {name: np.full((len(X), 1), getattr(c, name) * f)
               for name, (_, f) in PARAMETERS.items()}
        for i, name in enumerate(c.free):
            out[name] = X[:, i : i + 1]
        out["t_mm"] = np.full((len(X), 1), c.t_mm * MM)
        return out

    def initial_x(self) -> Floats:
        """The config's values of the free parameters (SI)."""
        return np.array([getattr(self.config, n) * PARAMETERS[n][1] for n in self.config.free])

    def x_of(self, values: dict[str, float]) -> Floats:
        """SI design of the free parameters from a {name: TOML-unit value} dict; parameters
        not given take the config's values."""
        return np.array([values.get(n, getattr(self.config, n)) * PARAMETERS[n][1]
                         for n in self.config.free])

    # ---- energies (Eq 5) -------------------------------------------------------------
    def spring_length(self, p: dict[str, Floats], theta: Floats) -> tuple[Floats, Floats]:
        """l' and dl'/dtheta of one spring (Eq 5)."""
        s, t = p["s_mm"], p["t_mm"]
        x = s * np.cos(theta) - t * np.sin(theta)
        y = s * np.sin(theta) + t * np.cos(theta)
        dx_, dy_ = p["u_mm"] - x, p["v_mm"] - y
        length = np.sqrt(dx_ * dx_ + dy_ * dy_)
        return length, (dx_ * y - dy_ * x) / length

    def inertia(self, p: dict[str, Floats], theta: Floats) -> Floats:
        """Generalised inertia J(theta) = I_o + n_c m_c (d cos theta)^2 (kg m^2, Eq 5)."""
        c = self.config
        return p["inertia_kg_m2"] + c.contact_count * c.contact_mass_kg * (
            self.d * np.cos(theta)) ** 2

    def potential(self, p: dict[str, Floats], theta: Floats) -> Floats:
        """V_e + V_g (Eq 5), with the contacts falling as the breaker opens (Eq 8's sign)."""
        c = self.config
        length, _ = self.spring_length(p, theta)
        elastic = 0.5 * c.spring_count * p["k_n_per_mm"] * (length - p["l0_mm"]) ** 2
        gravity = (c.follower_mass_kg * c.gravity * c.follower_centroid_mm * MM
                   * np.sin(c.follower_centroid_deg * DEG + theta)
                   - c.contact_count * c.contact_mass_kg * c.gravity * self.d * np.sin(theta))
        return elastic + gravity

    def work_nc(self, p: dict[str, Floats], theta: Floats) -> Floats:
        """Work of the self-closing forces from theta0 (Eq 5 with Eq 8's sign)."""
        c = self.config
        return -c.contact_count * p["self_closing_force_n"] * self.d * (
            np.sin(theta) - np.sin(self.theta0))

    def energy_balance(self, p: dict[str, Floats], theta: Floats, rate: Floats) -> Floats:
        """Left side of Eq 5 at (theta, rate) against the initial point; zero when satisfied."""
        kinetic = 0.5 * self.inertia(p, theta) * rate**2
        kinetic0 = 0.5 * self.inertia(p, self.theta0) * self.rate0**2
        return (self.potential(p, self.theta0) - self.potential(p, theta)
                + self.work_nc(p, theta) - (kinetic - kinetic0))  # Eq 5

    def rate_from_energy(self, p: dict[str, Floats], theta: Floats) -> Floats:
        """theta' at theta that Eq 5 gives; negative when the energy cannot reach theta."""
        kinetic0 = 0.5 * self.inertia(p, self.theta0) * self.rate0**2
        kinetic = (kinetic0 + self.potential(p, self.theta0) - self.potential(p, theta)
                   + self.work_nc(p, theta))
        sq = 2 * kinetic / self.inertia(p, theta)
        return np.sign(sq) * np.sqrt(np.abs(sq))

    # ---- Problem interface ----------------------------------------------------------
    def residuals(self, X: Floats) -> Floats:
        """Eq 5 at precision points 1..P-1, divided by the initial kinetic energy (n, P-1)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        available, inertia, _ = self._energies(X)
        return self._residuals(available, inertia)

    def _residuals(self, available: Floats, inertia: Floats) -> Floats:
        k = 1 + self._n_points
        return ((available - 0.5 * inertia[:, 1:k] * self.points_rate**2)[:, 1:]
                / self.energy_scale)

    def _energies(self, X: Floats) -> tuple[Floats, Floats, Floats]:
        """The lean path of :meth:`energy_balance` (the local solvers call it once per
        design, tens of thousands of times): one spring geometry over every angle visited,
        constants from :meth:`_precompute`. Returns the kinetic energy Eq 5 makes
        available at each precision point (n, P), the generalised inertia at every angle
        visited and the spring length there (n or 1, angles)."""
        c = self.config
        s, t = self._value(X, "s_mm"), self._value(X, "t_mm")
        dx_ = self._value(X, "u_mm") - (s * self._cos - t * self._sin)
        dy_ = self._value(X, "v_mm") - (s * self._sin + t * self._cos)
        length = np.atleast_2d(np.sqrt(dx_ * dx_ + dy_ * dy_))
        stretch = length - self._value(X, "l0_mm")
        potential = (0.5 * c.spring_count) * self._value(X, "k_n_per_mm") * stretch * stretch
        potential += self._gravity
        inertia = self._value(X, "inertia_kg_m2") + self._contact_inertia[None, :]
        k = 1 + self._n_points
        kinetic0 = 0.5 * inertia[:, :1] * self.rate0**2
        available = (kinetic0 + potential[:, :1] - potential[:, 1:k]
                     + self._value(X, "self_closing_force_n") * self._closing_shape[1:k])
        return available, inertia, length

    def _value(self, X: Floats, name: str) -> Floats | float:
        """A parameter in SI: an (n, 1) column of X if free, else the config's scalar."""
        i = self._free.get(name)
        return self._fixed[name] if i is None else X[:, i : i + 1]

    def evaluate(self, X: Floats) -> Evaluation:
        """Design mode: squared velocity error at the precision points (Eq 4, (rad/s)^2,
        plus the optional regularisation); identify mode: squared energy residuals (Eq 5).
        Constraints: the springs stay extended and the energy reaches every point.

        The lean path (:meth:`_energies`) of :meth:`energy_balance` and
        :meth:`rate_from_energy`."""
        c = self.config
        X = np.atleast_2d(np.asarray(X, dtype=float))
        available, inertia, length = self._energies(X)
        k = 1 + self._n_points
        l0 = self._value(X, "l0_mm")
        sq = 2 * available / inertia[:, 1:k]
        # the energy cannot reach that point: a negative rate (one copysign, not a masked
        # multiply: this runs once per Nelder-Mead evaluation)
        rate = np.copysign(np.sqrt(np.abs(sq)), sq)
        if c.mode == "design":
            err = self.points_rate - rate
            f = (err * err).sum(axis=1)  # Eq 4
            if self._reference is not None:
                rel = (X - self._reference) / self._reference
                f = f + c.regularization * (rel * rel).sum(axis=1)
        else:
            residual = self._residuals(available, inertia)
            f = (residual * residual).sum(axis=1)
        g = np.empty((len(X), 2))
        g[:, 0] = 1.0 - length[:, k:].min(axis=1) / np.ravel(l0)  # stays extended
        g[:, 1] = rate.min(axis=1) / -self.rate0  # the energy reaches every point
        return Evaluation(f=np.where(np.isfinite(f), f, np.inf), g=g)

    def residual_max(self, X: Floats) -> Floats:
        """Largest |Eq 5 residual| over the precision points per design (n,), relative to
        the initial kinetic energy (0 with a single point)."""
        if self._n_points < 2:
            return np.zeros(len(np.atleast_2d(X)))
        return np.abs(self.residuals(X)).max(axis=1)

    # ---- simulation -----------------------------------------------------------------
    def simulate(self, x: Floats, t_max: float = 0.05) -> Motion:
        """Integrate the equation of motion from (theta0, theta0') at t0 with solve_ivp until
        the contacts have travelled the gap (event), recording 9 mm and 10 mm."""
        c = self.config
        p = {k: v[0, 0] for k, v in self.params(x[None, :]).items()}
        n_c, m_c, d = c.contact_count, c.contact_mass_kg, self.d
        psi = c.follower_centroid_deg * DEG

        def rhs(_t: float, y: Floats) -> list[float]:
            th, w = y
            length, dlen = self.spring_length(p, th)
            dV = (c.spring_count * p["k_n_per_mm"] * (length - p["l0_mm"]) * dlen
                  + c.follower_mass_kg * c.gravity * c.follower_centroid_mm * MM
                  * np.cos(psi + th) - n_c * m_c * c.gravity * d * np.cos(th))
            q = -n_c * p["self_closing_force_n"] * d * np.cos(th)
            J = p["inertia_kg_m2"] + n_c * m_c * (d * np.cos(th)) ** 2
            dJ = -2 * n_c * m_c * d * d * np.cos(th) * np.sin(th)
            return [w, (-dV + q - 0.5 * dJ * w * w) / J]

        def travel(mm: float):
            def event(_t: float, y: Floats) -> float:
                return d * (np.sin(y[0]) - np.sin(self.theta0)) - mm * MM
            event.direction = 1  # type: ignore[attr-defined]
            return event

        from scipy.integrate import solve_ivp  # not at import: validate never integrates

        stop = travel(c.gap_mm)
        stop.terminal = True
        sol = solve_ivp(rhs, (self.t0, self.t0 + t_max), [self.theta0, self.rate0],
                        method="DOP853", events=[travel(0.9 * c.gap_mm), stop],
                        rtol=1e-10, atol=1e-12, max_step=2e-4)
        times = [float(e[0] - self.t0) if e.size else np.nan for e in sol.t_events]
        return Motion(sol.t, sol.y[0], sol.y[1], times[0], times[1])

    def tracking(self, x: Floats) -> dict[str, float]:
        """Velocity error of the motion against Eq 7 over the desired angles, one design
        (:meth:`tracking_rows`)."""
        rows = self.tracking_rows(np.asarray(x, dtype=float)[None, :])
        return {key: float(v[0]) for key, v in rows.items()}

    def tracking_rows(self, X: Floats) -> dict[str, Floats]:
        """Velocity error against Eq 7 over 400 desired angles and the travel times to 9
        and 10 mm of n designs at once (n,), by the work-energy equation of the equation
        of motion (module docstring): every force is a function of theta, so theta'(theta)
        is exact (:meth:`rate_from_energy`) and t(theta) = integral of dtheta / theta'
        (Gauss-Legendre, 16 panels of 16 nodes). A design whose energy runs out before an
        angle never gets there: its rate there counts 0 and its travel times are NaN. What
        ``simulate`` (solve_ivp, one design) gives, to 1e-7 (tests/cases/
        test_opening_spring.py), without an ODE per design."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        p = self.params(X)
        t = np.linspace(self.t0, self.ts, 400)
        th_d, rate_d = self.desired(t)
        rate = self.rate_from_energy(p, th_d[None, :])
        # the angle reached: the motion stops at the first angle its energy cannot reach
        stuck = np.cumsum(~(rate > 0), axis=1) > 0
        err = np.where(stuck, 0.0, rate) - rate_d
        gap = self.config.gap_mm * MM
        times = [self._travel_time(p, float(np.arcsin(np.sin(self.theta0) + share * gap
                                                       / self.d)))
                 for share in (0.9, 1.0)]
        with np.errstate(divide="ignore", invalid="ignore"):
            velocity = 0.9 * gap / times[0]
        return {
            "rms_velocity_error_rad_s": np.sqrt(np.mean(err**2, axis=1)),
            "max_velocity_error_rad_s": np.max(np.abs(err), axis=1),
            "travel_time_9mm_ms": times[0] / MS,
            "travel_time_10mm_ms": times[1] / MS,
            "avg_opening_velocity_m_s": velocity,
        }

    def _travel_time(self, p: dict[str, Floats], theta: float, panels: int = 16,
                     nodes: int = 16) -> Floats:
        """Time from theta0 to ``theta`` (s, (n,)), NaN where the energy stops short."""
        x, w = np.polynomial.legendre.leggauss(nodes)
        edges = np.linspace(self.theta0, theta, panels + 1)
        half = 0.5 * np.diff(edges)
        angles = (0.5 * (edges[:-1] + edges[1:])[:, None] + half[:, None] * x).ravel()
        rate = self.rate_from_energy(p, angles[None, :])
        with np.errstate(divide="ignore"):
            time = (np.repeat(half, nodes) * np.tile(w, panels) / rate).sum(axis=1)
        # a rate that reaches zero anywhere on the way (sampled, and at the end) stops it
        end = self.rate_from_energy(p, np.array([[theta]]))[:, 0]
        return np.where(np.all(rate > 0, axis=1) & (end > 0), time, np.nan)

    def design_values(self, x: Floats) -> dict[str, float]:
        """All spring and lumped parameters of a design, in TOML units."""
        p = self.params(x[None, :])
        return {name: float(p[name][0, 0] / PARAMETERS[name][1]) for name in PARAMETERS}

    def others(self) -> dict[str, tuple[OpeningSpringProblem, Floats]]:
        """The original design and the config's compare_designs, each as (problem, x)."""
        c = self.config
        if c.mode != "design":
            return {}
        designs = {"original": c.original, **c.compare_designs}
        out = {}
        for label, values in designs.items():
            variant = OpeningSpringProblem(c.model_copy(update={"free": list(values),
                                                                "compare_designs": {}}))
            out[label] = (variant, variant.x_of(values))
        return out

    def metrics(self, x: Floats) -> dict[str, object]:
        """Tracking of the design and, prefixed by their labels, of the original and the
        config's compare_designs (e.g. Table 1's columns)."""
        x = np.asarray(x, dtype=float)
        out: dict[str, object] = {**self.design_values(x), **self.tracking(x),
                                  "energy_residual_rel": float(self.residual_max(x)[0]),
                                  "lever_arm_mm": self.d / MM}
        for label, (problem, design) in self.others().items():
            out.update({f"{label}_{k}": v for k, v in problem.tracking(design).items()})
        return out

    def describe(self, X: Floats) -> Evaluation:
        """Evaluation plus each design's tracking (:meth:`tracking_rows`, one call)."""
        ev = self.evaluate(X)
        return Evaluation(ev.f, ev.g, {"energy_residual_rel": self.residual_max(X),
                                       **self.tracking_rows(X)})

    def analysis(self, x: Floats) -> dict[str, Floats]:
        """Desired and simulated theta(t), theta'(t) for the design and the original."""
        t = np.linspace(self.t0, self.ts, 200)
        th_d, rate_d = self.desired(t)
        out = {"desired_time_ms": t / MS, "desired_theta_rad": th_d, "desired_rate_rad_s": rate_d}
        runs = {"design": (self, np.asarray(x, dtype=float)), **self.others()}
        for label, (problem, design) in runs.items():
            motion = problem.simulate(design)
            out.update({f"{label}_time_ms": motion.t / MS, f"{label}_theta_rad": motion.theta,
                        f"{label}_rate_rad_s": motion.rate})
        return out
