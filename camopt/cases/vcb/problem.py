"""12 kV VCB closing mechanism as an optimisation problem: step 1 (cam + closing springs)
or step 2 (four-bar), Kang, Huang & Yang (2023), Eqs 37-43."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.band import BANDED, MotionBand
from camopt.cases.vcb.config import CamDesign, VcbConfig
from camopt.cases.vcb.constraints import CONSTRAINTS, Terms
from camopt.cases.vcb.dynamics import (
    ClosingMotion,
    MotionParameters,
    closing_events,
    closing_motion,
)
from camopt.cases.vcb.forms import form_of, link_mass_rows
from camopt.cases.vcb.model import (
    Loads,
    VcbModel,
    follower_dwell,
    phi_max,
    rate_zeros,
    row_max,
)
from camopt.core.capabilities import HasVariants, VariesCase
from camopt.core.problem import Evaluation, ObjectiveFloor, Problem, Variable
from camopt.errors import ConfigError
from camopt.mechanics import cam, hertz
from camopt.units import DEG, MM, MPA, N_PER_MM, TO_MS, TO_N_PER_MM

_WORST_LOW = ("latched", "lift_off_torque_ratio", "cam_torque_min_nm")
_WORST_HIGH = ("pickup_tau_mpa",)
"""Metrics of a set breaker's verdict over every form (:meth:`VcbProblem._worst_form`)
whose worst is their least / greatest, beside the band's ``_low`` / ``_high`` ends."""
SETTING_TRIAL_MM = 2.0
"""The factory setting's trial nut travel (mm; the other trial is none): the secant's
two points (:meth:`VcbProblem.as_set`)."""
LINK_FIELDS = ("l1_mm", "l3_mm", "l4_mm", "l5_mm", "theta1_deg")
"""The linkage fields of ``[case]`` in the order of a linkage row (``designs``)."""
PART_FIELDS = ("kc1_precompression_mm", "kc2_precompression_mm", "opening_k_n_per_mm",
               "wipe_k_n_per_mm", "cam_friction_nm", "efficiency", "cam_profile_error_mm")
"""The parts' fields of ``[case]`` a design can take per row in either step: the closing
springs' compressions in the opened state (their free lengths as made), the opening and
contact springs' rates, the friction and efficiency, the cam profile's radial error."""


@dataclass(frozen=True)
class Parts:
    """Each design's parts as made, one row per design (SI); None: the config's value.
    ``link`` (n, 5); ``pre`` the closing springs' compressions (n, 2) m; ``opening_k``,
    ``wipe_k`` the opening spring's and all contact springs' rates (n, 1) N/m;
    ``friction_scale`` (n,) every friction torque of every parameter set times this;
    ``efficiency_shift`` (n,) added to every efficiency below 1 (the forms with Eq 26's
    eps; a form without one keeps 1); ``profile_rad`` (n,) the follower's angle offset
    from the cam profile's radial error."""

    link: NDArray | None = None
    pre: NDArray | None = None
    opening_k: NDArray | None = None
    wipe_k: NDArray | None = None
    friction_scale: NDArray | None = None
    efficiency_shift: NDArray | None = None
    profile_rad: NDArray | None = None

    def take(self, rows: NDArray) -> Parts:
        """The parts of the designs ``rows`` (bool or index array)."""
        return Parts(*(None if v is None else v[rows] for v in
                       (self.link, self.pre, self.opening_k, self.wipe_k, self.friction_scale,
                        self.efficiency_shift, self.profile_rad)))


@dataclass(frozen=True)
class Setting:
    """A factory setting (:meth:`VcbProblem.as_set`) of n breakers under a form's k + 1
    parameter sets: the band's other sets' set compressions ``member_pre`` (k n, 2) m,
    set-major as the band's rows (None without other sets), and the nut travel each set
    needs, ``needed`` (k + 1, n) m (the fit's first; +inf: none reaches the velocity)."""

    member_pre: NDArray | None
    needed: NDArray

    @property
    def longest(self) -> NDArray:
        """(n,) the needed travel of the set that needs the most, with its sign."""
        return _longest(self.needed)


def _longest(travels: NDArray) -> NDArray:
    """(n,) each column's entry of largest magnitude, with its sign, of ``travels`` (k, n)."""
    index = np.argmax(np.abs(travels), axis=0)
    return np.take_along_axis(travels, index[None], axis=0)[0]


LIFE_END_METRICS = ("closing_velocity_low_m_s", "closing_velocity_high_m_s",
                    "latch_kinetic_energy_low_j", "latch_kinetic_energy_high_j",
                    "release_torque_margin_low", "band_sets_not_latched")
"""The metrics reported again at the end of life (``life_end_`` + name), where the run
judges it: the verdict's worst alone does not say when a requirement binds."""


def _worst_of(each: list[Evaluation], penalty: float, sum_counts: bool = False,
              life_end: Evaluation | None = None) -> Evaluation:
    """One verdict over several judgements of the same breakers (every model form, or the
    start and end of life): each constraint at its worst, the objective the first's with
    the worst violation's penalty, the band's lower ends the least and higher ends the
    greatest, the setting the longest nut travel, the other metrics the first's. With
    ``sum_counts`` the band's set counts add up (different sets); else they take their
    worst. ``life_end``: its :data:`LIFE_END_METRICS` reported as ``life_end_*``."""
    g = np.max([e.g for e in each], axis=0)
    violation = np.clip(g, 0, None).sum(axis=1)
    first = each[0]
    own = np.clip(first.g, 0, None).sum(axis=1)
    with np.errstate(invalid="ignore"):  # inf - inf: no finite objective either way
        base = np.where(own == 0, first.f, first.f - penalty * own)
    f = np.where(np.isfinite(base) & np.isfinite(violation), base + penalty * violation,
                 np.inf)
    extras = dict(first.extras)
    counts = ("band_sets", "band_sets_not_latched")
    for key in extras:
        stack = np.array([e.extras[key] for e in each], dtype=float)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns stay NaN
            name = key.removeprefix("life_end_")
            if name in counts:
                extras[key] = stack.sum(axis=0) if sum_counts else stack.max(axis=0)
            elif name == "preload_setting_mm":
                extras[key] = _longest(stack)
            elif name.startswith("closing_velocity_") and ("_low" in name
                                                         or "_high" in name):
                # NaN: a set that never closes, so the band has no velocity
                extras[key] = (np.max if "_high" in name else np.min)(stack, axis=0)
            elif "_low" in name or name in _WORST_LOW:
                extras[key] = np.nanmin(stack, axis=0)
            elif "_high" in name or name in _WORST_HIGH:
                extras[key] = np.nanmax(stack, axis=0)
    if life_end is not None:
        extras.update({f"life_end_{k}": life_end.extras[k] for k in LIFE_END_METRICS
                       if k in life_end.extras})
    return Evaluation(f=f, g=g, extras=extras)


def _joined(form: FormSets, efficiency: float) -> MotionParameters:
    """A form's fit and its other sets as k + 1 parameter sets ((k + 1,) arrays, the fit
    first), every field resolved as :meth:`MotionParameters.columns` resolves it."""
    columns = [form.nominal.columns(1, efficiency)]
    if form.members is not None:
        columns.append(form.members.columns(form.count, efficiency))
    return MotionParameters(**{f.name: np.concatenate([getattr(c, f.name)[:, 0]
                                                       for c in columns])
                               for f in fields(MotionParameters)})


@dataclass(frozen=True)
class FormSets:
    """The parameter sets a closing is judged under: the ``nominal`` set (its values and
    metrics are the design's ``closing_*``) and the ``members`` of the band beside it
    (``count`` sets, set-major arrays; None when there are none). Release offsets are the
    sets' own (rad); a design's latch moves every one with it."""

    name: str
    nominal: MotionParameters
    members: MotionParameters | None
    count: int


def _sets(rows: NDArray, c: VcbConfig | None = None) -> MotionParameters:
    """Eight-value band rows (k, 8) as k parameter sets (SI), with the case ``c``'s
    spring mass and rod damping (one value for every set; none without ``c``)."""
    return MotionParameters(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3], rows[:, 4] * DEG,
                            rows[:, 5], rows[:, 6], rows[:, 7],
                            spring_kg=0.0 if c is None else c.spring_mass_kg,
                            rod_damping_n_s_per_m=0.0 if c is None else c.rod_damping_n_s_per_m)


class VcbProblem(Problem, VariesCase, HasVariants):
    """Step 1 (cam + springs) or step 2 (four-bar) of the VCB design; minimise Eq 39."""

    def __init__(self, config: VcbConfig) -> None:
        self.config = c = config
        self.model = m = VcbModel(config)
        self.rod_offset = c.rod_arm_offset_deg * DEG
        vendor = m.kinematics(m.vendor_a[None, :], m.vendor_link[None, :], self.rod_offset)
        self.vendor_travel = float(vendor.s1[0, -1])
        self.load = m.loads(self.vendor_travel, c.opening_arm_ratio, c.free_contact_force_n)
        self.objective_name = "objective_j" if c.objective_form == "net" else "objective_n"
        if c.step == "cam":
            self.variables = (
                Variable("a1", c.a1_bounds.lower, c.a1_bounds.upper),
                Variable("a2", c.a2_bounds.lower, c.a2_bounds.upper),
                Variable("a3", c.a3_bounds.lower, c.a3_bounds.upper),
                Variable("kc1_n_per_mm", c.kc1_bounds_n_per_mm.lower * N_PER_MM,
                         c.kc1_bounds_n_per_mm.upper * N_PER_MM, TO_N_PER_MM),
                Variable("kc2_n_per_mm", c.kc2_bounds_n_per_mm.lower * N_PER_MM,
                         c.kc2_bounds_n_per_mm.upper * N_PER_MM, TO_N_PER_MM),
            ) + tuple(Variable(name, b.lower, b.upper)
                      for name, b in (("a4", c.a4_bounds), ("a5", c.a5_bounds)) if b is not None)
            self.higher_terms = len(self.variables) - 5
            if len(m.vendor_a) - 4 > self.higher_terms:
                need = "a4_bounds" if len(m.vendor_a) == 5 else "a4_bounds and a5_bounds"
                raise ConfigError("case", "reference_law", f"the reference cam's law has "
                                  f"degree {len(m.vendor_a) - 1}: set {need} so the "
                                  "search's law reaches it")
            r = c.release_offset_bounds_deg
            if r is not None:  # beyond the paper: where the latch holds the charged crank
                self.variables += (Variable("release_offset_deg", r.lower * DEG, r.upper * DEG,
                                            1 / DEG),)
            self.release_column = len(self.variables) - 1 if r is not None else None
            self.case_release = c.release_offset_deg * DEG
            v = c.velocity_setting_bounds_m_s
            if v is not None:  # beyond the paper: the velocity every breaker is set to
                self.variables += (Variable("velocity_setting_m_s", v.lower, v.upper),)
            self.setting_column = len(self.variables) - 1 if v is not None else None
        else:
            if c.cam_design is None:  # cam_archive is read into cam_design before a build
                raise ConfigError("case", "cam_archive", "the step-1 archive was not read")
            self.cam_a, self.cam_kc = self._cam(c.cam_design)
            self.release_column = self.setting_column = None
            self.case_release = (c.release_offset_deg if c.cam_design.release_offset_deg is None
                                 else c.cam_design.release_offset_deg) * DEG
            self.variables = tuple(
                Variable(name, b.lower * f, b.upper * f, 1 / f)
                for name, b, f in (("l1_mm", c.l1_bounds_mm, MM), ("l3_mm", c.l3_bounds_mm, MM),
                                   ("l4_mm", c.l4_bounds_mm, MM), ("l5_mm", c.l5_bounds_mm, MM),
                                   ("theta1_deg", c.theta1_bounds_deg, DEG)))
        self.constraints = tuple(con for con in CONSTRAINTS if con.applies(c))
        self.constraint_names = tuple(con.name for con in self.constraints)
        self.dynamics = MotionParameters(c.cam_inertia_kg_m2, c.follower_inertia_kg_m2,
                                         c.rod_mass_kg, c.contacts_mass_kg,
                                         c.release_offset_deg * DEG, c.cam_friction_nm,
                                         spring_kg=c.spring_mass_kg,
                                         rod_damping_n_s_per_m=c.rod_damping_n_s_per_m)
        # six-value rows are the shipped form: the free rotation's friction the same, the
        # case's efficiency
        band = np.array([tuple(r) + ((r[5], c.efficiency) if len(r) == 6 else ())
                         for r in c.dynamics_band], dtype=float).reshape(-1, 8)
        band = np.vstack([band, link_mass_rows(band, c)])  # the links' own masses
        self.band = _sets(band, c) if len(band) else None
        self.forms = self._forms(band)
        self.search_dynamics = (c.closing_velocity_m_s is not None or c.require_latch
                                or c.forbid_lift_off or self.setting_column is not None)

    def _forms(self, band: NDArray) -> tuple[FormSets, ...]:
        """The sets of every model form in the band (the identified parameters' form
        first): each form's closing is judged under its own fit (the identified set for
        that form, else the form's first row: the identification lists each form's fit
        first) and its other sets. A single form gives one entry, the full band."""
        c = self.config
        identified = np.array([[c.cam_inertia_kg_m2, c.follower_inertia_kg_m2, c.rod_mass_kg,
                                c.contacts_mass_kg, c.release_offset_deg, c.cam_friction_nm,
                                c.cam_friction_nm, c.efficiency]])
        names = [form_of(identified[0])] + [form_of(r) for r in band]
        order = list(dict.fromkeys(names))
        if len(order) == 1:
            return (FormSets(order[0], self.dynamics, self.band, len(band)),)
        out = []
        for name in order:
            rows = band[[i for i, f in enumerate(names[1:]) if f == name]]
            if name == names[0]:
                nominal, members = self.dynamics, rows
            else:
                nominal = replace(_sets(rows[:1], c), **{
                    f: float(np.ravel(getattr(_sets(rows[:1]), f))[0]) for f in
                    ("cam_kg_m2", "follower_kg_m2", "rod_kg", "contacts_kg",
                     "release_offset_rad", "friction_nm")})
                nominal = replace(nominal, release_friction_nm=float(rows[0, 6]),
                                  efficiency=float(rows[0, 7]))
                members = rows[1:]
            out.append(FormSets(name, nominal, _sets(members, c) if len(members) else None,
                                len(members)))
        return tuple(out)

    def variants(self) -> tuple[str, ...]:
        """The kept model forms the band holds (docs/tolerance.md, "Model forms in the
        draws"): a design drawn in form ``i`` is judged under that form's sets alone."""
        return tuple(f.name for f in self.forms) if len(self.forms) > 1 else ()

    def _cam(self, d: CamDesign) -> tuple[NDArray, NDArray]:
        a0 = self.model.phi0() if d.a0 is None else d.a0
        coefficients = np.array([a0, d.a1, d.a2, d.a3, d.a4, d.a5])
        degree = 5 if d.a5 else 4 if d.a4 else 3  # the paper's cubic unless a design has more
        return coefficients[:degree + 1], np.array([d.kc1_n_per_mm, d.kc2_n_per_mm]) * N_PER_MM

    def designs(self, X: NDArray, link: NDArray | None = None
                ) -> tuple[NDArray, NDArray, NDArray]:
        """Follower-law coefficients (n, d + 1: the cubic's 4, or with a4/a5 as design
        variables 5 or 6), spring rates (n, 2) and linkage (n, 5) of each row; step 1 takes
        the config's linkage unless ``link`` (n, 5) gives one per row."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        if self.config.step == "cam":
            # a1..a3, kc1, kc2, then any higher terms (a4, a5): the paper's order first
            A = np.column_stack([np.full(n, self.model.phi0()), X[:, :3],
                                 X[:, 5:5 + self.higher_terms]])
            return A, X[:, 3:5], np.tile(self.model.vendor_link, (n, 1)) if link is None \
                else link
        return np.tile(self.cam_a, (n, 1)), np.tile(self.cam_kc, (n, 1)), X[:, :5]

    def objective_floor(self) -> ObjectiveFloor:
        """Both forms of Eq 39 are absolute values (``|surplus|`` in J, a sum of ``|Fo -
        Fr/eps|`` in N): 0, whatever the dynamics model (a bound from the latch energy would
        depend on it: docs/design.md, Sec Performance)."""
        return ObjectiveFloor(0.0, "the objective is an absolute value")

    def vendor_x(self) -> NDArray:
        """The vendor's design in this step's variables (initial design of Tables 6, 7)."""
        if self.config.step == "cam":
            c = self.config
            # the paper's vendor law is a cubic; a reference cam read from points may have
            # higher terms (its degree was checked against the search's at the build)
            higher = np.zeros(self.higher_terms)
            higher[:len(self.model.vendor_a) - 4] = self.model.vendor_a[4:]
            release = [] if self.release_column is None else [c.release_offset_deg * DEG]
            # the vendor's breaker set to the middle of the setting's bounds (it has no
            # reference velocity of its own in this search)
            v = c.velocity_setting_bounds_m_s
            setting = [] if v is None else [0.5 * (v.lower + v.upper)]
            return np.r_[self.model.vendor_a[1:4], c.kc1_n_per_mm * N_PER_MM,
                         c.kc2_n_per_mm * N_PER_MM, higher, release, setting]
        return self.model.vendor_link.copy()

    def evaluate(self, X: NDArray) -> Evaluation:
        """Objective and constraints, with the metrics the search needs (hot path)."""
        return self._evaluate(X, detail=False)

    def describe(self, X: NDArray) -> Evaluation:
        """As :meth:`evaluate`, plus descriptive metrics (pressure angle, curvature,
        normal force, output range) for tables and reports."""
        return self._evaluate(X, detail=True)

    def case_fields(self) -> tuple[str, ...]:
        """Step 1: the linkage fields (the four-bar is fixed there, so its made lengths
        may vary per design); step 2 varies the linkage as design variables. Both: the
        parts (:data:`PART_FIELDS`)."""
        return (LINK_FIELDS if self.config.step == "cam" else ()) + PART_FIELDS

    def describe_with(self, X: NDArray, fields: Mapping[str, NDArray]) -> Evaluation:
        """As :meth:`describe`, with the named fields (mm, deg, N/mm, N m) per row: the
        linkage array the kinematics already takes per design, and the parts
        (:class:`Parts`); the loads' preloads stay those of the config's linkage (they
        describe the breaker, not the parts made)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        return self._evaluate(X, detail=True, parts=self.parts(len(X), fields))

    def describe_variants(self, X: NDArray, fields: Mapping[str, NDArray], variant: NDArray,
                          detail: bool = True) -> Evaluation:
        """As :meth:`describe_with`, each row judged under the sets of its model form
        ``variants()[variant[i]]`` alone (-1: every form, the case's own evaluation);
        ``detail=False``: :meth:`evaluate`'s metrics, not the descriptive ones."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        parts = self.parts(len(X), fields)
        variant = np.asarray(variant, dtype=int)
        order, pieces = [], []
        for v in np.unique(variant):
            rows = np.flatnonzero(variant == v)
            order.append(rows)
            pieces.append(self._evaluate(X[rows], detail=detail, parts=parts.take(rows),
                                         form=None if v < 0 else int(v)))
        if len(pieces) == 1:
            return pieces[0]
        return Evaluation.concat(pieces).take(np.argsort(np.concatenate(order), kind="stable"))

    def parts(self, n: int, fields: Mapping[str, NDArray]) -> Parts:
        """The :class:`Parts` of n rows from per-row case fields (their units)."""
        unknown = sorted(set(fields) - set(self.case_fields()))
        if unknown:
            raise ConfigError("case", unknown[0], "cannot vary per design; fields that can: "
                              f"{', '.join(self.case_fields()) or 'none'}")
        c = self.config

        def col(name: str) -> NDArray:
            return np.broadcast_to(np.asarray(fields[name], dtype=float), (n,))
        link = None
        if any(f in fields for f in LINK_FIELDS):
            link = np.tile(self.model.vendor_link, (n, 1))
            for i, name in enumerate(LINK_FIELDS):
                if name in fields:
                    link[:, i] = col(name) * (DEG if name.endswith("_deg") else MM)
        pre = None
        if "kc1_precompression_mm" in fields or "kc2_precompression_mm" in fields:
            pre = np.column_stack([
                col(f) if f in fields else np.full(n, float(getattr(c, f)))
                for f in ("kc1_precompression_mm", "kc2_precompression_mm")]) * MM
        profile = None
        if "cam_profile_error_mm" in fields:
            profile = self._profile_offset(col("cam_profile_error_mm"))
        return Parts(
            link=link, pre=pre,
            opening_k=col("opening_k_n_per_mm")[:, None] * N_PER_MM
            if "opening_k_n_per_mm" in fields else None,
            wipe_k=c.wipe_count * col("wipe_k_n_per_mm")[:, None] * N_PER_MM
            if "wipe_k_n_per_mm" in fields else None,
            friction_scale=col("cam_friction_nm") / c.cam_friction_nm
            if "cam_friction_nm" in fields and c.cam_friction_nm > 0 else None,
            efficiency_shift=col("efficiency") - c.efficiency if "efficiency" in fields
            else None,
            profile_rad=profile)

    def loads(self, parts: Parts | None) -> Loads:
        """The resisting loads, with the parts' spring rates and efficiency per row."""
        if parts is None or (parts.opening_k is None and parts.wipe_k is None
                             and parts.efficiency_shift is None):
            return self.load
        eff = (self.load.efficiency if parts.efficiency_shift is None
               else self.config.efficiency + parts.efficiency_shift)
        return replace(self.load,
                       opening_k=self.load.opening_k if parts.opening_k is None
                       else parts.opening_k,
                       wipe_k=self.load.wipe_k if parts.wipe_k is None else parts.wipe_k,
                       efficiency=eff)

    def _as_made(self, sets: MotionParameters, k: int, n: int, moved: NDArray,
                 parts: Parts | None) -> MotionParameters:
        """``k`` parameter sets for n designs (k n rows, set-major): each design's latch
        ``moved`` (n,) from the identified one moves every set's, and its parts scale the
        friction and shift the efficiency."""
        rows = sets.repeat(n)
        out = replace(rows, release_offset_rad=np.asarray(rows.release_offset_rad)
                      + np.tile(moved, k))
        if parts is None:
            return out
        if parts.friction_scale is not None:
            scale = np.tile(parts.friction_scale, k)
            out = replace(out, friction_nm=np.asarray(out.friction_nm) * scale,
                          release_friction_nm=None if out.release_friction_nm is None
                          else np.asarray(out.release_friction_nm) * scale)
        if parts.efficiency_shift is not None:
            shift = np.tile(parts.efficiency_shift, k)
            eff = (np.full(k * n, self.config.efficiency) if out.efficiency is None
                   else np.asarray(out.efficiency, dtype=float))
            out = replace(out, efficiency=np.where(eff < 1.0, eff + shift, eff))
        return out

    def motion(self, X: NDArray, link: NDArray | None = None, parts: Parts | None = None,
               form: int | None = None) -> ClosingMotion:
        """Closing dynamics of each row of ``X`` with the identified parameters
        (:mod:`camopt.cases.vcb.dynamics`), or model form ``form``'s fit, with each
        row's ``parts`` as made."""
        link = link if parts is None or parts.link is None else parts.link
        A, kc, link = self.designs(X, link)
        A = self._profiled(A, parts)
        if parts is None and form is None:
            params = replace(self.dynamics, release_offset_rad=self.release_offset(X))
            return closing_motion(self.model, A, kc, link, self.rod_offset, self.load,
                                  params, self.config.dynamics_steps)
        sets = self.forms[form or 0].nominal
        params = self._as_made(sets, 1, len(A), self._moved(X, len(A)), parts)
        return closing_motion(self.model, A, kc, link, self.rod_offset, self.loads(parts),
                              params, self.config.dynamics_steps,
                              pre=None if parts is None else parts.pre)

    def _moved(self, X: NDArray, n: int) -> NDArray:
        """How far each design's latch lies from the identified one (rad), (n,)."""
        return np.broadcast_to(self.release_offset(X) - self.config.release_offset_deg * DEG,
                               (n,))

    def _profile_offset(self, error_mm: NDArray | float) -> NDArray:
        """The follower's angle offset (rad) from a cam profile made ``error_mm`` oversize
        (a uniform offset along its normal): the roller sits that much further from O, so
        the follower angle at the base circle moves by the change of Eq 10's base angle,
        and (first order, docs/assumptions.md) by the same along the stroke."""
        m = self.model
        rp = m.rb + m.rf + self.config.node_clearance_mm * MM
        return np.asarray(cam.base_angle(m.l2, m.l6, rp + np.asarray(error_mm) * MM)
                          - cam.base_angle(m.l2, m.l6, rp), dtype=float)

    def _profiled(self, A: NDArray, parts: Parts | None) -> NDArray:
        """The follower law's coefficients with the cam profile's error (the row's, else
        the config's ``cam_profile_error_mm``) in a0."""
        if parts is not None and parts.profile_rad is not None:
            offset: NDArray | float = parts.profile_rad
        elif self.config.cam_profile_error_mm:
            offset = float(self._profile_offset(self.config.cam_profile_error_mm))
        else:
            return A
        A = A.copy()
        A[:, 0] += offset
        return A

    def as_set(self, X: NDArray, parts: Parts | None, form: int | None = None
               ) -> tuple[Parts | None, Setting | None]:
        """Each breaker of ``X`` (n rows, its ``parts`` as made) set at the factory, where
        the run has ``velocity_setting_bounds_m_s``: both closing springs' compressions in
        the opened state moved by the same nut travel d until the average closing velocity
        (what the breaker analyser reads) is the design's ``velocity_setting_m_s``. The
        analyser reads the breaker as it is, whichever of the form's parameter sets is
        true, so d is found under each set of form ``form`` (its fit and the band's other
        sets; form 0 for the case's own evaluation of a one-form band), and the breaker is
        judged under each set at that set's d. Returns the parts with the fit's set
        compressions and the :class:`Setting` (each set's compressions and needed d);
        without a setting ``(parts, None)``. d is clipped to +- ``preload_setting_range_mm``
        (the nut's end); the needed d is +inf where neither trial brings the contacts
        together (a stall at d = 0 and at the trial).

        d solves v(d)^2 = v_set^2 by one secant step from d = 0 and 2 mm: the kinetic
        energy at the touch is affine in d (the springs' energy is linear in their
        compression), so v^2 is nearly so, and the step leaves < 1e-3 m/s under every
        set, twenty times inside the analyser's 2 % (tests/cases/test_vcb_setting.py, on
        random designs and parts); a second step cost a third more."""
        if self.setting_column is None:
            return parts, None
        c, m = self.config, self.model
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        parts = Parts() if parts is None else parts
        base = parts.pre if parts.pre is not None else np.tile(
            [c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM], (n, 1))
        A, kc, link = self.designs(X, parts.link)
        A = self._profiled(A, parts)
        every = self.forms[form or 0]
        k = every.count + 1  # the fit, then the band's other sets of the form
        sets = _joined(every, c.efficiency)
        params = self._as_made(sets, k, n, self._moved(X, n), parts)
        A_rows, kc_rows, link_rows = (np.tile(a, (k, 1)) for a in (A, kc, link))
        loads, base_rows = self.loads(parts).tiled(k), np.tile(base, (k, 1))
        target = np.tile(X[:, self.setting_column], k) ** 2

        def squared_speed(d: NDArray) -> NDArray:
            ev = closing_events(m, A_rows, kc_rows, link_rows, self.rod_offset, loads,
                                params, c.dynamics_steps, pre=base_rows + d[:, None])
            return np.nan_to_num(ev.closing_velocity_avg, nan=0.0) ** 2

        d_a, d_b = np.zeros(k * n), np.full(k * n, SETTING_TRIAL_MM * MM)
        w_a, w_b = squared_speed(d_a), squared_speed(d_b)  # the breaker as made, and a trial
        with np.errstate(divide="ignore", invalid="ignore"):
            needed = d_b + (target - w_b) * (d_b - d_a) / (w_b - w_a)
        needed = np.where(np.isfinite(needed), needed, np.inf)
        reach = c.preload_setting_range_mm * MM
        pre = base_rows + np.clip(needed, -reach, reach)[:, None]
        return replace(parts, pre=pre[:n]), Setting(pre[n:] if k > 1 else None,
                                                    needed.reshape(k, n))

    def release_offset(self, X: NDArray) -> NDArray | float:
        """Where the closing latch holds the charged spring crank, past its dead centre,
        for each row of ``X`` (rad, (n,) or one for all): the design variable
        ``release_offset_deg`` when the run has it, else the step-1 design's (step 2) or
        the identified ``release_offset_deg``."""
        if self.release_column is None:
            return self.case_release
        return np.atleast_2d(np.asarray(X, dtype=float))[:, self.release_column]

    def motion_band(self, X: NDArray, nominal: ClosingMotion, link: NDArray | None = None,
                    parts: Parts | None = None, form: int | None = None,
                    member_pre: NDArray | None = None) -> MotionBand:
        """The closing of each row under every parameter set of ``dynamics_band`` (or of
        model form ``form``'s) and the nominal one (``nominal``, already computed): the
        extremes per design. One vectorised call over (sets x designs) rows;
        ``member_pre`` (sets x n, 2) m: each set's own closing-spring compressions (a
        breaker set at the factory under that set, :meth:`as_set`), else the parts'."""
        members, k = ((self.band, len(np.ravel(self.band.cam_kg_m2))) if self.band is not None
                      else (None, 0)) if form is None else (
            self.forms[form].members, self.forms[form].count)
        if members is None:
            return MotionBand.of(nominal)
        link = link if parts is None or parts.link is None else parts.link
        A, kc, link = self.designs(X, link)
        A = self._profiled(A, parts)
        n = len(A)
        # a design's latch moved from the identified offset moves every set's with it: the
        # sets keep their spread (what the ADAMS data leave open) about the design's
        sets = self._as_made(members, k, n, self._moved(X, n), parts)
        if member_pre is not None:  # each set's breaker set with its own nut travel
            events = closing_events(self.model, np.tile(A, (k, 1)), np.tile(kc, (k, 1)),
                                    np.tile(link, (k, 1)), self.rod_offset,
                                    self.loads(parts).tiled(k), sets,
                                    self.config.dynamics_steps, pre=member_pre)
        else:
            events = closing_events(self.model, A, kc, link, self.rod_offset,
                                    self.loads(parts), sets, self.config.dynamics_steps,
                                    sets=k, pre=None if parts is None else parts.pre)
        return MotionBand.of(nominal, events, k)

    def _evaluate(self, X: NDArray, detail: bool, parts: Parts | None = None,
                  form: int | None = None) -> Evaluation:
        if form is None and self.setting_column is not None and len(self.forms) > 1:
            return self._worst_form(X, detail, parts)
        parts, setting = self.as_set(X, parts, form)
        start = self._judge(X, detail, parts, setting, form)
        if not self.ages:
            return start
        aged_parts, aged_setting = self._aged(len(start.f), parts, setting)
        end = self._judge(X, detail, aged_parts, aged_setting, form)
        if "preload_setting" in self.constraint_names:  # the nut is set once, as built
            column = self.constraint_names.index("preload_setting")
            end = replace(end, g=end.g.copy())
            end.g[:, column] = start.g[:, column]
        return _worst_of([start, end], self.config.penalty, life_end=end)

    @property
    def ages(self) -> bool:
        """Whether a design is judged at the end of its life too (``life_friction_rise``
        or ``life_spring_relaxation``): only where the dynamics run, which it changes."""
        c = self.config
        return self.search_dynamics and (c.life_friction_rise > 0
                                         or c.life_spring_relaxation > 0)

    def _aged(self, n: int, parts: Parts | None, setting: Setting | None
              ) -> tuple[Parts, Setting | None]:
        """n breakers as built (``parts``, set at the factory by ``setting``) at the end of
        their life: every friction torque times 1 + ``life_friction_rise``, and the closing
        springs relaxed, their compression in the charged (opened) state times 1 -
        ``life_spring_relaxation`` (their force there that share lower); the setting's nut
        stays where the factory left it (each set's own compressions, likewise relaxed)."""
        c = self.config
        parts = Parts() if parts is None else parts
        keep, rise = 1.0 - c.life_spring_relaxation, 1.0 + c.life_friction_rise
        pre = parts.pre if parts.pre is not None else np.tile(
            [c.kc1_precompression_mm * MM, c.kc2_precompression_mm * MM], (n, 1))
        scale = (np.ones(n) if parts.friction_scale is None else parts.friction_scale) * rise
        aged = replace(parts, pre=pre * keep, friction_scale=scale)
        if setting is None or setting.member_pre is None:
            return aged, setting
        return aged, replace(setting, member_pre=setting.member_pre * keep)

    def _judge(self, X: NDArray, detail: bool, parts: Parts | None, setting: Setting | None,
               form: int | None) -> Evaluation:
        """Objective, constraints and metrics of n breakers with their ``parts`` (set at
        the factory by ``setting``, where the run sets them) under form ``form``'s sets."""
        c, m = self.config, self.model
        A, kc, link = self.designs(X, None if parts is None else parts.link)
        A = self._profiled(A, parts)
        pre = None if parts is None else parts.pre
        kin = m.kinematics(A, link, self.rod_offset)
        torque = m.closing_torque(kc, pre=pre)
        bal = m.balance(kin, kc, torque, self.loads(parts), pre)
        end = m.theta_c[-1]
        zeros = rate_zeros(A, end)  # where phi' = 0: dwell, and phi_max's candidates
        sigma_max = m.peak_stress(A, kin.follower, torque, zeros)
        motion = (self.motion(X, parts=parts, form=form) if (detail or self.search_dynamics)
                  else None)
        q = Terms(config=c, model=m, kin=kin, bal=bal, link=link,
                  phi_top=phi_max(A, end, zeros) / DEG,  # exact, not the sampled maximum
                  tau_max=hertz.max_shear_stress(sigma_max),  # Eq 31
                  motion=motion,
                  band=self.motion_band(X, motion, parts=parts, form=form,
                                        member_pre=None if setting is None
                                        else setting.member_pre)
                  if motion is not None else None,
                  setting=None if setting is None else setting.longest,
                  setting_velocity=None if setting is None else X[:, self.setting_column])
        G = np.column_stack([con.g(q) for con in self.constraints])
        G = np.where(np.isnan(G), np.inf, G)
        violation = np.clip(G, 0, None).sum(axis=1)
        base = np.abs(bal.surplus) if c.objective_form == "net" else m.abs_sum(bal)
        f = np.where(np.isfinite(base) & np.isfinite(violation),
                     base + c.penalty * violation, np.inf)  # Eq 39
        extras = {
            "phi_max_deg": q.phi_top, "sigma_max_mpa": sigma_max / MPA,
            "tau_max_mpa": q.tau_max / MPA,
            "driving_work_j": bal.driving, "resistant_work_j": bal.resistant,
            "surplus_work_j": bal.surplus, "rod_travel_mm": q.travel / MM,
        }
        if setting is not None:  # the nut travel the factory setting needs (+inf: none)
            extras["preload_setting_mm"] = setting.longest / MM  # the set needing most
            extras["preload_setting_fit_mm"] = setting.needed[0] / MM  # the form's fit
        if motion is not None:
            spread = q.spread
            closes = np.isfinite(spread.high["touch_time"])  # every set touches
            extras.update({
                # the identified parameters, and the band over the sets equally
                # consistent with the ADAMS data (dynamics_band): every velocity and time
                "closing_velocity_avg_m_s": motion.closing_velocity_avg,
                # undefined (NaN: "n/a, fails") where a set never brings the contacts
                # together; the constraints keep the band's finite stand-in (0 m/s) so a
                # search among stalling designs still sees how far it is
                "closing_velocity_low_m_s": np.where(closes, spread.velocity_low, np.nan),
                "closing_velocity_high_m_s": np.where(closes, spread.velocity_high, np.nan),
            })
            for name, (field, unit, scale) in BANDED.items():
                extras[name] = getattr(motion, field) / scale
                extras[name.replace(unit, "_low" + unit)] = spread.low[field] / scale
                extras[name.replace(unit, "_high" + unit)] = spread.high[field] / scale
            if c.latch_delay_ms is not None:  # the analyser's closing time: command to touch
                for end in ("", "_low", "_high"):
                    extras[f"closing_time{end}_ms"] = (c.latch_delay_ms
                                                       + extras[f"touch_time{end}_ms"])
            extras.update({
                "latch_kinetic_energy_j": motion.final_kinetic,
                "latch_kinetic_energy_low_j": spread.kinetic_low,
                "latch_kinetic_energy_high_j": spread.kinetic_high,
                "band_sets": np.full(len(spread.latched), float(spread.sets)),
                "band_sets_not_latched": spread.not_latched.astype(float),
                "cam_torque_min_nm": q.cam_torque_min,
                "lift_off_torque_ratio": q.lift_off_ratio,
                "release_torque_margin": motion.release_torque_ratio,
                "release_torque_margin_low": spread.release_ratio_low,
                # the cam's blow on the resting roller, the band's worst (Hertz estimate)
                "pickup_tau_mpa": q.pickup_tau / MPA,
                "latched": spread.latched.astype(float),  # at every end of the band
            })
        if detail:
            con = m.contact(kin.follower, torque)
            ends = m.output_angle(kin.ends()) / DEG
            dwell = follower_dwell(A, end, zeros) / DEG
            eq39 = m.abs_sum(bal)
            extras.update({
                **{f"a{k}": A[:, k] for k in range(A.shape[1])},
                "pressure_angle_max_deg": q.psi_max,
                # the least radius of the convex part, where a roller can undercut (the
                # profile radius is rho_p - rf: a concave pitch curve gives < -rf, never
                # an undercut, whatever its size); inf for a wholly concave profile
                "curvature_min_mm": np.min(np.where(con.curvature > -m.rf, con.curvature,
                                                    np.inf), axis=1) / MM,
                # unbounded where the follower dwells (Fn = T / arm, arm = 0 there)
                "normal_force_max_n": np.where(np.isfinite(dwell), np.inf,
                                               row_max(con.normal_force)),
                "follower_dwell_deg": dwell,
                "eq39_sum_n": eq39, "eq39_mean_n": eq39 / c.positions,
                "output_start_deg": ends[:, 0], "output_end_deg": ends[:, 1],
            })
        return Evaluation(f=f, g=G, extras=extras)

    def _worst_form(self, X: NDArray, detail: bool, parts: Parts | None) -> Evaluation:
        """The case's own verdict on a breaker set at the factory, over every kept model
        form: whichever form is the breaker's, the analyser reads it and the nut sets it,
        so each form is judged with its own setting (:meth:`as_set`), and the verdict is
        each constraint's worst form. The objective and the metrics are the identified
        form's (the first), the band's ends and counts over every form's sets: a lower end
        the least, a higher end the greatest, the setting the longest nut travel."""
        each = [self._evaluate(X, detail, parts, form=f) for f in range(len(self.forms))]
        return _worst_of(each, self.config.penalty, sum_counts=True)

    # ---- single-design output ----------------------------------------------------
    def _metrics_of(self, x: NDArray) -> dict[str, object]:
        ev = self.describe(x[None, :])
        out: dict[str, object] = {k: float(v[0]) for k, v in ev.extras.items()}
        ends = [float(ev.extras[k][0]) for k in ("output_start_deg", "output_end_deg")]
        del out["output_start_deg"], out["output_end_deg"]
        out["output_range_deg"] = [min(ends), max(ends)]
        out["feasible"] = float(ev.feasible[0])
        return out

    def metrics(self, x: NDArray) -> dict[str, object]:
        """Headline metrics of the design and, prefixed ``initial_``, of the vendor's."""
        out = self._metrics_of(np.asarray(x, dtype=float))
        vendor = self._metrics_of(self.vendor_x())
        out.update({f"initial_{k}": v for k, v in vendor.items()})
        out["initial_objective"] = float(self.evaluate(self.vendor_x()[None, :]).f[0])
        return out

    def curves(self, x: NDArray) -> dict[str, NDArray]:
        """Analysis curves of one design along the closing stroke (display units)."""
        m = self.model
        A, kc, link = self.designs(x)
        parts, _ = self.as_set(x, None)  # the breaker as set at the factory, if it is
        pre = None if parts is None else parts.pre
        kin = m.kinematics(A, link, self.rod_offset)
        torque = m.closing_torque(kc, pre=pre)
        bal = m.balance(kin, kc, torque, self.load, pre)
        con = m.contact(kin.follower, torque)
        xc, yc = cam.profile(con.xp, con.yp, con.dxp, con.dyp, m.rf)
        return {
            "cam_angle_deg": m.theta_c / DEG,
            "pitch_x_mm": con.xp[0] / MM, "pitch_y_mm": con.yp[0] / MM,
            "profile_x_mm": xc[0] / MM, "profile_y_mm": yc[0] / MM,
            "follower_angle_deg": kin.follower.phi[0] / DEG,
            "pressure_angle_deg": cam.pressure_angle(m.l2, m.l6, kin.follower)[0] / DEG,
            "curvature_mm": con.curvature[0] / MM,
            "normal_force_n": con.normal_force[0],
            "sigma_max_mpa": con.sigma[0] / MPA, "tau_max_mpa": con.tau[0] / MPA,
            "output_angle_deg": m.output_angle(kin)[0] / DEG,
            "rod_travel_mm": kin.s1[0] / MM,
            "fo_n": np.r_[np.nan, m.output_force(bal)[0]], "fr_n": np.r_[np.nan, bal.fr[0]],
            # works along the stroke as exact potential differences
            "driving_work_j": m.closing_energy(kc, m.spring_ext, pre)[0, 0]
            - m.closing_energy(kc, m.spring_ext, pre)[0],
            "resistant_work_j": self.load.resistant_energy(kin.s1[0]),
            **self._motion_curves(x, parts),
        }

    def _motion_curves(self, x: NDArray, parts: Parts | None = None) -> dict[str, NDArray]:
        """Closing dynamics of one design (its ``parts``) against time (display units)."""
        mo = self.motion(x, parts=parts)
        shown = np.isfinite(mo.time[0])
        return {
            "time_ms": mo.time[0, shown] * TO_MS,
            "dyn_cam_angle_deg": mo.theta_c[shown] / DEG,
            "dyn_rod_travel_mm": mo.rod[0, shown] / MM,
            "dyn_rod_velocity_m_s": mo.rod_velocity[0, shown],
            "dyn_contact_travel_mm": mo.contact[0, shown] / MM,
            "dyn_contact_velocity_m_s": mo.contact_velocity[0, shown],
            "dyn_cam_torque_nm": mo.cam_torque[0, shown],
        }

    def analysis(self, x: NDArray) -> dict[str, NDArray]:
        """Curves of the design and of the vendor's initial design (``initial_`` prefix)."""
        out = self.curves(np.asarray(x, dtype=float))
        out.update({f"initial_{k}": v for k, v in self.curves(self.vendor_x()).items()})
        return out
