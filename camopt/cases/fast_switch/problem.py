"""Fast acting switch: minimum closure time of a spring-driven slider crank.

Clauss & Papalambros (1982), UM-MEAM-81-3 (``shared/papers/004_*.txt``).
The full model has 13 variables x1..x13 and constraints R1-R20 (+ R21, the
branch sf vs sud). Generic solvers search the reduced problem left after
direct elimination: coils N (for x8 through R13, integer), sf (x3), sud (x4),
s0 (x5), r3 (x6), r2 (x7); x1, x2 and x9-x13 follow from the equalities.

``reduced_form = "corrected"`` solves the loop equations R8-R11 exactly and
takes the arcsine branch that the physical motion crosses; ``"printed"`` is
the paper's 7-variable statement as printed (Eq 58 objective and bounds), kept
so users can see what its errors do. Either way every design can be checked on
the full model with :meth:`FastSwitchProblem.full_model`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

import numpy as np

from camopt.cases.fast_switch.config import FastSwitchConfig
from camopt.core.capabilities import HasFamily, VariesCase
from camopt.core.problem import FEASIBILITY_TOL, Evaluation, Problem, Variable
from camopt.errors import ConfigError
from camopt.mechanics import Floats, dynamics, springs
from camopt.mechanics.slider_crank import coupler_angle, coupler_derivatives, crank_angle_for_span
from camopt.units import DEG, GPA, MM, MPA, TO_DEG, TO_MM, TO_MS

TWO_PI = 2.0 * np.pi
EXACT_MAX_CALLS = 6000
"""Budget of the exact-dynamics ODE in right-hand-side calls (~500 DOP853 steps; a
feasible switch closes in 13-35 steps, an oscillating one never would)."""

FULL_INEQUALITIES = ("R1", "R2", "R3", "R4", "R5", "R6", "R7", "R12", "R14", "R15", "R16",
                     "R19", "R20", "R21")
EQUALITIES = ("R8", "R9", "R10", "R11", "R13", "R17", "R18")
# Implied by the equalities once they are solved: R10a (x7 <= x6, Eq 43), R9b (the
# loop closes at t = 0) and R3b (the piston moves forward, sf >= s0).
CORRECTED_CONSTRAINTS = FULL_INEQUALITIES + ("R10a", "R9b", "R3b")
PRINTED_CONSTRAINTS = ("R1", "R2", "R3", "R4", "R6", "R7", "R8a", "R9a", "R10a", "R12", "R14",
                       "R16", "R19", "R20", "R21")

DESIGN_NAMES = {  # x_i -> archive name with its display unit and factor from SI
    "x1": ("xi", 1.0), "x2": ("omega_n_rad_s", 1.0), "x3": ("sf_mm", TO_MM),
    "x4": ("sud_mm", TO_MM), "x5": ("s0_mm", TO_MM), "x6": ("r3_mm", TO_MM),
    "x7": ("r2_mm", TO_MM), "x8": ("k_n_per_m", 1.0), "x9": ("coils", 1.0),
    "x10": ("g_mm", TO_MM), "x11": ("theta3f_deg", TO_DEG), "x12": ("theta30_deg", TO_DEG),
    "x13": ("theta20_deg", TO_DEG),
}


@dataclass(frozen=True)
class SwitchDesign:
    """The 13 variables of the full model for a population, each (n,), SI (rad for angles):
    x1 damping ratio, x2 natural frequency (rad/s), x3 sf, x4 sud, x5 s0, x6 r3, x7 r2,
    x8 spring rate (N/m), x9 coils, x10 g, x11 theta3f, x12 theta30, x13 theta20; and
    ``cos20``, cos theta20 before clipping (outside [-1, 1]: the loop cannot close, R9b)."""

    x1: Floats
    x2: Floats
    x3: Floats
    x4: Floats
    x5: Floats
    x6: Floats
    x7: Floats
    x8: Floats
    x9: Floats
    x10: Floats
    x11: Floats
    x12: Floats
    x13: Floats
    cos20: Floats

    def display(self) -> dict[str, Floats]:
        """x1..x13 under their archive names in display units (``DESIGN_NAMES``)."""
        return {name: getattr(self, key) * scale for key, (name, scale) in DESIGN_NAMES.items()}

    def take(self, i: int) -> dict[str, float]:
        """One design's values as SI floats, by field name."""
        return {f.name: float(getattr(self, f.name)[i]) for f in fields(self)}


@dataclass(frozen=True)
class SwitchParameters:
    """Nomenclature parameters in SI."""

    L: float
    p4: float
    M2: float
    M3: float
    M4: float
    D: float
    d: float
    A: float
    m: float
    G: float
    W: float
    F_rated: float
    d_strength: float  # d in the unit the strength law A d^-m uses

    @classmethod
    def from_config(cls, c: FastSwitchConfig) -> SwitchParameters:
        """The Nomenclature parameters of a config, converted to SI."""
        d = c.wire_diameter_mm * MM
        return cls(
            L=c.link2_length_mm * MM, p4=c.half_piston_mm * MM, M2=c.m2_kg, M3=c.m3_kg,
            M4=c.m4_kg, D=c.spring_diameter_mm * MM, d=d, A=c.wire_strength_a_mpa * MPA,
            m=c.wire_strength_exponent, G=c.shear_modulus_gpa * GPA,
            W=c.max_initial_angle_deg * DEG, F_rated=c.max_joint_load_n,
            d_strength=d if c.wire_strength_d_unit == "m" else c.wire_diameter_mm,
        )

    def rate(self, coils: Floats) -> Floats:
        """Spring rate (N/m) of each coil count (R13, Eq 21)."""
        return np.asarray(springs.helical_rate(self.d, self.D, self.G, coils))  # R13, Eq 21

    def strength(self, k: Floats, deflection: Floats) -> Floats:
        """Shear-strength use at a deflection (m); <= 1 is safe (R14/R15, Eqs 22-23)."""
        return np.asarray(springs.strength_ratio(k, deflection, self.d, self.D, self.A, self.m,
                                                 self.d_strength))  # R14/R15, Eqs 22-23

    def effective_mass(self, r2: Floats) -> Floats:
        """Effective mass m' (kg) for crank length r2 (m) (Eq 32)."""
        return self.M4 + 0.083 * self.M2 * self.L**2 / r2**2 + 0.021 * self.M3  # Eq 32

    def velocity_coefficient(self, r2: Floats, r3: Floats) -> Floats:
        """Velocity-dependent coefficient c (kg/s) of the approximate damping (Eq 33)."""
        M2L2 = self.M2 * self.L**2
        return (0.0083 * M2L2 / r2**3 + 0.0042 * self.M3 / r3 + 0.033 * M2L2 / (r2**2 * r3)
                + 0.067 * self.M3 / r2)  # Eq 33


def closure_time(xi: Floats, omega: Floats, sf: Floats, sud: Floats, s0: Floats
                 ) -> Floats:
    """Closure time of Eq 39 on the branch the motion crosses first.

    s - sud = (s0 - sud)/sqrt(1 - xi^2) sin(wd t + phi), phi = atan(sqrt(1 - xi^2)/xi) (Eq 34):
    starting at phi < pi/2 with sin falling, s first equals sf where wd t + phi = pi - asin(v).
    The printed Eq 39 takes +asin(v), which is negative in case I (the paper's Eq 76 uses pi).
    """
    root = np.sqrt(1.0 - xi**2)
    v = (sf - sud) * root / (s0 - sud)
    phase = np.arctan(root / xi)
    return (np.pi - np.arcsin(v) - phase) / (root * omega)


SPRING_FIELDS = ("wire_diameter_mm", "spring_diameter_mm")
"""Case fields a design may take per row (tolerance analysis, robust design): the spring's
made wire and coil diameters, through which its rate (R13) and stress (R14/R15) vary."""


class FastSwitchProblem(Problem, HasFamily, VariesCase):
    """Reduced fast-switch problem over (coils, sf, sud, s0, r3, r2); minimise closure time."""

    objective_name = "closure_time_ms"

    def __init__(self, config: FastSwitchConfig) -> None:
        self.config = config
        self.p = SwitchParameters.from_config(config)
        self.variables = (
            Variable("coils", config.min_coils, config.max_coils, 1.0, True, "x9"),
            Variable("sf_mm", config.sf_bounds_mm.lower * MM, config.sf_bounds_mm.upper * MM,
                     TO_MM, symbol="x3"),
            Variable("sud_mm", config.sud_bounds_mm.lower * MM, config.sud_bounds_mm.upper * MM,
                     TO_MM, symbol="x4"),
            Variable("s0_mm", config.s0_bounds_mm.lower * MM, config.s0_bounds_mm.upper * MM,
                     TO_MM, symbol="x5"),
            Variable("r3_mm", config.r3_bounds_mm.lower * MM, config.r3_bounds_mm.upper * MM,
                     TO_MM, symbol="x6"),
            Variable("r2_mm", config.r2_bounds_mm.lower * MM, config.r2_bounds_mm.upper * MM,
                     TO_MM, symbol="x7"),
        )
        printed = config.reduced_form == "printed"
        self.constraint_names = PRINTED_CONSTRAINTS if printed else CORRECTED_CONSTRAINTS

    # ---- the 13-variable model -------------------------------------------------------
    def complete(self, X: Floats) -> SwitchDesign:
        """x1..x13 from the reduced variables (n, 6), solving R13, R17, R18, R10, R11, R8, R9
        exactly."""
        p = self.p
        N, x3, x4, x5, x6, x7 = np.asarray(X, dtype=float).T
        x8 = p.rate(N)
        x2 = np.sqrt(x8 / p.effective_mass(x7))  # R18, Eq 57
        x1 = x2 * p.velocity_coefficient(x7, x6) / (2.0 * x8)  # R17, Eq 35
        ratio = np.clip(x7 / x6, 0.0, 1.0)
        x11 = TWO_PI - np.arcsin(ratio)  # R10, Eq 42 (fourth quadrant)
        x10 = x6 * np.cos(x11) + p.p4 + x3  # R11, Eq 56
        span0 = x10 - p.p4 - x5
        cos20 = crank_angle_for_span(x7, x6, span0)  # R8 and R9 at t = 0
        x13 = np.arccos(np.clip(cos20, -1.0, 1.0))
        x12 = coupler_angle(x7, x6, x13, span0)
        return SwitchDesign(x1, x2, x3, x4, x5, x6, x7, x8, N, x10, x11, x12, x13, cos20)

    def full_model(self, x: SwitchDesign) -> tuple[dict[str, Floats], dict[str, Floats]]:
        """Inequalities R1-R21 (normalised, <= 0 feasible) and equality residuals R8-R18,
        each (n,), keyed by the paper's constraint names."""
        return self.inequalities(x), self.equalities(x)

    def inequalities(self, x: SwitchDesign) -> dict[str, Floats]:
        """The full model's inequalities R1-R21, normalised (<= 0 feasible), each (n,)."""
        p = self.p
        x1, x2, x3, x4, x5, x7 = x.x1, x.x2, x.x3, x.x4, x.x5, x.x7
        x8, x9, x10, x12, x13 = x.x8, x.x9, x.x10, x.x12, x.x13
        with np.errstate(divide="ignore", invalid="ignore"):
            damped = np.sqrt(1.0 - x1**2)
            return {
                "R1": x7 / p.L - 1.0,  # Eq 4
                "R2": 0.5 * x10 / p.L - 1.0,  # Eq 5
                "R3": x5 / x4 - 1.0,  # Eq 7
                "R4": x13 / p.W - 1.0,  # Eq 9
                "R5": x13 / (0.5 * np.pi) - 1.0,  # Eq 10
                "R6": 1.5 * np.pi / x12 - 1.0,  # Eq 11
                "R7": x12 / TWO_PI - 1.0,  # Eq 12
                "R12": np.where(2 * x4 - x5 > 0, x3 / (2 * x4 - x5), np.inf) - 1.0,  # Eq 20
                "R14": p.strength(x8, x4 - x5) - 1.0,  # Eq 22
                "R15": p.strength(x8, x3 - x4) - 1.0,  # Eq 23
                "R16": x9 * p.d / x5 - 1.0,  # Eq 24
                "R19": x1 - 1.0,  # Eq 40
                # Eq 41; M4 w^2 - k < 0 always (m' > M4), so the joint load is its magnitude.
                "R20": 1.2 * (x4 - x5) / damped * np.abs(p.M4 * x2**2 - x8) / p.F_rated - 1.0,
                "R21": self._branch(x3, x4),
            }

    def equalities(self, x: SwitchDesign) -> dict[str, Floats]:
        """The full model's equality residuals R8-R18 (zero where the loop closes), each
        (n,); ``complete`` solves them, so they are a check, not read by the search."""
        p = self.p
        x1, x2, x6, x7, x8, x9 = x.x1, x.x2, x.x6, x.x7, x.x8, x.x9
        x3, x5, x10, x11, x12, x13 = x.x3, x.x5, x.x10, x.x11, x.x12, x.x13
        with np.errstate(divide="ignore", invalid="ignore"):
            return {
                "R8": (x7 * np.sin(x13) + x6 * np.sin(x12)) / p.L,  # Eq 14
                "R9": (x7 * np.cos(x13) + x6 * np.cos(x12) + p.p4 + x5 - x10) / p.L,  # Eq 15
                "R10": (x7 + x6 * np.sin(x11)) / p.L,  # Eq 16
                "R11": (x6 * np.cos(x11) + p.p4 + x3 - x10) / p.L,  # Eq 17
                "R13": x8 / p.rate(x9) - 1.0,  # Eq 21
                "R17": x1 / (x2 * p.velocity_coefficient(x7, x6) / (2 * x8)) - 1.0,  # Eq 35
                "R18": x2 / np.sqrt(x8 / p.effective_mass(x7)) - 1.0,  # Eq 36
            }

    def _branch(self, x3: Floats, x4: Floats) -> Floats:
        """R21: case I (x4/x3 <= 1), case II (x3/x4 <= 1), or both (active iff x3 == x4)."""
        if self.config.branch == "I":
            return x4 / x3 - 1.0  # Eq 59
        if self.config.branch == "II":
            return x3 / x4 - 1.0
        return -np.abs(x3 / x4 - 1.0)

    # ---- Problem interface ---------------------------------------------------------------
    def evaluate(self, X: Floats) -> Evaluation:
        """Closure time in ms (Eq 39 on the right arcsine branch, or Eq 58 as printed), the
        reduced problem's constraints, and what a search may name as an objective: the
        closure time and the spring's stress margin (% below its strength at the worse of
        the two loads, R14 and R15). :meth:`describe` adds x1..x13 and the full model's
        largest equality residual (not computed for a search: it solves the full model
        per design, which a search does not need)."""
        return self._evaluate(X)[0]

    def describe(self, X: Floats) -> Evaluation:
        """As :meth:`evaluate`, plus x1..x13 in display units and the largest equality
        residual R8-R18 of the full model."""
        ev, x = self._evaluate(X)
        h = self.equalities(x)
        extras = {**x.display(), "closure_time_ms": ev.extras["closure_time_ms"],
                  "equality_residual_max": np.max(np.abs(np.stack(list(h.values()))), axis=0),
                  "spring_stress_margin_pct": ev.extras["spring_stress_margin_pct"]}
        return Evaluation(ev.f, ev.g, extras)

    def case_fields(self) -> tuple[str, ...]:
        """The spring's wire and coil diameters (:data:`SPRING_FIELDS`)."""
        return SPRING_FIELDS

    def describe_with(self, X: Floats, fields: Mapping[str, Floats]) -> Evaluation:
        """As :meth:`describe`, with the spring's wire and/or coil diameter (mm) per row.
        Every equation reads the Nomenclature parameters from ``self.p`` and broadcasts
        over rows, so the parameters are rebuilt with (n,) arrays for the call."""
        unknown = sorted(set(fields) - set(SPRING_FIELDS))
        if unknown:
            raise ConfigError("case", unknown[0], "cannot vary per design; fields that can: "
                              f"{', '.join(SPRING_FIELDS)}")
        rows = {k: np.asarray(v, dtype=float) for k, v in fields.items()}
        saved, self.p = self.p, SwitchParameters.from_config(self.config.model_copy(update=rows))
        try:
            return self.describe(X)
        finally:
            self.p = saved

    def _evaluate(self, X: Floats) -> tuple[Evaluation, SwitchDesign]:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        x = self.complete(X)
        full = self.inequalities(x)
        if self.config.reduced_form == "printed":
            f, g = self._printed(x)
        else:
            f, g = self._corrected(x, full)
        f = np.where(np.isfinite(f), f, np.inf) * TO_MS
        extras = {"closure_time_ms": f,
                  "spring_stress_margin_pct": -100.0 * np.maximum(full["R14"], full["R15"])}
        return Evaluation(f=f, g=g, extras=extras), x

    def _corrected(self, x: SwitchDesign, g_full: dict[str, Floats]
                   ) -> tuple[Floats, Floats]:
        with np.errstate(divide="ignore", invalid="ignore"):
            extra = {
                "R10a": x.x7 / x.x6 - 1.0,  # Eq 43
                "R9b": np.abs(x.cos20) - 1.0,
                "R3b": x.x5 / x.x3 - 1.0,
            }
            f = closure_time(x.x1, x.x2, x.x3, x.x4, x.x5)
        g = np.column_stack([{**g_full, **extra}[name] for name in self.constraint_names])
        return f, g

    def _printed(self, x: SwitchDesign) -> tuple[Floats, Floats]:
        """The 7-variable statement exactly as printed after Eq 57 (including its errors)."""
        p = self.p
        x1, x3, x4, x5, x6, x7, x8 = x.x1, x.x3, x.x4, x.x5, x.x6, x.x7, x.x8
        with np.errstate(divide="ignore", invalid="ignore"):
            b = np.sqrt(x6**2 - x7**2)
            x10 = b + p.p4 + x3  # Eq 56
            q = (x10 - p.p4 - x5) / (2 * x6)
            x12_hi = np.arcsin(-np.sqrt((x7 / x6) ** 2 - q**2))  # Eq 53 as printed
            x12_lo = np.arcsin(-np.sqrt(1 - q**2))  # Eq 54 as printed
            mprime = p.effective_mass(x7)
            root = np.sqrt(1 - x1**2)
            g = {
                "R1": x7 / p.L - 1,
                "R2": 0.5 * (b + p.p4 + x3) / p.L - 1,
                "R3": x5 / x4 - 1,
                "R4": 2 * x7 * np.cos(p.W) / (b + x3 - x5) - 1,
                "R6": 1.5 * np.pi / x12_hi - 1,
                "R7": x12_lo / TWO_PI - 1,
                "R8a": np.arccos((x10 - p.p4 - x5) / (2 * x7)) / (TWO_PI - x12_lo) - 1,
                "R9a": x10 / (x7 + x6 + p.p4 + x5) - 1,
                "R10a": x7 / x6 - 1,
                "R12": x3 / (2 * x4 - x5) - 1,
                "R14": p.strength(x8, x4 - x5) - 1,
                "R16": 0.125 * p.D**-3 / x8 / x5 * p.d**5 * p.G - 1,
                "R19": x1 - 1,
                "R20": 1.2 * (x4 - x5) / root * x8 * (p.M4 / mprime - 1) / p.F_rated - 1,
                "R21": self._branch(x3, x4),
            }
            v = (x3 - x4) * root / (x5 - x4)
            f = (np.arcsin(v) - np.arctan(root / x1)) * np.sqrt(mprime) / (root * np.sqrt(x8))
        return f, np.column_stack([g[name] for name in self.constraint_names])

    # ---- capabilities ----------------------------------------------------------------
    def family(self) -> Floats:
        """The one-degree-of-freedom family left by R2, R4, R14, R16, R21 active (Eq 86).

        One member per integer coil count; R4 active is solved exactly by the law of cosines
        with theta20 = W and g = 2L, which is what Eq 86's x7 expression is.
        """
        p = self.p
        N = np.arange(self.config.min_coils, self.config.max_coils + 1, dtype=float)
        x5 = N * p.d  # R16 active
        x8 = p.rate(N)  # R13
        x4 = x5 + springs.max_deflection(x8, p.d, p.D, p.A, p.m, p.d_strength)  # R14 active
        x3 = x4  # R21 active
        a = 2 * p.L - p.p4 - x5  # R2 active: g = 2L
        b = 2 * p.L - p.p4 - x3
        x7 = (a**2 - b**2) / (2 * a * np.cos(p.W))  # R4 active (Eq 86)
        x6 = np.sqrt(b**2 + x7**2)  # R2 with Eq 56
        return np.column_stack([N, x3, x4, x5, x6, x7])

    def metrics(self, x: Floats) -> dict[str, object]:
        """Headline metrics of one design, with the exact-dynamics closure time.

        The exact motion is integrated only for a design the reduced problem finds
        feasible with a finite Eq 39 time, and within :data:`EXACT_MAX_CALLS`: for any
        other the ODE could oscillate short of 90 deg for its whole second (minutes of
        Python calls). ``exact_dynamics`` says which: ``computed``,
        ``skipped: infeasible design`` (times NaN) or ``capped: ...`` (times NaN)."""
        ev = self.describe(np.atleast_2d(x))
        out: dict[str, object] = {k: float(v[0]) for k, v in ev.extras.items()}
        out["closure_time_exact_ms"] = out["closure_speed_rad_s"] = float("nan")
        if not (ev.feasible[0] and np.isfinite(ev.f[0])):
            out["exact_dynamics"] = "skipped: infeasible design"
        else:
            exact = self.exact_closure(x)
            out["exact_dynamics"] = ("computed" if not exact.capped else
                                     f"capped: not closed within {EXACT_MAX_CALLS} ODE calls")
            out["closure_time_exact_ms"] = exact.time * TO_MS
            out["closure_speed_rad_s"] = exact.speed
        g_full, _ = self.full_model(self.complete(np.atleast_2d(x)))
        out["full_model_feasible"] = float(all(v[0] <= FEASIBILITY_TOL for v in g_full.values()))
        out["joint_load_n"] = float((g_full["R20"][0] + 1.0) * self.p.F_rated)  # R20, Eq 41
        return out

    def exact_closure(self, x: Floats) -> dynamics.Travel:
        """Integrate the exact 1-DOF motion of Eqs 2-3 until theta2 = 90 deg.

        T = (I2 theta2'^2 + I3 theta3'^2 + M4 s'^2)/2 with I2 = M2 L^2/12, I3 = M3 r3^2/12
        (Eq 106); V = k (s - sud)^2 / 2. Link translation inertia is neglected as in the paper.
        """
        p = self.p
        v = self.complete(np.atleast_2d(x)).take(0)
        r2, r3, k, sud = v["x7"], v["x6"], v["x8"], v["x4"]
        g, theta20 = v["x10"], v["x13"]
        I2, I3 = p.M2 * p.L**2 / 12.0, p.M3 * r3**2 / 12.0

        def kinematics(q: float) -> tuple[float, float, float, float, float]:
            th3, d3, dd3, ds, dds = coupler_derivatives(r2, r3, q)
            s = g - p.p4 - r2 * np.cos(q) - r3 * np.cos(th3)
            return float(s), float(d3), float(dd3), float(ds), float(dds)

        def mass(q: float) -> float:
            _, d3, _, ds, _ = kinematics(q)
            return I2 + I3 * d3**2 + p.M4 * ds**2

        def mass_slope(q: float) -> float:
            _, d3, dd3, ds, dds = kinematics(q)
            return 2 * I3 * d3 * dd3 + 2 * p.M4 * ds * dds

        def force(q: float) -> float:
            s, _, _, ds, _ = kinematics(q)
            return -k * (s - sud) * ds

        return dynamics.time_to_reach(mass, mass_slope, force, theta20, np.pi / 2, t_max=1.0,
                                      max_calls=EXACT_MAX_CALLS)

    def analysis(self, x: Floats) -> dict[str, Floats]:
        """Curves for the archive: exact motion theta2(t), spring length s(t); none for a
        design :meth:`metrics` does not integrate (infeasible, or the ODE capped)."""
        ev = self.evaluate(np.atleast_2d(x))
        if not (ev.feasible[0] and np.isfinite(ev.f[0])):
            return {}
        travel = self.exact_closure(x)
        if travel.capped:
            return {}
        v = self.complete(np.atleast_2d(x)).take(0)
        r2, r3, g = v["x7"], v["x6"], v["x10"]
        th3 = coupler_derivatives(r2, r3, travel.q)[0]
        s = g - self.p.p4 - r2 * np.cos(travel.q) - r3 * np.cos(th3)
        return {"time_ms": travel.t * TO_MS, "theta2_deg": travel.q * TO_DEG,
                "theta2_rate_rad_s": travel.qdot, "spring_length_mm": s * TO_MM}
