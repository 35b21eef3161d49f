"""One-degree-of-freedom equations of motion from kinetic and potential energy.

scipy.integrate is imported where used (scipy is slow to import; the closed forms need
none)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Travel:
    """Result of :func:`time_to_reach`: time (s), final speed, and the sampled path;
    ``capped`` when the integration stopped at its budget of right-hand-side calls (no
    path then: ``t``, ``q``, ``qdot`` empty)."""

    time: float
    speed: float
    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    reached: bool
    capped: bool = False


class _Budget(Exception):
    """Raised inside the right-hand side when its call budget is spent."""


def time_to_reach(
    mass: Callable[[float], float],
    mass_slope: Callable[[float], float],
    force: Callable[[float], float],
    q0: float,
    q_end: float,
    t_max: float,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_calls: int | None = None,
) -> Travel:
    """Integrate M(q) q'' + M'(q) q'^2 / 2 = Q(q) from rest at q0 until q reaches q_end.

    This is Lagrange's equation for T = M(q) q'^2 / 2 and a generalised force Q;
    ``solve_ivp`` (DOP853) stops on the event q = q_end. ``max_calls`` bounds the work:
    after that many right-hand-side calls (DOP853 makes ~12 a step) the result is
    ``capped``, not reached (a motion that oscillates short of q_end for all of ``t_max``
    would otherwise take minutes of Python calls).
    """
    calls = [0]

    def rhs(_t: float, y: np.ndarray) -> list[float]:
        calls[0] += 1
        if max_calls is not None and calls[0] > max_calls:
            raise _Budget
        q, qd = y
        return [qd, (force(q) - 0.5 * mass_slope(q) * qd * qd) / mass(q)]

    def arrive(_t: float, y: np.ndarray) -> float:
        return y[0] - q_end

    arrive.terminal = True  # type: ignore[attr-defined]
    arrive.direction = np.sign(q_end - q0)  # type: ignore[attr-defined]
    from scipy.integrate import solve_ivp  # not at import: validate never integrates

    try:
        sol = solve_ivp(rhs, (0.0, t_max), [q0, 0.0], method="DOP853", events=arrive,
                        rtol=rtol, atol=atol, dense_output=False)
    except _Budget:
        empty = np.zeros(0)
        return Travel(float("nan"), float("nan"), empty, empty, empty, False, capped=True)
    reached = sol.t_events[0].size > 0
    time = float(sol.t_events[0][0]) if reached else float("nan")
    speed = float(sol.y_events[0][0][1]) if reached else float("nan")
    return Travel(time, speed, sol.t, sol.y[0], sol.y[1], reached)
