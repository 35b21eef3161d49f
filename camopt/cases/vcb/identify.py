"""Identification of the VCB parameters the paper omits, from the numbers it reports.

Unknowns: the rod arm's angle on the output link, the opening spring's arm ratio
r7/r6 and the interrupters' free-contact force. Evidence (Kang 2023): rod travel
18 mm (Sec 3.2), the vendor design's objective 1.75e3 and the Table 6 optimum's
near-zero objective (Table 6). Least squares of the normalised residuals, solved
by any of the project's generic solvers; vectorised over candidate parameters.

The dynamics' parameters (J_cam, m_rod, m_c, the closing crank's release offset, the
friction torque at the cam shaft) from the vendor design's seven ADAMS data (Sec 3.2,
Table 4): :class:`VcbDynamicsIdentification`, with the leave-one-out validation
(:func:`leave_one_out`) and the parameter sets equally consistent with the data
(:func:`consistent_band`) that give every prediction its band; the Jacobian's
identifiability is :mod:`camopt.core.fitting`'s.

``scipy.optimize`` is imported inside :func:`fit` only: the case's Problem is built by
``validate``, which must not load it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from camopt.cases.vcb.dynamics import MotionParameters, opening_motion
from camopt.cases.vcb.forms import BAND_COLUMNS, FORMS, INERTIAS, ModelForm, get_form
from camopt.cases.vcb.identify_config import VcbDynamicsIdentifyConfig, VcbIdentifyConfig
from camopt.cases.vcb.model import VcbModel
from camopt.core.fitting import Identifiability, central_jacobian
from camopt.core.fitting import identifiability as core_identifiability
from camopt.core.problem import Evaluation, Problem, Variable
from camopt.mechanics import Floats
from camopt.units import DEG, MM, MS, N_PER_MM


class VcbIdentification(Problem):
    """Fit (rod offset, opening arm ratio, free-contact force) to the paper's evidence."""

    objective_name = "misfit"
    constraint_names = ()

    def __init__(self, config: VcbIdentifyConfig) -> None:
        self.config = c = config
        self.model = m = VcbModel(config)
        b = c.rod_offset_bounds_deg, c.opening_arm_bounds, c.free_contact_bounds_n
        self.variables = (
            Variable("rod_arm_offset_deg", b[0].lower * DEG, b[0].upper * DEG, 1 / DEG),
            Variable("opening_arm_ratio", b[1].lower, b[1].upper),
            Variable("free_contact_force_n", b[2].lower, b[2].upper),
        )
        d = c.paper_optimum
        self.A = np.array([m.vendor_a, [m.phi0(), d.a1, d.a2, d.a3]])
        self.kc = np.array([[c.kc1_n_per_mm, c.kc2_n_per_mm],
                            [d.kc1_n_per_mm, d.kc2_n_per_mm]]) * N_PER_MM

    def evaluate(self, X: Floats) -> Evaluation:
        """Squared normalised misfit of (rod travel, vendor surplus, optimum surplus) to
        the paper's evidence, with each residual and work as extras; no constraints."""
        c, m = self.config, self.model
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        offset, arm, free = (X[:, i : i + 1] for i in range(3))
        link = np.tile(m.vendor_link, (n, 1))
        out = {}
        travel = None
        for label, A, kc in zip(("vendor", "optimum"), self.A, self.kc):
            kin = m.kinematics(np.tile(A, (n, 1)), link, offset)
            if travel is None:
                travel = kin.s1[:, -1:]
            loads = m.loads(travel, arm, free)
            kcs = np.tile(kc, (n, 1))
            bal = m.balance(kin, kcs, m.closing_torque(kcs), loads)
            out[label] = bal
        assert travel is not None
        r_travel = (travel[:, 0] - c.rod_travel_mm * MM) / (c.rod_travel_tolerance_mm * MM)
        r_vendor = ((out["vendor"].surplus - c.vendor_surplus_target_j)
                    / out["vendor"].driving)
        r_optimum = ((out["optimum"].surplus - c.optimum_surplus_target_j)
                     / out["optimum"].driving)
        f = r_travel**2 + r_vendor**2 + r_optimum**2
        extras = {
            "rod_travel_mm": travel[:, 0] / MM,
            "vendor_surplus_j": out["vendor"].surplus,
            "optimum_surplus_j": out["optimum"].surplus,
            "vendor_driving_work_j": out["vendor"].driving,
            "vendor_resistant_work_j": out["vendor"].resistant,
            "optimum_resistant_work_j": out["optimum"].resistant,
            "misfit_travel": r_travel, "misfit_vendor": r_vendor, "misfit_optimum": r_optimum,
        }
        return Evaluation(f=np.where(np.isfinite(f), f, np.inf), g=np.zeros((n, 0)),
                          extras=extras)


@dataclass(frozen=True)
class Datum:
    """One ADAMS datum of the vendor design (Kang 2023 Sec 3.2): its name, the short
    ``key`` of its residual, the config field holding its value, the unit, and whether it
    is an upper bound only (the simulation's end time) rather than an event."""

    name: str
    key: str
    field: str
    unit: str
    upper_bound_only: bool = False


DATA = (
    Datum("departure_time_ms", "departure_time", "departure_time_target_ms", "ms"),
    Datum("open_time_ms", "open_time", "open_time_target_ms", "ms"),
    Datum("opening_velocity_avg_m_s", "opening_velocity", "opening_velocity_target_m_s", "m/s"),
    Datum("cam_contact_time_ms", "cam_contact_time", "cam_contact_time_target_ms", "ms"),
    Datum("touch_time_ms", "touch_time", "touch_time_target_ms", "ms"),
    Datum("closing_velocity_avg_m_s", "closing_velocity", "closing_velocity_target_m_s", "m/s"),
    Datum("release_to_latch_ms", "closing_time", "closed_by_ms", "ms", upper_bound_only=True),
)
PARAMETERS = FORMS[0].parameters
"""The shipped form's parameters (J_cam kg m^2, m_rod kg, m_c kg, release offset deg,
friction torque N m)."""


def motion_parameters(X: Floats, follower_kg_m2: float) -> MotionParameters:
    """Rows of the shipped form's :data:`PARAMETERS` as MotionParameters."""
    return FORMS[0].motion_parameters(X, follower_kg_m2)


class VcbDynamicsIdentification(Problem):
    """Least squares of the vendor design's seven ADAMS data (Kang 2023 Sec 3.2, Table 4):
    contact separation 3.2 ms, opening complete 7 ms, opening velocity 2.5 m/s, cam meets
    roller 13.1 ms, contacts collide 27.8 ms, closing velocity 1.71 m/s, and closed by the
    simulation's end at 45 ms (one-sided) for five parameters: J_cam, m_rod, m_c, the
    release offset and the friction torque at the cam shaft. Residuals are relative
    (prediction / datum - 1); every prediction, residual (%), ``n_data``,
    ``n_parameters`` and ``max_residual_pct`` are extras."""

    objective_name = "misfit"
    constraint_names = ()

    def __init__(self, config: VcbDynamicsIdentifyConfig) -> None:
        self.config = c = config
        self.model = m = VcbModel(config)
        self.form = get_form(c.model_form)
        self.variables = self.form.variables(c)
        self.A = m.vendor_a[None, :]
        self.kc = np.array([[c.kc1_n_per_mm, c.kc2_n_per_mm]]) * N_PER_MM
        self.rod_offset = c.rod_arm_offset_deg * DEG
        vendor = m.kinematics(self.A, m.vendor_link[None, :], self.rod_offset)
        self.travel = float(vendor.s1[0, -1])
        self.load = m.loads(self.travel, c.opening_arm_ratio, c.free_contact_force_n)
        self.targets = np.array([getattr(c, d.field) for d in DATA])
        self.one_sided = np.array([d.upper_bound_only for d in DATA])

    def predict(self, X: Floats) -> Floats:
        """The seven simulated data of the vendor design for each parameter row of ``X``
        (n, p), (n, 7) in the units of :data:`DATA`."""
        c, m = self.config, self.model
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n = len(X)
        params = self.form.motion_parameters(X, c.follower_inertia_kg_m2)
        A, link = np.tile(self.A, (n, 1)), np.tile(m.vendor_link, (n, 1))
        closing = self.form.closing(m, A, np.tile(self.kc, (n, 1)), link, self.rod_offset,
                                    self.load, X, c.follower_inertia_kg_m2, c.dynamics_steps)
        opening = opening_motion(m, A, link, self.rod_offset, self.load, params)
        return np.column_stack([
            opening.departure_time / MS, opening.open_time / MS,
            opening.opening_velocity_avg, closing.cam_contact_time / MS,
            closing.touch_time / MS, closing.closing_velocity_avg,
            closing.closing_time / MS])

    def residuals(self, predictions: Floats) -> Floats:
        """Relative residuals (n, 7): prediction / datum - 1; the one-sided datum counts
        only when exceeded; NaN (a design that never gets there) as 10 (1,000 %)."""
        r = predictions / self.targets - 1
        r = np.where(self.one_sided, np.maximum(r, 0.0), r)
        return np.where(np.isfinite(r), r, 10.0)

    def evaluate(self, X: Floats) -> Evaluation:
        """Sum of squared relative residuals; predictions and residuals as extras."""
        X = np.atleast_2d(np.asarray(X, dtype=float))
        y = self.predict(X)
        r = self.residuals(y)
        extras: dict[str, Floats] = {}
        for i, d in enumerate(DATA):
            extras[d.name] = y[:, i]
            extras[f"residual_{d.key}_pct"] = 100 * r[:, i]
        extras["max_residual_pct"] = 100 * np.max(np.abs(r), axis=1)
        extras["n_data"] = np.full(len(X), float(len(DATA)))
        extras["n_parameters"] = np.full(len(X), float(len(self.variables)))
        return Evaluation(f=np.sum(r * r, axis=1), g=np.zeros((len(X), 0)), extras=extras)

    def findings(self, x: Floats) -> dict[str, object]:
        """Every model form fitted on the same data from the run's best ``x`` (p,), which
        are kept (:func:`fit_forms`), and the identifiability of the run's form at ``x``
        (:func:`identifiability`) and the band of parameter sets over the kept forms
        (:func:`data_band`): ``show --format json``'s ``model_forms``, ``band`` and
        ``identifiability``."""
        x = np.asarray(x, dtype=float)
        fits = fit_forms(self.config, dict(zip(self.names, x)))
        return {"model_forms": [f.to_json() for f in fits],
                "band": data_band(self.config, fits),
                "identifiability": {"form": self.form.name,
                                    **identifiability(self, x).to_json()}}


def fit(problem: VcbDynamicsIdentification, start: Floats, drop: int | None = None
        ) -> Floats:
    """Least squares (scipy, trust region in log parameters, within the bounds) of the
    data, without datum ``drop`` when given; returns the parameters (p,)."""
    from scipy.optimize import least_squares  # lazy: module docstring

    keep = np.array([i != drop for i in range(len(DATA))])
    lower = np.log(np.maximum([v.lower for v in problem.variables], 1e-9))
    upper = np.log([v.upper for v in problem.variables])

    def residuals(q: Floats) -> Floats:
        r: Floats = problem.residuals(problem.predict(np.exp(q)[None, :]))[0, keep]
        return r

    def jacobian(q: Floats) -> Floats:
        J: Floats = log_jacobian(problem, np.exp(q))[keep]
        return J

    # a start on a zero lower bound (a mass the search drove to 0) starts at the log
    # bound's 1e-9 instead: log(0) is no start
    x0 = np.clip(np.log(np.maximum(start, np.exp(lower))), lower + 1e-9, upper - 1e-9)
    x: Floats = np.exp(least_squares(residuals, x0, jac=jacobian, bounds=(lower, upper),
                                     x_scale=1.0).x)
    return x


def log_jacobian(problem: VcbDynamicsIdentification, x: Floats, step: float = 1e-6
                 ) -> Floats:
    """d residual / d log parameter at ``x`` (p,), (7, p), by central differences of
    ``step`` in every log parameter (:func:`camopt.core.fitting.central_jacobian`), all
    2 p simulations in one vectorised call. A parameter at zero (a lower bound of 0) is
    taken at 1e-9, the log bounds' floor."""
    return central_jacobian(lambda Q: problem.residuals(problem.predict(np.exp(Q))),
                            np.log(np.maximum(x, 1e-9)), step)


def leave_one_out(problem: VcbDynamicsIdentification, best: Floats
                  ) -> list[dict[str, object]]:
    """Fit without each datum in turn and predict it: one row per datum with its value,
    the prediction of the fit without it and that residual (%), and the largest residual
    of the fit on the remaining data (%)."""
    rows = []
    for i, d in enumerate(DATA):
        x = fit(problem, best, drop=i)
        y = problem.predict(x[None, :])
        r = problem.residuals(y)[0]
        rows.append({"datum": d.name, "value": float(problem.targets[i]),
                     "predicted": float(y[0, i]), "residual_pct": 100 * float(r[i]),
                     "max_residual_others_pct": 100 * float(np.max(np.abs(np.delete(r, i)))),
                     **{name: float(v) for name, v in zip(problem.names, x)}})
    return rows


def data_tolerance(config: VcbDynamicsIdentifyConfig, widened: float) -> Floats:
    """How far each simulated datum may lie from the datum itself, (7,) in the data's
    units: the reading error (``velocity_reading_pct`` of a velocity, ``time_reading_ms``
    of a time), widened to ``widened`` (a fraction: the largest residual of the kept
    forms' fits) of the datum where that is larger, since no kept form meets the data
    closer than its own residuals."""
    targets = np.array([getattr(config, d.field) for d in DATA])
    reading = np.array([config.velocity_reading_pct / 100 * v if d.unit == "m/s"
                        else config.time_reading_ms for d, v in zip(DATA, targets)])
    tolerance: Floats = np.maximum(reading, widened * np.abs(targets))
    return tolerance


def consistent_band(problem: VcbDynamicsIdentification, best: Floats, tolerance: Floats,
                    samples: int, rng: np.random.Generator) -> Floats:
    """Parameter sets of ``problem``'s form that predict every ADAMS datum within
    ``tolerance`` (7,) of the datum itself (the one-sided closing time only below its
    bound plus the tolerance), (k, p) with ``best`` (p,) first: from ``samples``
    log-uniform draws in a box around ``best`` sized by the linearised sensitivities,
    the extremes of each parameter among the consistent draws (k <= 2 p + 1)."""
    y0 = problem.predict(best[None, :])[0]
    # box half-widths: how far each parameter alone may move before some datum moves by
    # its tolerance (linearised), times 3 so that combined moves are sampled too
    h = 1e-3
    steps = np.exp(np.log(best)[None, :] + h * np.eye(len(best)))
    slope = np.abs(problem.predict(steps) - y0) / h  # (p, 7): d datum / d log parameter
    event = ~problem.one_sided
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(slope[:, event] > 0, tolerance[event] / slope[:, event], np.inf)
    half = np.minimum(3 * np.min(ratio, axis=1), 1.0)
    lower = np.log(np.maximum([v.lower for v in problem.variables], 1e-9))
    upper = np.log([v.upper for v in problem.variables])
    q = np.clip(np.log(best) + rng.uniform(-1, 1, (samples, len(best))) * half, lower, upper)
    y = problem.predict(np.exp(q))
    ok = np.all(np.abs(y - problem.targets)[:, event] <= tolerance[event], axis=1) & np.all(
        (y <= problem.targets + tolerance)[:, ~event], axis=1)
    members = np.exp(q[ok])
    if len(members) == 0:
        return best[None, :]
    pick = np.unique(np.r_[np.argmin(members, axis=0), np.argmax(members, axis=0)])
    return np.vstack([best[None, :], members[pick]])


def band_rows(form: ModelForm, X: Floats, config: VcbDynamicsIdentifyConfig) -> Floats:
    """Parameter rows ``X`` (k, p) of ``form`` as ``dynamics_band`` rows (k, 8)
    (:meth:`~camopt.cases.vcb.forms.ModelForm.band_rows`)."""
    return form.band_rows(X, config)


def data_band(config: VcbDynamicsIdentifyConfig, fits: tuple[FormFit, ...]
              ) -> dict[str, object]:
    """The band of every VCB prediction: for each kept form, the parameter sets consistent
    with the data within :func:`data_tolerance` widened by the kept forms' largest
    residual (:func:`consistent_band`, ``band_samples`` draws from a generator seeded by
    ``band_seed`` and spawned per form), as ``dynamics_band`` rows (``sets``), with the
    tolerance, each form's count and the range of each datum's prediction over the sets
    beside the datum and its reading-error interval."""
    kept = [f for f in fits if f.kept]
    widened = max(f.max_residual_pct for f in kept) / 100
    tolerance = data_tolerance(config, widened)
    rngs = [np.random.default_rng(s)
            for s in np.random.SeedSequence(config.band_seed).spawn(len(FORMS))]
    rows, counts, predictions = [], {}, []
    for f in kept:
        problem = VcbDynamicsIdentification(config.model_copy(update={"model_form": f.form.name}))
        X = consistent_band(problem, f.x, tolerance, config.band_samples,
                            rngs[FORMS.index(f.form)])
        rows.append(band_rows(f.form, X, config))
        counts[f.form.name] = len(X)
        predictions.append(problem.predict(X))
    y = np.vstack(predictions)
    reading = data_tolerance(config, 0.0)
    targets = np.array([getattr(config, d.field) for d in DATA])
    return {
        "widened_by_pct": 100 * widened, "sets_per_form": counts,
        "columns": list(BAND_COLUMNS), "sets": np.vstack(rows).tolist(),
        "data": [{"datum": d.name, "value": float(v), "upper_bound_only": d.upper_bound_only,
                  "reading_low": None if d.upper_bound_only else float(v - r),
                  "reading_high": float(v + r), "tolerance": float(t),
                  "predicted_low": float(lo), "predicted_high": float(hi),
                  # how far the band stays from the reading-error interval (0: reaches it)
                  "misses_reading_interval_by": float(max(lo - (v + r), 0.0) if
                                                      d.upper_bound_only else
                                                      max(lo - (v + r), (v - r) - hi, 0.0))}
                 for d, v, r, t, lo, hi in zip(DATA, targets, reading, tolerance,
                                               y.min(axis=0), y.max(axis=0))]}


@dataclass(frozen=True)
class FormFit:
    """One model form fitted on the seven ADAMS data: the ``form``, its parameters ``x``
    (p,) in their names' units, the ``misfit`` (sum of squared relative residuals), the
    largest residual (%) and each datum's (%), and whether it is ``kept`` (every band and
    robust draw runs over the kept forms: :func:`fit_forms`)."""

    form: ModelForm
    x: Floats
    misfit: float
    max_residual_pct: float
    residuals_pct: dict[str, float]
    kept: bool = False

    def to_json(self) -> dict[str, object]:
        """The form's row of ``show --format json``'s ``model_forms``."""
        return {"name": self.form.name, "summary": self.form.summary,
                "misfit": self.misfit, "max_residual_pct": self.max_residual_pct,
                "kept": self.kept,
                "parameters": {n: float(v) for n, v in zip(self.form.parameters, self.x)},
                "residuals_pct": self.residuals_pct}


def fit_forms(config: VcbDynamicsIdentifyConfig, start: dict[str, float]
              ) -> tuple[FormFit, ...]:
    """Every model form (:data:`~camopt.cases.vcb.forms.FORMS`) fitted by least squares
    from two starts, ``start`` (values by parameter name; a form's parameters it lacks
    from the config's) and a release 8 deg past the dead centre with 2 N m of friction,
    the better kept. A form is kept when its largest residual is at most
    ``form_keep_ratio`` times the best form's or at most ``form_keep_pct``, whichever is
    larger: a form that fits the data about as well as the best is as credible."""
    fits = []
    for form in FORMS:
        problem = VcbDynamicsIdentification(config.model_copy(update={"model_form": form.name}))
        defaults = {"efficiency": config.efficiency, "cam_friction_nm": config.cam_friction_nm,
                    **{n: getattr(config, n) for n in INERTIAS}}
        first = np.array([start.get(n, defaults[n]) for n in form.parameters])
        second = np.array([{"release_offset_deg": 8.0, "cam_friction_nm": 2.0}.get(n, v)
                           for n, v in zip(form.parameters, first)])
        x = min((fit(problem, s) for s in (first, second)),
                key=lambda x: float(problem.evaluate(x[None, :]).f[0]))
        ev = problem.evaluate(x[None, :])
        fits.append(FormFit(form, x, float(ev.f[0]), float(ev.extras["max_residual_pct"][0]),
                            {d.name: float(ev.extras[f"residual_{d.key}_pct"][0])
                             for d in DATA}))
    best = min(f.max_residual_pct for f in fits)
    limit = max(config.form_keep_ratio * best, config.form_keep_pct)
    return tuple(replace(f, kept=f.max_residual_pct <= limit) for f in fits)


def identifiability(problem: VcbDynamicsIdentification, x: Floats) -> Identifiability:
    """What the seven data determine about ``problem``'s form at parameters ``x`` (p,):
    :func:`camopt.core.fitting.identifiability` of the relative residuals' Jacobian with
    respect to the log parameters (:func:`log_jacobian`)."""
    return core_identifiability(log_jacobian(problem, x), problem.names)
