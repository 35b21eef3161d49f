"""``camopt verify`` for the VCB: a design as the data a multibody model is built from
(points, lengths, the cam's follower law, springs, masses, inertias and friction, SI plain
floats), and camopt's lumped closing beside the engine's (:mod:`.multibody`,
docs/verify.md).

The mechanism is read from the run's problem (its stored config and the design's
variables): the geometry and parameters only, never camopt's closing dynamics, so the
multibody model is an independent check of them. Each parameter set of the run's band is
checked (every kept model form's fit, its other sets, the links' own masses), or the
identified set alone. Times run from the release of the closing springs (the closing latch
letting go, both models' t = 0); with the case's ``latch_delay_ms`` the IEC closing time,
command to touch (``closing_time_ms`` everywhere in camopt), is reported too: the same
delay on both sides."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, TypedDict

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.mechanism import mechanism_of
from camopt.errors import CamoptError

TIME_LIMIT = 0.02
"""Largest relative difference of the release-to-touch time (and of the closing time,
command to touch) the check accepts (2 %)."""
VELOCITY_LIMIT = 0.03
"""Largest relative difference of the touch and the analyser's contact velocity (3 %)."""
INSTALL = "pip install 'camopt[multibody]'"


class QuantityDoc(TypedDict):
    """A compared quantity in ``verify --format json``: both models' values, their ratio
    and relative difference, the limit and whether the difference is within it."""

    name: str
    unit: str
    camopt: float
    multibody: float
    ratio: float
    relative_difference: float
    limit: float | None
    within: bool | None


class SetDoc(TypedDict):
    form: str
    set: int
    parameters: dict[str, float]
    quantities: list[QuantityDoc]
    agree: bool
"""The comparison under one parameter set (``set``: its index in its form)."""


class EngineSettings(TypedDict):
    """The multibody engine and the settings it ran with."""

    name: str
    version: str
    step_s: float
    contact_stiffness_n_per_m: float
    restitution: float
    contact_restitution: float
    coupler_kg: float


class VerificationDoc(TypedDict):
    """``verify --format json``: the design, the engine, the identified set's quantities,
    every set's comparison and whether all agree."""

    design: str
    engine: EngineSettings
    quantities: list[QuantityDoc]
    sets: list[SetDoc]
    agree: bool


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
        """Whether the difference is inside the limit (None without one); where neither
        model has the quantity (nan: the contacts never meet in either) they agree."""
        if self.limit is None:
            return None
        if not (math.isfinite(self.camopt) or math.isfinite(self.multibody)):
            return True
        return bool(abs(self.relative_difference) <= self.limit)

    def as_dict(self) -> QuantityDoc:
        return {"name": self.name, "unit": self.unit, "camopt": self.camopt,
                "multibody": self.multibody, "ratio": self.ratio,
                "relative_difference": self.relative_difference, "limit": self.limit,
                "within": self.within}


@dataclass(frozen=True)
class SetCheck:
    """The comparison under one parameter set: its model form, its index in the form
    (0: the form's fit; the identified parameters for the identified form), its values
    (``dynamics_band`` units) and the quantities."""

    form: str
    index: int
    parameters: dict[str, float]
    quantities: tuple[Quantity, ...]

    @property
    def agree(self) -> bool:
        return all(q.within is not False for q in self.quantities)

    def as_dict(self) -> SetDoc:
        return {"form": self.form, "set": self.index, "parameters": self.parameters,
                "quantities": [q.as_dict() for q in self.quantities], "agree": self.agree}


@dataclass(frozen=True)
class Verification:
    """The comparison of one design under each checked parameter set (the identified one
    first) and the engine's settings."""

    design: str
    sets: tuple[SetCheck, ...]
    engine: EngineSettings

    @property
    def quantities(self) -> tuple[Quantity, ...]:
        """The identified set's quantities."""
        return self.sets[0].quantities

    @property
    def agree(self) -> bool:
        return all(s.agree for s in self.sets)

    def as_dict(self) -> VerificationDoc:
        return {"design": self.design, "engine": self.engine,
                "quantities": [q.as_dict() for q in self.quantities],
                "sets": [s.as_dict() for s in self.sets], "agree": self.agree}


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


@dataclass(frozen=True)
class BandSet:
    """One parameter set a design is judged under: its form, index in the form, the set
    (MotionParameters of one row, the release moved with the design's latch, the parts'
    friction and efficiency) and the closing springs' compressions (2,) m of a breaker set
    at the factory under it (None: the case's)."""

    form: str
    index: int
    params: Any
    pre: NDArray | None


def band_sets(problem: Any, x: NDArray, every: bool = True) -> list[BandSet]:
    """The parameter sets design ``x`` is judged under, as the run judges it: each kept
    form's fit and its other sets (the identified set first), a factory-set breaker set
    under each with its own nut travel; ``every`` False: the identified set alone."""
    from camopt.cases.vcb.band_sets import joined
    from camopt.cases.vcb.dynamics import MotionParameters
    from camopt.cases.vcb.parts import as_made

    X = x[None, :]
    out = []
    for f, form in enumerate(problem.forms):
        k = form.count + 1
        parts, setting = problem.as_set(X, None, form=f)
        efficiency = problem.config.efficiency
        sets = as_made(joined(form, efficiency), k, 1, problem._moved(X, 1), parts,
                       efficiency)
        for j in range(k if every else 1):
            one = MotionParameters(**{
                name: np.asarray(getattr(sets, name), dtype=float)[j:j + 1]
                for name in MotionParameters.__dataclass_fields__})
            pre = None
            if parts is not None and parts.pre is not None:
                pre = parts.pre[0] if j == 0 else setting.member_pre[j - 1]
            out.append(BandSet(form.name, j, one, pre))
        if not every:
            break
    return out


def _row(params: Any) -> dict[str, float]:
    """A set's values in ``dynamics_band`` units."""
    from camopt.units import DEG

    def one(v: Any) -> float:
        return float(np.ravel(v)[0])
    return {"cam_inertia_kg_m2": one(params.cam_kg_m2),
            "follower_inertia_kg_m2": one(params.follower_kg_m2),
            "rod_mass_kg": one(params.rod_kg), "contacts_mass_kg": one(params.contacts_kg),
            "release_offset_deg": one(params.release_offset_rad) / DEG,
            "cam_friction_nm": one(params.friction_nm),
            "release_friction_nm": one(params.release_friction_nm),
            "efficiency": one(params.efficiency)}


def camopt_side(problem: Any, x: NDArray, band_set: BandSet | None = None
                ) -> dict[str, float]:
    """camopt's own closing of design ``x`` under ``band_set`` (None: the identified
    parameters; a breaker set at the factory as set), the quantities the check compares
    (SI)."""
    from camopt.cases.vcb.dynamics import closing_motion
    from camopt.cases.vcb.multibody_events import LEAST_FROM

    if band_set is None:
        parts, _ = problem.as_set(x[None, :], None)
        mo = problem.motion(x[None, :], parts=parts)
    else:
        A, kc, link = problem.designs(x[None, :])
        A = problem.profiled(A, None)
        mo = closing_motion(problem.model, A, kc, link, problem.rod_offset, problem.load,
                            band_set.params, problem.config.dynamics_steps,
                            pre=None if band_set.pre is None else band_set.pre[None, :])
    window = (mo.theta_c >= LEAST_FROM * mo.theta_c[-1])[None, :] & np.isfinite(mo.time)
    gap = float(problem.load.gap)
    rod = mo.rod[0][np.isfinite(mo.time[0])]
    if not len(rod):  # the cam never releases: no closing
        rod = np.array([math.nan])
    touched = bool(np.isfinite(mo.touch_time[0]))  # else no touch: no touch velocity
    return {"touch_time": float(mo.touch_time[0]),
            "touch_velocity": float(mo.touch_velocity[0]) if touched else math.nan,
            "contact_velocity_avg": float(mo.closing_velocity_avg[0]),
            "end_time": float(mo.closing_time[0]),
            "latch_energy": float(mo.final_kinetic[0]),
            "least_roller_torque": float(np.min(np.where(window, mo.cam_torque, np.inf))),
            # rigid links and plastic contacts: the rod ends where the cam puts it, the
            # contacts stay at the gap
            "wipe_at_end": float(rod[-1] - gap),
            "rod_over_travel": float(rod.max() - rod[-1]),
            "bounce_time": 0.0, "rebound": 0.0}


def _quantities(ours: dict[str, float], ev: Any, latch_delay_ms: float | None
                ) -> tuple[Quantity, ...]:
    ms, mm = 1e3, 1e3
    delay = () if latch_delay_ms is None else (
        Quantity("closing_time", "ms", latch_delay_ms + ours["touch_time"] * ms,
                 latch_delay_ms + ev.touch_time * ms, TIME_LIMIT),)
    return delay + (
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
        Quantity("wipe_at_end_of_travel", "mm", ours["wipe_at_end"] * mm,
                 ev.wipe_at_end * mm, None),
        Quantity("rod_over_travel", "mm", ours["rod_over_travel"] * mm,
                 ev.rod_over_travel * mm, None),
        Quantity("contact_bounce", "ms", ours["bounce_time"] * ms, ev.bounce_time * ms, None),
        Quantity("contact_rebound", "mm", ours["rebound"] * mm, ev.rebound * mm, None),
    )


def verify(run: Any, problem: Any, design: str = "best", step: float | None = None,
           restitution: float = 0.0, coupler_kg: float = 0.0, every: bool = True,
           contact_restitution: float = 0.0) -> Verification:
    """Compare camopt's closing of the run's ``design`` (its rebuilt ``problem``) with the
    multibody engine's under each parameter set of the band (``every``; else the
    identified set alone)."""
    from camopt.cases.vcb import multibody

    if not multibody.available():
        raise CamoptError(f"{run.path}: verify: the multibody engine is not installed: "
                          f"{INSTALL}")
    x = design_of(run, problem, design)
    step = multibody.STEP if step is None else step
    checks = []
    for band_set in band_sets(problem, x, every):
        ours = camopt_side(problem, x, band_set)
        mech = replace(mechanism_of(problem, x, band_set.params, band_set.pre),
                       coupler_mass=coupler_kg)
        try:
            ev, _ = multibody.run(mech, step, restitution,
                                  contact_restitution=contact_restitution)
        except exudyn_error() as exc:  # Newton failed: a mechanism the model cannot follow
            raise CamoptError(
                f"{run.path}: verify: the multibody simulation failed "
                f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
            ) from None
        checks.append(SetCheck(band_set.form, band_set.index, _row(band_set.params),
                               _quantities(ours, ev, problem.config.latch_delay_ms)))
    import exudyn

    engine: EngineSettings = {"name": "exudyn", "version": exudyn.__version__, "step_s": step,
              "contact_stiffness_n_per_m": multibody.CONTACT_STIFFNESS,
              "restitution": restitution, "contact_restitution": contact_restitution,
              "coupler_kg": coupler_kg}
    return Verification(design, tuple(checks), engine)
