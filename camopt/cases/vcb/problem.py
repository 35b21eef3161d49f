"""12 kV VCB closing mechanism as an optimisation problem: step 1 (cam + closing springs)
or step 2 (four-bar), Kang, Huang & Yang (2023), Eqs 37-43."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from camopt.cases.vcb import life
from camopt.cases.vcb.band import MotionBand, band_motion, merged_band, merged_motion
from camopt.cases.vcb.band_sets import band_rows, form_sets, identified, joined, parameter_sets
from camopt.cases.vcb.config import CamDesign, VcbConfig
from camopt.cases.vcb.constraints import CONSTRAINTS, Terms
from camopt.cases.vcb.dynamics import ClosingMotion, closing_motion
from camopt.cases.vcb.forms import link_mass_rows
from camopt.cases.vcb.metrics import (
    design_metrics,
    motion_curves,
    motion_metrics,
    setting_metrics,
    shape_metrics,
    stroke_curves,
)
from camopt.cases.vcb.model import Loads, VcbModel, phi_max, rate_zeros
from camopt.cases.vcb.motion import compiled
from camopt.cases.vcb.parts import (
    LINK_FIELDS,
    PART_FIELDS,
    Parts,
    as_made,
    case_pre,
    loads_of,
    parts_of,
    profiled,
)
from camopt.cases.vcb.setting import Setting, set_at_factory
from camopt.cases.vcb.verdict import over_life, worst_of
from camopt.core.capabilities import HasVariants, VariesCase
from camopt.core.problem import Evaluation, ObjectiveFloor, Problem, Variable
from camopt.errors import ConfigError
from camopt.mechanics import Floats, Ints, hertz
from camopt.units import DEG, MM, MPA, N_PER_MM, TO_N_PER_MM


class VcbProblem(Problem, VariesCase, HasVariants):
    """Step 1 (cam + springs) or step 2 (four-bar) of the VCB design; minimise Eq 39."""

    batch_rows = 512
    """Rows per call of a chunked evaluation (:mod:`camopt.core.batch`): robust draws
    cost 8 % less per row at 512 than at 256 (docs/design.md); per model form where the
    rows mix forms."""
    mixed_variants = True
    """:meth:`describe_variants` judges rows of every model form in one call (the statics
    and the verdict once, the closing per form): chunked together, not per form."""

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
        self.dynamics = identified(c)
        band = band_rows(c)
        band = np.vstack([band, link_mass_rows(band, c)])  # the links' own masses
        self.band = parameter_sets(band, c) if len(band) else None
        self.forms = form_sets(c, band, self.dynamics)
        self.search_dynamics = (c.closing_velocity_m_s is not None or c.require_latch
                                or c.forbid_lift_off or self.setting_column is not None)

    def variants(self) -> tuple[str, ...]:
        """The kept model forms the band holds (docs/tolerance.md, "Model forms in the
        draws"): a design drawn in form ``i`` is judged under that form's sets alone."""
        return tuple(f.name for f in self.forms) if len(self.forms) > 1 else ()

    def _cam(self, d: CamDesign) -> tuple[Floats, Floats]:
        a0 = self.model.phi0() if d.a0 is None else d.a0
        coefficients = np.array([a0, d.a1, d.a2, d.a3, d.a4, d.a5])
        degree = 5 if d.a5 else 4 if d.a4 else 3  # the paper's cubic unless a design has more
        return coefficients[:degree + 1], np.array([d.kc1_n_per_mm, d.kc2_n_per_mm]) * N_PER_MM

    def designs(self, X: Floats, link: Floats | None = None
                ) -> tuple[Floats, Floats, Floats]:
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

    def vendor_x(self) -> Floats:
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

    def evaluate(self, X: Floats) -> Evaluation:
        """Objective and constraints, with the metrics the search needs (hot path)."""
        return self._evaluate(X, detail=False)

    def describe(self, X: Floats) -> Evaluation:
        """As :meth:`evaluate`, plus descriptive metrics (pressure angle, curvature,
        normal force, output range) for tables and reports."""
        return self._evaluate(X, detail=True)

    def case_fields(self) -> tuple[str, ...]:
        """Step 1: the linkage fields (the four-bar is fixed there, so its made lengths
        may vary per design); step 2 varies the linkage as design variables. Both: the
        parts (:data:`PART_FIELDS`)."""
        return (LINK_FIELDS if self.config.step == "cam" else ()) + PART_FIELDS

    def describe_with(self, X: Floats, fields: Mapping[str, Floats]) -> Evaluation:
        """As :meth:`describe`, with the named fields (mm, deg, N/mm, N m) per row: the
        linkage array the kinematics already takes per design, and the parts
        (:class:`Parts`); the loads' preloads stay those of the config's linkage (they
        describe the breaker, not the parts made)."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        return self._evaluate(X, detail=True, parts=self.parts(len(X), fields))

    def describe_variants(self, X: Floats, fields: Mapping[str, Floats], variant: Ints,
                          detail: bool = True) -> Evaluation:
        """As :meth:`describe_with`, each row judged under the sets of its model form
        ``variants()[variant[i]]`` alone (-1: every form, the case's own evaluation);
        ``detail=False``: :meth:`evaluate`'s metrics, not the descriptive ones."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        parts = self.parts(len(X), fields)
        variant = np.asarray(variant, dtype=int)
        kinds = np.unique(variant)
        if (len(kinds) > 1 and kinds[0] >= 0 and self.setting_column is None
                and not self.ages):
            # one call over every form's rows: only the closing differs by form (no
            # factory setting, no end of life to judge per form)
            return self._judge(X, detail, parts, None, variant)
        order, pieces = [], []
        for v in np.unique(variant):
            rows = np.flatnonzero(variant == v)
            order.append(rows)
            pieces.append(self._evaluate(X[rows], detail=detail, parts=parts.take(rows),
                                         form=None if v < 0 else int(v)))
        if len(pieces) == 1:
            return pieces[0]
        return Evaluation.concat(pieces).take(np.argsort(np.concatenate(order), kind="stable"))

    def parts(self, n: int, fields: Mapping[str, Floats]) -> Parts:
        """The :class:`Parts` of n rows from per-row case fields (their units)."""
        return parts_of(n, fields, self.case_fields(), self.config, self.model)

    def loads(self, parts: Parts | None) -> Loads:
        """The resisting loads, with the parts' spring rates and efficiency per row."""
        return loads_of(self.load, self.config.efficiency, parts)

    def motion(self, X: Floats, link: Floats | None = None, parts: Parts | None = None,
               form: int | None = None) -> ClosingMotion:
        """Closing dynamics of each row of ``X`` with the identified parameters
        (:mod:`camopt.cases.vcb.dynamics`), or model form ``form``'s fit, with each
        row's ``parts`` as made."""
        link = link if parts is None or parts.link is None else parts.link
        A, kc, link = self.designs(X, link)
        A = self.profiled(A, parts)
        if parts is None and form is None:
            params = replace(self.dynamics, release_offset_rad=self.release_offset(X))
            return closing_motion(self.model, A, kc, link, self.rod_offset, self.load,
                                  params, self.config.dynamics_steps)
        sets = self.forms[form or 0].nominal
        params = as_made(sets, 1, len(A), self._moved(X, len(A)), parts, self.config.efficiency)
        return closing_motion(self.model, A, kc, link, self.rod_offset, self.loads(parts),
                              params, self.config.dynamics_steps,
                              pre=None if parts is None else parts.pre)

    def _moved(self, X: Floats, n: int) -> Floats:
        """How far each design's latch lies from the identified one (rad), (n,)."""
        return np.broadcast_to(self.release_offset(X) - self.config.release_offset_deg * DEG,
                               (n,))

    def profiled(self, A: Floats, parts: Parts | None) -> Floats:
        """The follower law ``A`` with the cam profile's error (the row's or the case's)."""
        return profiled(A, parts, self.model, self.config)

    def as_set(self, X: Floats, parts: Parts | None, form: int | None = None
               ) -> tuple[Parts | None, Setting | None]:
        """Each breaker of ``X`` (n rows, its ``parts`` as made) set at the factory, where
        the run has ``velocity_setting_bounds_m_s`` (:mod:`camopt.cases.vcb.setting`).
        The analyser reads the breaker as it is, whichever of the form's parameter sets
        is true, so the nut travel is found under each set of form ``form`` (its fit and
        the band's other sets; form 0 for the case's own evaluation of a one-form band),
        and the breaker is judged under each set at that set's travel. Returns the parts
        with the fit's set compressions and the :class:`Setting` (each set's compressions
        and needed travel); without a setting ``(parts, None)``."""
        if self.setting_column is None:
            return parts, None
        c = self.config
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        parts = Parts() if parts is None else parts
        A, kc, link = self.designs(X, parts.link)
        every = self.forms[form or 0]
        k = every.count + 1  # the fit, then the band's other sets of the form
        params = as_made(joined(every, c.efficiency), k, n, self._moved(X, n), parts,
                         c.efficiency)
        pre, setting = set_at_factory(
            self.model, c, self.profiled(A, parts), kc, link, self.rod_offset,
            self.loads(parts), params, parts.pre if parts.pre is not None else case_pre(c, n),
            X[:, self.setting_column], k)
        return replace(parts, pre=pre), setting

    def release_offset(self, X: Floats) -> Floats | float:
        """Where the closing latch holds the charged spring crank, past its dead centre,
        for each row of ``X`` (rad, (n,) or one for all): the design variable
        ``release_offset_deg`` when the run has it, else the step-1 design's (step 2) or
        the identified ``release_offset_deg``."""
        if self.release_column is None:
            return self.case_release
        return np.atleast_2d(np.asarray(X, dtype=float))[:, self.release_column]

    def motion_band(self, X: Floats, nominal: ClosingMotion, link: Floats | None = None,
                    parts: Parts | None = None, form: int | None = None,
                    member_pre: Floats | None = None) -> MotionBand:
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
        A = self.profiled(A, parts)
        n = len(A)
        # a design's latch moved from the identified offset moves every set's with it: the
        # sets keep their spread (what the ADAMS data leave open) about the design's
        sets = as_made(members, k, n, self._moved(X, n), parts, self.config.efficiency)
        return band_motion(self.model, nominal, A, kc, link, self.rod_offset,
                           self.loads(parts), sets, k, self.config.dynamics_steps,
                           pre=None if parts is None else parts.pre, member_pre=member_pre)

    def _evaluate(self, X: Floats, detail: bool, parts: Parts | None = None,
                  form: int | None = None) -> Evaluation:
        if form is None and self.setting_column is not None and len(self.forms) > 1:
            return self._worst_form(X, detail, parts)
        parts, setting = self.as_set(X, parts, form)
        start = self._judge(X, detail, parts, setting, form)
        if not self.ages:
            return start
        aged_parts, aged_setting = life.aged(self.config, len(start.f), parts, setting)
        end = self._judge(X, detail, aged_parts, aged_setting, form)
        return over_life(start, end, self.constraint_names, self.config.penalty)

    @property
    def ages(self) -> bool:
        """Whether a design is judged at the end of its life too (:mod:`.life`)."""
        return life.ages(self.config, self.search_dynamics)

    def _judge(self, X: Floats, detail: bool, parts: Parts | None, setting: Setting | None,
               form: int | Ints | None) -> Evaluation:
        """Objective, constraints and metrics of n breakers with their ``parts`` (set at
        the factory by ``setting``, where the run sets them) under form ``form``'s sets,
        or each row under its own form (``form`` (n,) ints; no setting): the statics and
        the verdict once over every row, the closing per form (:meth:`_form_motions`)."""
        c, m = self.config, self.model
        A, kc, link = self.designs(X, None if parts is None else parts.link)
        A = self.profiled(A, parts)
        pre = None if parts is None else parts.pre
        kernel = compiled()  # the statics on the nodes in compiled passes, where numba is
        kin = m.kinematics(A, link, self.rod_offset, kernel=kernel)
        torque = m.closing_torque(kc, pre=pre)
        bal = m.balance(kin, kc, torque, self.loads(parts), pre)
        end = m.theta_c[-1]
        zeros = rate_zeros(A, end)  # where phi' = 0: dwell, and phi_max's candidates
        sigma_max = m.peak_stress(A, kin.follower, torque, zeros, kernel)
        motion = band = None
        if detail or self.search_dynamics:
            if isinstance(form, np.ndarray):
                motion, band = self._form_motions(X, parts, form)
            else:
                motion = self.motion(X, parts=parts, form=form)
                band = self.motion_band(X, motion, parts=parts, form=form,
                                        member_pre=None if setting is None
                                        else setting.member_pre)
        q = Terms(config=c, model=m, kin=kin, bal=bal, link=link,
                  phi_top=phi_max(A, end, zeros) / DEG,  # exact, not the sampled maximum
                  tau_max=hertz.max_shear_stress(sigma_max),  # Eq 31
                  motion=motion, band=band,
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
        if setting is not None:
            extras.update(setting_metrics(setting))
        if motion is not None:
            extras.update(motion_metrics(motion, q, c.latch_delay_ms))
        if detail:
            extras.update(shape_metrics(q, A, torque, zeros))
        return Evaluation(f=f, g=G, extras=extras)

    def _form_motions(self, X: Floats, parts: Parts | None, form: Ints
                      ) -> tuple[ClosingMotion, MotionBand]:
        """The nominal closing and its band of each row of ``X`` under its own model form
        ``form`` (n,): each form's rows in one call of :meth:`motion` and of
        :meth:`motion_band` (the numbers of a call per form), put back in row order."""
        groups, motions, bands = [], [], []
        for f in np.unique(form):
            rows = np.flatnonzero(form == f)
            part = None if parts is None else parts.take(rows)
            motion = self.motion(X[rows], parts=part, form=int(f))
            groups.append(rows)
            motions.append(motion)
            bands.append(self.motion_band(X[rows], motion, parts=part, form=int(f)))
        return merged_motion(motions, groups, len(X)), merged_band(bands, groups, len(X))

    def _worst_form(self, X: Floats, detail: bool, parts: Parts | None) -> Evaluation:
        """The case's own verdict on a breaker set at the factory, over every kept model
        form: whichever form is the breaker's, the analyser reads it and the nut sets it,
        so each form is judged with its own setting (:meth:`as_set`), and the verdict is
        each constraint's worst form. The objective and the metrics are the identified
        form's (the first), the band's ends and counts over every form's sets: a lower end
        the least, a higher end the greatest, the setting the longest nut travel."""
        each = [self._evaluate(X, detail, parts, form=f) for f in range(len(self.forms))]
        return worst_of(each, self.config.penalty, sum_counts=True)

    # ---- single-design output ----------------------------------------------------
    def _metrics_of(self, x: Floats) -> dict[str, object]:
        return design_metrics(self.describe(x[None, :]))

    def metrics(self, x: Floats) -> dict[str, object]:
        """Headline metrics of the design and, prefixed ``initial_``, of the vendor's."""
        out = self._metrics_of(np.asarray(x, dtype=float))
        vendor = self._metrics_of(self.vendor_x())
        out.update({f"initial_{k}": v for k, v in vendor.items()})
        out["initial_objective"] = float(self.evaluate(self.vendor_x()[None, :]).f[0])
        return out

    def curves(self, x: Floats) -> dict[str, Floats]:
        """Analysis curves of one design along the closing stroke and against time
        (display units; :func:`stroke_curves`, :func:`motion_curves`), the breaker as set
        at the factory where the run sets it."""
        A, kc, link = self.designs(x)
        parts, _ = self.as_set(x, None)
        pre = None if parts is None else parts.pre
        return {**stroke_curves(self.model, A, kc, link, self.rod_offset, self.load, pre),
                **motion_curves(self.motion(x, parts=parts))}

    def analysis(self, x: Floats) -> dict[str, Floats]:
        """Curves of the design and of the vendor's initial design (``initial_`` prefix)."""
        out = self.curves(np.asarray(x, dtype=float))
        out.update({f"initial_{k}": v for k, v in self.curves(self.vendor_x()).items()})
        return out
