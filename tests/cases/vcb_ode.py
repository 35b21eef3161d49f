"""An independent simulation of a VCB closing for the calibration tests: Lagrange's equation
integrated in time by scipy (solve_ivp, DOP853), phase by phase, with the plastic impacts
between them, from the model's kinematics and loads at single angles only (nothing of
camopt's work-energy quadrature or its time grid).

    J(theta) theta'' + J'(theta) theta'^2 / 2 = eps T(theta) - T_f - Fr(s1) ds1/dtheta

free rotation (J = J_cam) from the release to the roller, the cam meeting the roller at
rest (J_cam omega- = J(0) omega+), the contacts' touch at s1 = gap (their kinetic energy
lost, omega continuous), the latch at the cam's last angle (held at rest after it).

``python -m tests.cases.vcb_ode`` writes the synthetic "vendor" curves of
``tests/data/curves/`` (10 kHz, 0.02 mm noise, a 3.4 ms latch delay): synthetic, made by
this file, not measured."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from camopt.cases.vcb.model import VcbModel
from camopt.cases.vcb.problem import VcbProblem
from camopt.units import DEG, N_PER_MM, TO_MM, TO_MS

CURVES = Path(__file__).resolve().parents[1] / "data" / "curves"


@dataclass(frozen=True)
class Truth:
    """The parameters the synthetic curves are made with (SI but the offset, deg)."""

    cam_kg_m2: float = 6.3e-4
    rod_kg: float = 3.2
    contacts_kg: float = 1.8
    release_offset_deg: float = 12.5
    friction_nm: float = 8.0
    follower_kg_m2: float = 0.0


TRUTH = Truth()
SPRING_SETS = {"vendor": (7.72, 9.33), "stiff": (9.6, 9.9)}  # kc1, kc2 N/mm
LATCH_DELAY_S = 3.4e-3
NOISE_M = 0.02e-3


@dataclass(frozen=True)
class Closing:
    """What :func:`simulate` gives: rod travel (m) as a function of the time from the
    release (s), the times (s) of the cam meeting the roller, the contacts' touch and the
    latch, and the average velocity over the last third of the contact stroke (m/s)."""

    rod: object
    cam_contact_time: float
    touch_time: float
    closing_time: float
    closing_velocity_avg: float


def closing(problem: VcbProblem, kc_n_per_mm: tuple[float, float], truth: Truth = TRUTH,
            a: np.ndarray | None = None, spring_kg: float = 0.0, dashpot_n_s_per_m: float = 0.0):
    """Rod travel (m) as a function of the time from the release (s), and the touch time
    and the average velocity over the last third of the contact stroke (m/s), of the
    problem's reference cam (or follower law ``a``) with spring rates ``kc_n_per_mm``.

    Physics camopt's model forms leave out, for the calibration's verdict: ``spring_kg``
    the mass of each of the two closing springs (a uniform coil with one end fixed moves
    with kinetic energy 1/2 (m/3) L'^2, Rayleigh's third: an inertia (m/3) (dL/dtheta)^2
    per spring on the cam, in the free rotation too), ``dashpot_n_s_per_m`` a viscous
    force on the rod (a buffer, c ds1/dt against the motion: a torque c ds1'^2 omega)."""
    sim = simulate(problem, kc_n_per_mm, truth, a, spring_kg=spring_kg,
                   dashpot_n_s_per_m=dashpot_n_s_per_m)
    return sim.rod, sim.touch_time, sim.closing_velocity_avg


def truth_of(problem: VcbProblem) -> Truth:
    """The problem's own motion parameters (its config's) as a :class:`Truth`."""
    c = problem.config
    return Truth(cam_kg_m2=c.cam_inertia_kg_m2, rod_kg=c.rod_mass_kg,
                 contacts_kg=c.contacts_mass_kg, release_offset_deg=c.release_offset_deg,
                 friction_nm=c.cam_friction_nm, follower_kg_m2=c.follower_inertia_kg_m2)


def simulate(problem: VcbProblem, kc_n_per_mm: tuple[float, float], truth: Truth = TRUTH,
             a: np.ndarray | None = None, rtol: float = 1e-10, spring_kg: float = 0.0,
             dashpot_n_s_per_m: float = 0.0) -> Closing:
    """The closing of the problem's reference cam (or follower law ``a``) with spring
    rates ``kc_n_per_mm`` under ``truth``, integrated phase by phase (DOP853, ``rtol``,
    each phase ended by an event)."""
    m: VcbModel = problem.model
    c, loads = problem.config, problem.load
    A = (m.vendor_a if a is None else np.asarray(a))[None, :]
    link = m.vendor_link[None, :]
    kc = np.array([kc_n_per_mm]) * N_PER_MM
    eps, tf = c.efficiency, truth.friction_nm
    end = m.theta_c[-1]

    def state(theta):
        kin = m.kinematics(A, link, problem.rod_offset, np.array([0.0, theta]))
        return kin.s1[0, 1], kin.ds1[0, 1], kin.dphi[0, 1]

    def springs(theta):  # the closing springs' own inertia on the cam
        rate = m.closing_spring_geometry(np.array([theta]))[1][0]
        return 2 * spring_kg / 3 * rate**2

    def inertia(theta, mass):
        _, ds1, dphi = state(theta)
        return (truth.cam_kg_m2 + truth.follower_kg_m2 * dphi**2 + mass * ds1**2
                + springs(theta))

    def torque(theta):
        return m.closing_torque(kc, m.closing_spring_geometry(np.array([theta])))[0, 0]

    def driven(mass):
        def rhs(_t, y):
            theta, omega = y
            s1, ds1, _ = state(theta)
            h = 1e-6
            dj = (inertia(theta + h, mass) - inertia(theta - h, mass)) / (2 * h)
            force = loads.resistant_force(np.array([s1]))[0]
            damping = dashpot_n_s_per_m * ds1 * ds1 * omega
            return [omega, (eps * torque(theta) - tf - force * ds1 - damping
                            - 0.5 * dj * omega**2) / inertia(theta, mass)]
        return rhs

    tol = dict(method="DOP853", rtol=rtol, atol=1e-12, dense_output=True)
    # 1. free rotation from rest at the release
    start = m.dead_centre + truth.release_offset_deg * DEG - m.contact_crank_angle

    def free(_t, y):
        h = 1e-6
        dj = (springs(y[0] + h) - springs(y[0] - h)) / (2 * h)
        return [y[1], (eps * torque(y[0]) - tf - 0.5 * dj * y[1] ** 2)
                / (truth.cam_kg_m2 + springs(y[0]))]

    def roller(_t, y):
        return y[0]

    roller.terminal = True
    s0 = solve_ivp(free, (0.0, 0.2), [start, 0.0], events=roller, **tol)
    t0, (_, w_free) = s0.t_events[0][0], s0.y_events[0][0]
    # 2. the cam meets the roller: generalised momentum kept
    both = truth.rod_kg + truth.contacts_kg
    w0 = (truth.cam_kg_m2 + springs(0.0)) * w_free / inertia(0.0, both)

    def touch(_t, y):
        return state(y[0])[0] - loads.gap

    def two_thirds(_t, y):
        return state(y[0])[0] - 2 * loads.gap / 3

    touch.terminal = True
    s1 = solve_ivp(driven(both), (t0, t0 + 0.2), [0.0, w0], events=[touch, two_thirds], **tol)
    t1, (th1, w1) = s1.t_events[0][0], s1.y_events[0][0]
    v_avg = (loads.gap / 3) / (t1 - s1.t_events[1][0])

    # 3. after the touch, without the contacts, to the latch
    def latch(_t, y):
        return y[0] - end

    latch.terminal = True
    s2 = solve_ivp(driven(truth.rod_kg), (t1, t1 + 0.2), [th1, w1], events=latch, **tol)
    t2 = s2.t_events[0][0]

    def rod(t):
        t = np.asarray(t, dtype=float)
        theta = np.where(t < t1, s1.sol(np.clip(t, t0, t1))[0], s2.sol(np.clip(t, t1, t2))[0])
        theta = np.where(t < t0, 0.0, np.where(t > t2, end, theta))
        kin = m.kinematics(A, link, problem.rod_offset, np.r_[0.0, theta.ravel()])
        return kin.s1[0, 1:].reshape(t.shape)

    return Closing(rod, t0, t1, t2, v_avg)


def sample(rod, delay: float = LATCH_DELAY_S, noise: float = NOISE_M, seed: int = 0,
           duration: float = 0.045, rate_hz: float = 10_000.0):
    """(time from the command (s), noisy travel (m)) at ``rate_hz``."""
    t = np.arange(0.0, duration, 1.0 / rate_hz)
    rng = np.random.default_rng(seed)
    return t, rod(t - delay) + noise * rng.standard_normal(t.size)


def write_csv(path: Path, t: np.ndarray, s: np.ndarray) -> None:
    """A CSV as an analyser exports it: time_ms,travel_mm."""
    lines = ["time_ms,travel_mm"] + [f"{a * TO_MS:.2f},{b * TO_MM:.4f}" for a, b in zip(t, s)]
    path.write_text("\n".join(lines) + "\n")


def main() -> None:  # pragma: no cover - writes tests/data/curves
    from tests.conftest import CONFIGS
    from tests.helpers import load

    problem = VcbProblem(load(CONFIGS / "vcb.toml").case)
    CURVES.mkdir(parents=True, exist_ok=True)
    for seed, (name, kc) in enumerate(SPRING_SETS.items()):
        rod, t_touch, v = closing(problem, kc)
        write_csv(CURVES / f"{name}.csv", *sample(rod, seed=seed))
        print(name, kc, f"touch {(t_touch + LATCH_DELAY_S) * TO_MS:.3f} ms, v {v:.4f} m/s")


if __name__ == "__main__":
    main()


def problem_at_release_ratio(ratio: float) -> VcbProblem:
    """configs/vcb.toml (identified set alone) with the friction torque set so that eps T_s
    / T_f at the vendor's release crank angle is ``ratio`` (the near-balance release)."""
    from tests.conftest import CONFIGS
    from tests.helpers import load

    base = VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]").case)
    m, c = base.model, base.config
    _, kc, _ = base.designs(base.vendor_x())
    start = m.dead_centre + c.release_offset_deg * DEG - m.contact_crank_angle
    spring = m.closing_torque(kc, m.closing_spring_geometry(np.array([start])))[0, 0]
    friction = float(c.efficiency * spring / ratio)
    return VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]",
                           f"case.cam_friction_nm={friction!r}").case)


def problem_released_at_ratio(ratio: float) -> VcbProblem:
    """configs/vcb.toml (identified set alone) with the closing latch moved so that eps T_s
    / T_f at the release crank angle is ``ratio``: the identified friction throughout, so
    the driven closing is the identified one and latches; only the release is near
    balance (the offset found by brentq on the springs' torque, which grows away from the
    dead centre)."""
    from scipy.optimize import brentq

    from tests.conftest import CONFIGS
    from tests.helpers import load

    base = VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]").case)
    m, c = base.model, base.config
    _, kc, _ = base.designs(base.vendor_x())

    def excess(offset_deg: float) -> float:
        start = m.dead_centre + offset_deg * DEG - m.contact_crank_angle
        spring = m.closing_torque(kc, m.closing_spring_geometry(np.array([start])))[0, 0]
        return c.efficiency * spring / c.cam_friction_nm - ratio

    offset = brentq(excess, 0.5, c.release_offset_deg, xtol=1e-14, rtol=1e-15)
    return VcbProblem(load(CONFIGS / "vcb.toml", "case.dynamics_band=[]",
                           f"case.release_offset_deg={offset!r}").case)
