"""One-degree-of-freedom equations of motion from kinetic and potential energy."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp


@dataclass(frozen=True)
class Travel:
    """Result of :func:`time_to_reach`: time (s), final speed, and the sampled path."""

    time: float
    speed: float
    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    reached: bool


def time_to_reach(
    mass: Callable[[float], float],
    mass_slope: Callable[[float], float],
    force: Callable[[float], float],
    q0: float,
    q_end: float,
    t_max: float,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> Travel:
    """Integrate M(q) q'' + M'(q) q'^2 / 2 = Q(q) from rest at q0 until q reaches q_end.

    This is Lagrange's equation for T = M(q) q'^2 / 2 and a generalised force Q;
    ``solve_ivp`` (DOP853) stops on the event q = q_end.
    """

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        q, qd = y
        return [qd, (force(q) - 0.5 * mass_slope(q) * qd * qd) / mass(q)]

    def arrive(_t: float, y: np.ndarray) -> float:
        return y[0] - q_end

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = np.sign(q_end - q0)  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, t_max), [q0, 0.0], method="DOP853", events=arrive,
                    rtol=rtol, atol=atol, dense_output=False)
    reached = sol.t_events[0].size > 0
    time = float(sol.t_events[0][0]) if reached else float("nan")
    speed = float(sol.y_events[0][0][1]) if reached else float("nan")
    return Travel(time, speed, sol.t, sol.y[0], sol.y[1], reached)
