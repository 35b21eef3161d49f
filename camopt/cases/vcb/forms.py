"""Model forms of the VCB closing dynamics: which losses the rigid model charges, and so
which parameters a fit on measured events (the vendor's ADAMS data,
:mod:`camopt.cases.vcb.identify`) or travel curves (calibration) determines.

Every form keeps the inertias of :mod:`camopt.cases.vcb.dynamics` (J_cam, m_rod, m_c) and
the closing latch's release offset; they differ in the losses, each an equivalent for
what the rigid, one-degree-of-freedom model leaves out (bearing and contact friction,
damping, the springs' own mass):

* ``efficiency_coulomb`` (the shipped fit): eps = the case's ``efficiency`` (Eq 26, 0.85)
  on every spring's work and a Coulomb torque T_f at the cam shaft whenever it turns;
* ``coulomb``: T_f alone (eps = 1), from the release on;
* ``efficiency_driven_coulomb``: the case's eps, T_f only while the cam drives the roller
  (the free rotation from the release turns without it);
* ``driven_coulomb``: T_f only in the driven closing, eps = 1;
* ``fitted_efficiency``: no friction torque; eps itself fitted (a loss proportional to the
  springs' work, in the opening too).

A form is data (:class:`ModelForm`): its fitted parameters with their bounds (the
identification config's ``*_bounds`` fields for the seven ADAMS data; :data:`CURVE_SEARCH`
for travel curves, :meth:`ModelForm.curve_parameters`), their starting values from a case
(:meth:`ModelForm.start`) and the map from a parameter vector to
:class:`~camopt.cases.vcb.dynamics.MotionParameters`, with which :meth:`ModelForm.closing`
simulates the closing (events and rod travel curve) of designs, vectorised over rows, and
:meth:`ModelForm.band_rows` writes ``dynamics_band`` rows. The identification
(:mod:`camopt.cases.vcb.identify`) and the calibration on travel curves
(:mod:`camopt.cases.vcb.calibrate`) both fit every form of :data:`FORMS` through this
one seam.
Viscous friction (a torque c omega) is not among them: the work it takes depends on the
speed, so the work-energy integration would become a time-stepped ODE
(docs/assumptions.md, "VCB: model forms").
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Literal, get_args

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import ModelFormName, VcbConfig
from camopt.cases.vcb.dynamics import (
    ClosingEvents,
    ClosingMotion,
    MotionParameters,
    closing_events,
    closing_motion,
)
from camopt.cases.vcb.model import Loads, VcbModel
from camopt.core.problem import Variable
from camopt.errors import ConfigError
from camopt.units import DEG, MM

if TYPE_CHECKING:  # a vcb run never imports the identification's config
    from camopt.cases.vcb.identify_config import VcbDynamicsIdentifyConfig

INERTIAS = ("cam_inertia_kg_m2", "rod_mass_kg", "contacts_mass_kg", "release_offset_deg")
"""The parameters every form fits (units in the names)."""
BOUNDS = {"cam_inertia_kg_m2": "cam_inertia_bounds_kg_m2", "rod_mass_kg": "rod_mass_bounds_kg",
          "contacts_mass_kg": "contacts_mass_bounds_kg",
          "release_offset_deg": "release_offset_bounds_deg",
          "cam_friction_nm": "cam_friction_bounds_nm", "efficiency": "efficiency_bounds"}
"""Each fitted parameter's bounds: the identification config's field."""
BAND_COLUMNS = ("cam_inertia_kg_m2", "follower_inertia_kg_m2", "rod_mass_kg",
                "contacts_mass_kg", "release_offset_deg", "cam_friction_nm",
                "release_friction_nm", "efficiency")
"""A ``dynamics_band`` row: every MotionParameters field, in the units of the names."""


@dataclass(frozen=True)
class FitParameter:
    """A parameter fitted on travel curves: its name (a ``[case]`` field, so the fitted
    value can be written back), unit, search bounds (in the unit) and whether it is fitted
    in its log (a positive quantity)."""

    name: str
    unit: str
    lower: float
    upper: float
    log: bool = True


CURVE_SEARCH = {p.name: p for p in (
    FitParameter("cam_inertia_kg_m2", "kg m^2", 1e-5, 0.05),
    FitParameter("rod_mass_kg", "kg", 0.05, 30.0),
    FitParameter("contacts_mass_kg", "kg", 0.05, 15.0),
    FitParameter("release_offset_deg", "deg", 0.5, 40.0),
    FitParameter("cam_friction_nm", "N m", 0.01, 100.0),
    FitParameter("efficiency", "1", 0.2, 1.0),
    FitParameter("spring_mass_kg", "kg", 0.01, 20.0),
    FitParameter("rod_damping_n_s_per_m", "N s/m", 1.0, 5000.0),
)}
"""Search bounds of a calibration on travel curves (wider than the identification's: a
breaker maker's own mechanism, not the paper's); every parameter positive, fitted in its
log (the friction from 0.01 N m: a loss too small to see on a curve)."""


@dataclass(frozen=True)
class ModelForm:
    """One model form: ``name``, a one-line ``summary``, where the efficiency comes from
    (``case``: the case's ``efficiency``; ``none``: 1; ``fitted``: a parameter) and where
    the Coulomb friction torque acts (``everywhere``: from the release on; ``driven``:
    only while the cam drives the roller; ``none``), and the physics it adds to its
    ``base`` form (``extra``: the closing springs' own mass, a rod dashpot; fitted as
    :data:`EXTRA_PARAMETER`)."""

    name: str
    summary: str
    efficiency: Literal["case", "none", "fitted"]
    friction: Literal["everywhere", "driven", "none"]
    extra: Literal["none", "spring_mass", "dashpot"] = "none"
    base: str | None = None

    @property
    def parameters(self) -> tuple[str, ...]:
        """The fitted parameters' names, units in the names (the order of a vector)."""
        return (INERTIAS + (("cam_friction_nm",) if self.friction != "none" else ())
                + (("efficiency",) if self.efficiency == "fitted" else ())
                + ((EXTRA_PARAMETER[self.extra],) if self.extra != "none" else ()))

    def variables(self, config: VcbDynamicsIdentifyConfig) -> tuple[Variable, ...]:
        """The parameters with the identification config's bounds."""
        return tuple(Variable(name, getattr(config, BOUNDS[name]).lower,
                              getattr(config, BOUNDS[name]).upper) for name in self.parameters)

    def curve_parameters(self) -> tuple[FitParameter, ...]:
        """The parameters with the search bounds of a calibration on travel curves
        (:data:`CURVE_SEARCH`), in the order of a vector."""
        return tuple(CURVE_SEARCH[name] for name in self.parameters)

    def start(self, config: VcbConfig) -> NDArray:
        """The case's values of the parameters (their units), (p,): a fit's first start.
        A friction torque starts at 0.1 N m at least, a spring mass at 0.1 kg, a damping
        at 20 N s/m (fitted in their logs)."""
        values = {"cam_friction_nm": max(config.cam_friction_nm, 0.1),
                  "efficiency": config.efficiency,
                  "spring_mass_kg": max(config.spring_mass_kg, 0.1),
                  "rod_damping_n_s_per_m": max(config.rod_damping_n_s_per_m, 20.0)}
        return np.array([values[n] if n in values else getattr(config, n)
                         for n in self.parameters], dtype=float)

    def band_rows(self, X: NDArray, config: VcbConfig) -> NDArray:
        """Parameter rows ``X`` (k, p) as ``dynamics_band`` rows (k, 8):
        :data:`BAND_COLUMNS`, the case's follower inertia and efficiency where the form
        does not fit them."""
        mp = self.motion_parameters(X, config.follower_inertia_kg_m2)
        k = len(np.atleast_2d(X))
        friction = mp.friction_nm if mp.release_friction_nm is None else mp.release_friction_nm
        eps = config.efficiency if mp.efficiency is None else mp.efficiency
        columns = (mp.cam_kg_m2, mp.follower_kg_m2, mp.rod_kg, mp.contacts_kg,
                   np.asarray(mp.release_offset_rad) / DEG, mp.friction_nm, friction, eps)
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), (k,))
                                for c in columns])

    def motion_parameters(self, X: NDArray, follower_kg_m2: float) -> MotionParameters:
        """Parameter rows ``X`` (n, len(parameters)), in the names' units, as
        MotionParameters (SI), one set per row."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        col = dict(zip(self.parameters, X.T))
        friction = col.get("cam_friction_nm", 0.0)
        return MotionParameters(
            col["cam_inertia_kg_m2"], follower_kg_m2, col["rod_mass_kg"],
            col["contacts_mass_kg"], col["release_offset_deg"] * DEG, friction,
            release_friction_nm=0.0 if self.friction == "driven" else None,
            efficiency={"case": None, "none": 1.0}.get(self.efficiency, col.get("efficiency")),
            spring_kg=col.get("spring_mass_kg", 0.0),
            rod_damping_n_s_per_m=col.get("rod_damping_n_s_per_m", 0.0))

    def closing(self, model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
                rod_offset: NDArray | float, loads: Loads, X: NDArray, follower_kg_m2: float,
                steps: int) -> ClosingMotion:
        """The closing of n designs (``A`` (n, d + 1), ``kc`` (n, 2) N/m, ``link`` (n, 5))
        under parameter rows ``X`` (n, p), one per design: events and curves (rod travel
        ``rod`` against ``time``, (n, m))."""
        return closing_motion(model, A, kc, link, rod_offset, loads,
                              self.motion_parameters(X, follower_kg_m2), steps)

    def events(self, model: VcbModel, A: NDArray, kc: NDArray, link: NDArray,
               rod_offset: NDArray | float, loads: Loads, X: NDArray, follower_kg_m2: float,
               steps: int) -> ClosingEvents:
        """As :meth:`closing`, the events alone, every parameter row of ``X`` (k, p) for
        every design: k x n rows, set-major."""
        k = len(np.atleast_2d(X))
        mp = self.motion_parameters(X, follower_kg_m2)
        # one value per set (a form's fixed value for all) before each is repeated
        params = replace(mp, **{f.name: np.broadcast_to(np.asarray(v, dtype=float), (k,))
                                for f in fields(mp)
                                if (v := getattr(mp, f.name)) is not None}).repeat(len(A))
        return closing_events(model, A, kc, link, rod_offset, loads, params, steps, sets=k)


FORMS = (
    ModelForm("efficiency_coulomb", "Eq 26's efficiency and a Coulomb torque at the cam shaft",
              "case", "everywhere"),
    ModelForm("coulomb", "a Coulomb torque at the cam shaft alone (no efficiency)",
              "none", "everywhere"),
    ModelForm("efficiency_driven_coulomb", "Eq 26's efficiency; Coulomb torque only while "
              "the cam drives the roller", "case", "driven"),
    ModelForm("driven_coulomb", "a Coulomb torque only while the cam drives the roller",
              "none", "driven"),
    ModelForm("fitted_efficiency", "an efficiency on every spring's work, fitted; no "
              "friction torque", "fitted", "none"),
)
"""Every model form, the shipped one first."""
FORM_NAMES = tuple(f.name for f in FORMS)
assert len(set(FORM_NAMES)) == len(FORMS), "a model form's name is taken twice"
assert set(FORM_NAMES) == set(get_args(ModelFormName)), "config.ModelFormName is out of date"
EXTRA_PARAMETER = {"spring_mass": "spring_mass_kg", "dashpot": "rod_damping_n_s_per_m"}
"""The parameter a form with more physics fits besides its base form's."""
CURVE_FORMS = FORMS + (
    ModelForm("efficiency_coulomb_spring_mass", "efficiency_coulomb with the closing "
              "springs' own mass (effective, at their free ends)", "case", "everywhere",
              "spring_mass", "efficiency_coulomb"),
    ModelForm("efficiency_coulomb_dashpot", "efficiency_coulomb with a viscous damper on "
              "the rod (dashpot, buffer)", "case", "everywhere", "dashpot",
              "efficiency_coulomb"),
)
"""The forms a calibration on travel curves fits: :data:`FORMS` and forms with physics
the seven ADAMS data cannot see, each its ``base`` form plus one term (the closing
springs' own mass, a rod dashpot), kept only where the curves need the term
(:func:`camopt.cases.vcb.calibrate.nested_keep`)."""
CURVE_FORM_NAMES = tuple(f.name for f in CURVE_FORMS)


def get_form(name: str) -> ModelForm:
    """The form named ``name`` (of :data:`CURVE_FORMS`); bad input names the known ones."""
    for f in CURVE_FORMS:
        if f.name == name:
            return f
    raise ConfigError("case", "model_form", f"unknown form {name!r}; known: "
                      f"{', '.join(CURVE_FORM_NAMES)}")


def form_of(row: NDArray) -> str:
    """The model form a parameter set of ``dynamics_band`` belongs to, read from its
    eight values (:data:`~camopt.cases.vcb.config.BandRow`): no friction torque is
    ``fitted_efficiency``; friction in the driven closing alone (none in the free rotation)
    one of the ``driven`` forms, else one with friction everywhere; an efficiency of 1 a
    form without efficiency (``coulomb``, ``driven_coulomb``), any other the case's
    (``efficiency_*``: the identification fits those with the case's eps)."""
    friction, release_friction, efficiency = float(row[5]), float(row[6]), float(row[7])
    if friction == 0.0:
        return "fitted_efficiency"
    driven = release_friction == 0.0
    if efficiency == 1.0:
        return "driven_coulomb" if driven else "coulomb"
    return "efficiency_driven_coulomb" if driven else "efficiency_coulomb"


def link_mass_rows(band: NDArray, config: VcbConfig) -> NDArray:
    """The band's link-mass sets, (f, 8) ``dynamics_band`` rows: each model form's fit
    (the identified parameters for theirs, else the form's first row of ``band``) with the
    links' own masses the identified model leaves out, ``band_coupler_mass_kg`` and
    ``band_follower_inertia_kg_m2``. The coupler DL is lumped as two point masses at its
    joints: half at D on the follower (``follower_inertia_kg_m2`` + m/2 l2^2), half at L
    on the output link, which turns l4/l5 times as fast at L as at the arm's end M that
    lifts the rod (``rod_mass_kg`` + m/2 (l4/l5)^2, the config's l4, l5); the follower's
    own inertia adds to ``follower_inertia_kg_m2``. Nothing is refitted: the set is the
    fit with heavier links, the band's slow end (docs/assumptions.md, "VCB: link masses";
    the multibody model with the coupler as a bar moves the vendor's closing as this
    lumping does, docs/verify.md). None (0 rows) without a band (the identified
    parameters alone) or without link masses."""
    c = config
    m, jf = c.band_coupler_mass_kg, c.band_follower_inertia_kg_m2
    band = np.asarray(band, dtype=float).reshape(-1, len(BAND_COLUMNS))
    if not len(band) or not (m or jf):
        return np.empty((0, len(BAND_COLUMNS)))
    identified = np.array([c.cam_inertia_kg_m2, c.follower_inertia_kg_m2, c.rod_mass_kg,
                           c.contacts_mass_kg, c.release_offset_deg, c.cam_friction_nm,
                           c.cam_friction_nm, c.efficiency])
    firsts: dict[str, NDArray] = {}
    for row in (identified, *band):
        firsts.setdefault(form_of(row), row)
    rows = np.array(list(firsts.values()))
    l2, l4, l5 = c.l2_mm * MM, c.l4_mm * MM, c.l5_mm * MM
    rows[:, 1] += m / 2 * l2**2 + jf
    rows[:, 2] += m / 2 * (l4 / l5) ** 2
    return rows
