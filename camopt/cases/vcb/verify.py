"""``camopt verify`` for the VCB: a design as the data a multibody model is built from
(points, lengths, the cam's follower law, springs, masses, inertias and friction, SI plain
floats), and camopt's lumped closing beside the engine's (:mod:`.multibody`,
docs/verify.md).

The mechanism is read from the run's problem (its stored config and the design's
variables): the geometry and parameters only, never camopt's closing dynamics, so the
multibody model is an independent check of them. Times are from the release of the
closing springs (the closing latch letting go), the lumped model's t = 0, not from a close
command."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.mechanism import mechanism_of
from camopt.errors import CamoptError

TIME_LIMIT = 0.02
"""Largest relative difference of the release-to-touch time the check accepts (2 %)."""
VELOCITY_LIMIT = 0.03
"""Largest relative difference of the touch and the analyser's contact velocity (3 %)."""
INSTALL = "pip install 'camopt[multibody]'"


@dataclass(frozen=True)
class Quantity:
    """One compared quantity: camopt's value, the engine's, and the limit on their
    relative difference (None: shown, not judged)."""

    name: str
    unit: str
    camopt: float
    multibody: float
    limit: float | None

    @property
    def ratio(self) -> float:
        """multibody / camopt."""
        return self.multibody / self.camopt if self.camopt else math.nan

    @property
    def relative_difference(self) -> float:
        """(multibody - camopt) / |camopt|."""
        return (self.multibody - self.camopt) / abs(self.camopt) if self.camopt else math.nan

    @property
    def within(self) -> bool | None:
        """Whether the difference is inside the limit (None without one)."""
        if self.limit is None:
            return None
        return bool(abs(self.relative_difference) <= self.limit)

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "unit": self.unit, "camopt": self.camopt,
                "multibody": self.multibody, "ratio": self.ratio,
                "relative_difference": self.relative_difference, "limit": self.limit,
                "within": self.within}


@dataclass(frozen=True)
class Verification:
    """The comparison of one design: its quantities and the engine's settings."""

    design: str
    quantities: tuple[Quantity, ...]
    engine: dict[str, Any]

    @property
    def agree(self) -> bool:
        return all(q.within is not False for q in self.quantities)

    def as_dict(self) -> dict[str, Any]:
        return {"design": self.design, "engine": self.engine,
                "quantities": [q.as_dict() for q in self.quantities], "agree": self.agree}


def exudyn_error() -> type[Exception]:
    """The exception Exudyn's solver raises when it fails."""
    import exudyn

    error: type[Exception] = getattr(exudyn, "SolverError", RuntimeError)
    return error


def design_of(run: Any, problem: Any, design: str) -> NDArray:
    """The design variables (SI) of the run's best design or of the case's reference
    (the vendor's) design."""
    if design == "reference":
        return np.asarray(problem.vendor_x(), dtype=float)
    for rep in run.repeats:
        if rep.index == run.best.repeat:
            return np.asarray(rep.x, dtype=float)
    raise CamoptError(f"{run.path}: archive: the best repeat's design is not stored")


def camopt_side(problem: Any, x: NDArray) -> dict[str, float]:
    """camopt's own closing of design ``x`` (its identified parameters; a breaker set at
    the factory as set), the quantities the check compares (SI)."""
    from camopt.cases.vcb.multibody import LEAST_FROM

    parts, _ = problem.as_set(x[None, :], None)
    mo = problem.motion(x[None, :], parts=parts)
    window = (mo.theta_c >= LEAST_FROM * mo.theta_c[-1])[None, :] & np.isfinite(mo.time)
    return {"touch_time": float(mo.touch_time[0]), "touch_velocity": float(
        mo.touch_velocity[0]), "contact_velocity_avg": float(mo.closing_velocity_avg[0]),
        "end_time": float(mo.closing_time[0]), "latch_energy": float(mo.final_kinetic[0]),
        "least_roller_torque": float(np.min(np.where(window, mo.cam_torque, np.inf)))}


def verify(run: Any, problem: Any, design: str = "best", step: float | None = None,
           restitution: float = 0.0, coupler_kg: float = 0.0) -> Verification:
    """Compare camopt's closing of the run's ``design`` (its rebuilt ``problem``) with the
    multibody engine's."""
    from camopt.cases.vcb import multibody

    if not multibody.available():
        raise CamoptError(f"{run.path}: verify: the multibody engine is not installed: "
                          f"{INSTALL}")
    x = design_of(run, problem, design)
    ours = camopt_side(problem, x)
    mech = replace(mechanism_of(problem, x), coupler_mass=coupler_kg)
    step = multibody.STEP if step is None else step
    try:
        ev, _ = multibody.run(mech, step, restitution)
    except exudyn_error() as exc:  # Newton failed: a mechanism the model cannot follow
        raise CamoptError(f"{run.path}: verify: the multibody simulation failed "
                          f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
                          ) from None
    ms = 1e3
    quantities = (
        Quantity("release_to_touch", "ms", ours["touch_time"] * ms, ev.touch_time * ms,
                 TIME_LIMIT),
        Quantity("touch_velocity", "m/s", ours["touch_velocity"], ev.touch_velocity,
                 VELOCITY_LIMIT),
        Quantity("contact_velocity_avg", "m/s", ours["contact_velocity_avg"],
                 ev.contact_velocity_avg, VELOCITY_LIMIT),
        Quantity("release_to_end_of_travel", "ms", ours["end_time"] * ms, ev.end_time * ms,
                 None),
        Quantity("latch_energy", "J", ours["latch_energy"], ev.latch_energy, None),
        Quantity("least_cam_roller_torque", "N m", ours["least_roller_torque"],
                 ev.least_roller_torque, None),
    )
    import exudyn

    engine = {"name": "exudyn", "version": exudyn.__version__, "step_s": step,
              "contact_stiffness_n_per_m": multibody.CONTACT_STIFFNESS,
              "restitution": restitution, "coupler_kg": coupler_kg}
    return Verification(design, quantities, engine)
