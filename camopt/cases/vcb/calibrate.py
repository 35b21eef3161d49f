"""Calibration of the VCB closing dynamics on measured travel curves (issue #32).

Each curve belongs to a design (the case's reference cam and springs unless the curve
names others) and is timed from the close command; the model's closing starts at the
release of the closing springs, a latch delay later. For every model form
(:class:`ModelForm`: the parameters it fits and the travel it simulates for a design and a
parameter vector) the fit is

    min over (p, d)  sum_curves sum_samples  rho( ((s_model(t_i - d_c; p) - s_i) / sigma_c)^2 )

robust least squares (scipy ``least_squares``, ``loss="soft_l1"``, ``f_scale`` 3: samples
further than ~3 noise levels from the model, an analyser's spikes, count linearly, not
quadratically) in the log of each positive parameter, with one latch delay d_c per curve
unless given (a nuisance parameter), sigma_c each curve's noise (its second differences,
:func:`camopt.cases.vcb.curves.noise_level`). Samples before the motion are fitted too: the
model holds the rod at rest until the cam meets the roller, so they fix the delay plus the
free rotation's time; the curve's zero is the median of those samples.

Intervals are **profile likelihood** (not a posterior): for each parameter in turn, fixed
at values stepped away from the optimum and every other parameter re-fitted, the 95 %
interval is where the cost rises by chi2(1, 0.95) / 2 = 1.92 times the fit's reduced
chi-square s^2 = 2 cost / (N - P) (so a model that misfits gets wider intervals, not
narrower). A parameter whose profile stays under the threshold up to a search bound is
"not identified" by the curves (its interval reaches the bound). Samples along a travel
curve are not quite independent (the model's misfit is smooth), so these intervals are
the ones white noise would give; ``docs/calibration.md`` says so.

Predictions (closing velocity over the case's window, touch time) for designs without a
curve get the envelope of their values over every re-fitted parameter vector met on the
profiles within the threshold.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.curves import (
    AnalyserQuantities,
    TravelCurve,
    VelocityPoints,
    analyse,
)
from camopt.cases.vcb.dynamics import MotionParameters, closing_motion
from camopt.cases.vcb.model import Kinematics, VcbModel
from camopt.units import DEG, MM, MS

CHI2_95_1DOF = 3.841458820694124
"""chi-square quantile, 1 degree of freedom, 0.95 (scipy.stats.chi2.ppf(0.95, 1))."""
ROBUST_SCALE = 3.0
"""soft-l1 loss scale in noise levels: quadratic within, linear beyond."""
IDENTIFIED_WITHIN = 0.05
"""A parameter counts as identified when its 95 % interval is closed inside the search
bounds and lies within +-5 % of its value (the accuracy a designer asks of a calibrated
value: the truth, inside the interval, is then within 5 %); the latch delay, within
+-IDENTIFIED_DELAY_MS."""
IDENTIFIED_DELAY_MS = 0.25
MAX_DELAY_S = 0.1
"""Upper search bound of a fitted latch delay (s)."""


@dataclass(frozen=True)
class FitParameter:
    """A parameter a model form fits: its name (a ``[case]`` field, so the fitted value
    can be written back), unit, search bounds and whether it is fitted in its log (a
    positive quantity). Values in the field's unit."""

    name: str
    unit: str
    lower: float
    upper: float
    log: bool = True


@dataclass(frozen=True)
class Design:
    """The design a curve (or a prediction) belongs to: follower-law coefficients ``a``
    (d + 1,) rad/rad^k, spring rates ``kc`` (2,) N/m, and a label."""

    label: str
    a: NDArray
    kc: NDArray


class ModelForm(Protocol):
    """A model form of the VCB closing: the seam where the forms of
    ``camopt/cases/vcb`` plug into the calibration."""

    @property
    def name(self) -> str:
        """The form's name (``--form``)."""

    @property
    def description(self) -> str:
        """One line: what the form's friction and losses are."""

    @property
    def parameters(self) -> tuple[FitParameter, ...]:
        """The parameters it fits, in the order of a parameter row."""

    def start(self, config: VcbConfig) -> NDArray:
        """The case's values of the parameters (their units), (P,)."""

    def travel(self, model: VcbModel, designs: Sequence[Design], P: NDArray, steps: int
               ) -> tuple[NDArray, NDArray]:
        """Time from the release (s) and rod travel (m) of each design under each
        parameter row of ``P`` (k, P): arrays (k, n, m) on the form's own grid, time
        increasing along m (inf after a stall)."""

    def velocity(self, model: VcbModel, designs: Sequence[Design], P: NDArray, steps: int
                 ) -> tuple[NDArray, NDArray]:
        """The case's closing velocity (m/s) and the touch time from the release (s) of
        each design under each parameter row, (k, n) each."""


@dataclass(frozen=True)
class EfficiencyCoulomb:
    """Today's VCB dynamics (:mod:`camopt.cases.vcb.dynamics`): the mechanical efficiency
    on the driving springs' work (Eq 26) and a Coulomb friction torque at the cam shaft;
    fits J_cam, m_rod, m_c, the release offset and the friction torque (the follower's
    inertia stays the case's: travel curves cannot separate it from m_rod either)."""

    name: str = "efficiency_coulomb"
    description: str = "efficiency (Eq 26) + Coulomb friction at the cam shaft"
    parameters: tuple[FitParameter, ...] = (
        FitParameter("cam_inertia_kg_m2", "kg m^2", 1e-5, 0.05),
        FitParameter("rod_mass_kg", "kg", 0.05, 30.0),
        FitParameter("contacts_mass_kg", "kg", 0.05, 15.0),
        FitParameter("release_offset_deg", "deg", 0.5, 40.0),
        FitParameter("cam_friction_nm", "N m", 0.01, 100.0),
    )

    def start(self, config: VcbConfig) -> NDArray:
        c = config
        return np.array([c.cam_inertia_kg_m2, c.rod_mass_kg, c.contacts_mass_kg,
                         c.release_offset_deg, max(c.cam_friction_nm, 0.1)])

    def _motion(self, model: VcbModel, designs: Sequence[Design], P: NDArray, steps: int):
        P = np.atleast_2d(P)
        k, n = len(P), len(designs)
        rows = np.repeat(P, n, axis=0)  # parameter-major: set 0 for every design, ...
        params = MotionParameters(rows[:, 0], model.c.follower_inertia_kg_m2, rows[:, 1],
                                  rows[:, 2], rows[:, 3] * DEG, rows[:, 4])
        degree = max(len(d.a) for d in designs)
        A = np.array([np.pad(d.a, (0, degree - len(d.a))) for d in designs])
        kc = np.array([d.kc for d in designs])
        link = np.tile(model.vendor_link, (k * n, 1))
        rod_offset = model.c.rod_arm_offset_deg * DEG
        loads = _loads(model)
        return closing_motion(model, np.tile(A, (k, 1)), np.tile(kc, (k, 1)), link,
                              rod_offset, loads, params, steps), k, n

    def travel(self, model: VcbModel, designs: Sequence[Design], P: NDArray, steps: int
               ) -> tuple[NDArray, NDArray]:
        mo, k, n = self._motion(model, designs, P, steps)
        return mo.time.reshape(k, n, -1), mo.rod.reshape(k, n, -1)

    def velocity(self, model: VcbModel, designs: Sequence[Design], P: NDArray, steps: int
                 ) -> tuple[NDArray, NDArray]:
        mo, k, n = self._motion(model, designs, P, steps)
        return mo.closing_velocity_avg.reshape(k, n), mo.touch_time.reshape(k, n)


FORMS: dict[str, ModelForm] = {f.name: f for f in (EfficiencyCoulomb(),)}
"""The model forms calibrate fits, by name."""


class _KinematicsMemo(VcbModel):
    """The case's model with its kinematics remembered by input (a calibration simulates
    the same few designs, tiled by as many parameter rows, hundreds of times: the
    kinematics depend on the designs alone; ~20 % of an evaluation). The arrays kept are
    read-only, so nothing downstream can change them in place."""

    SIZE = 16

    def __init__(self, config: VcbConfig) -> None:
        super().__init__(config)
        self._memo: dict[tuple, Kinematics] = {}

    def kinematics(self, A: NDArray, link: NDArray, rod_offset: NDArray | float,
                   theta_c: NDArray | None = None) -> Kinematics:
        key = tuple(np.asarray(v, dtype=float).tobytes() + bytes(str(np.shape(v)), "ascii")
                    for v in (A, link, rod_offset, () if theta_c is None else theta_c))
        kin = self._memo.get(key)
        if kin is None:
            kin = super().kinematics(A, link, rod_offset, theta_c)
            for a in (kin.cos4, kin.sin4, kin.s1, kin.ds1, kin.follower.dphi):
                a.setflags(write=False)
            if len(self._memo) >= self.SIZE:
                self._memo.pop(next(iter(self._memo)))
            self._memo[key] = kin
        return kin


def _loads(model: VcbModel):
    """The case's resisting loads, with the rod travel of its reference design."""
    c = model.c
    kin = model.kinematics(model.vendor_a[None, :], model.vendor_link[None, :],
                           c.rod_arm_offset_deg * DEG)
    return model.loads(float(kin.s1[0, -1]), c.opening_arm_ratio, c.free_contact_force_n)


def sample_travel(time: NDArray, rod: NDArray, query: NDArray) -> NDArray:
    """Rod travel of each row at the query times (s from the release), linearly between
    the model's nodes, 0 before its first node, its last value after the last (the latch)
    or a stall: rows ``time``/``rod`` (r, m), ``query`` (r, q); one searchsorted for all
    rows (each row shifted past the previous one's span)."""
    r, m = time.shape
    never = ~np.isfinite(time[:, 0])  # the cam never leaves the release: no motion
    t = np.where(np.isfinite(time), time, np.nan)
    t[never, 0] = 0.0
    last = np.nanmax(t, axis=1, keepdims=True)
    t = np.where(np.isnan(t), last + 1.0 + np.arange(m) * 1e-9, t)  # held after a stall
    # the nodes a stalled row never reaches hold its last reached travel
    reached = np.maximum(np.sum(np.isfinite(time), axis=1) - 1, 0)
    rod = np.where(np.isfinite(time), rod, rod[np.arange(r), reached][:, None])
    span = np.max(t[:, -1] - np.minimum(t[:, 0], np.min(query, axis=1))) + 10.0
    shift = (np.arange(r) * span)[:, None]
    flat = (t + shift).ravel()
    q = np.clip(query, t[:, :1], t[:, -1:]) + shift
    idx = np.clip(np.searchsorted(flat, q.ravel(), side="right"), 1, r * m - 1).reshape(q.shape)
    row0 = (np.arange(r) * m)[:, None]
    idx = np.clip(idx, row0 + 1, row0 + m - 1)
    f_rod = rod.ravel()
    t0, t1 = flat[idx - 1], flat[idx]
    w = np.clip((q - t0) / (t1 - t0), 0.0, 1.0)
    out = (1 - w) * f_rod[idx - 1] + w * f_rod[idx]
    return np.where((query < t[:, :1]) | never[:, None], 0.0, out)


@dataclass(frozen=True)
class CurveCase:
    """A measured curve with its design and latch delay (s; None: fitted)."""

    curve: TravelCurve
    design: Design
    latch_delay: float | None = None


@dataclass(frozen=True)
class ParameterEstimate:
    """A fitted parameter (its unit): value, 95 % profile-likelihood interval (low, high;
    a search bound where the profile does not cross the threshold) and whether the curves
    identify it (:data:`IDENTIFIED_WITHIN`)."""

    name: str
    unit: str
    value: float
    low: float
    high: float
    identified: bool


@dataclass(frozen=True)
class Prediction:
    """A design's predicted closing (the case's closing velocity, m/s, and its touch time
    from the release, s) at the fit and its low/high over the profiles."""

    design: str
    closing_velocity: float
    closing_velocity_low: float
    closing_velocity_high: float
    touch_time: float
    touch_time_low: float
    touch_time_high: float


@dataclass(frozen=True)
class CurveFit:
    """One curve's fit: its source, the samples' time (s) and measured and fitted travel
    (m), the RMS misfit (m) and the analyser's quantities of both curves."""

    source: str
    design: str
    latch_delay: float
    time: NDArray
    measured: NDArray
    fitted: NDArray
    rms: float
    measured_quantities: AnalyserQuantities
    fitted_quantities: AnalyserQuantities


@dataclass(frozen=True)
class FormFit:
    """The calibration of one model form: RMS misfit over every sample (m), the
    parameters (the form's, then the fitted latch delay in ms, if any), their correlation
    matrix at the optimum (linearised: (J^T J)^-1 s^2), the curves, the predictions, and
    ``band``: the form's parameter rows met on the profiles inside the intervals, the fit
    first."""

    form: str
    description: str
    rms: float
    parameters: tuple[ParameterEstimate, ...]
    correlation: NDArray
    curves: tuple[CurveFit, ...]
    predictions: tuple[Prediction, ...]
    band: NDArray = field(repr=False)


class Calibration:
    """Fits one model form to the curves (module docstring). ``steps`` the form's grid
    (the case's ``dynamics_steps``)."""

    def __init__(self, config: VcbConfig, form: ModelForm, curves: Sequence[CurveCase],
                 points: VelocityPoints | None = None) -> None:
        self.config, self.form, self.curves = config, form, tuple(curves)
        self.model = _KinematicsMemo(config)
        self.steps = config.dynamics_steps
        self.points = points or VelocityPoints.last_third(config.contact_gap_mm * MM)
        self.designs = [c.design for c in self.curves]
        self.n_form = len(form.parameters)
        # one latch delay for every curve without its own (the same breaker's coil and latch)
        self.free_delay = [i for i, c in enumerate(self.curves) if c.latch_delay is None]
        lo = [np.log(p.lower) if p.log else p.lower for p in form.parameters]
        hi = [np.log(p.upper) if p.log else p.upper for p in form.parameters]
        shared = 1 if self.free_delay else 0
        self.lower = np.r_[lo, np.zeros(shared)]
        self.upper = np.r_[hi, np.full(shared, MAX_DELAY_S / MS)]
        self.log = np.array([p.log for p in form.parameters] + [False] * shared)
        self.sigma = np.array([max(c.curve.noise, 1e-3 * MM) for c in self.curves])
        self.n_samples = sum(len(c.curve.time) for c in self.curves)

    # ---- parameter vectors: q (fitted coordinates) <-> form values and delays --------
    def values(self, Q: NDArray) -> tuple[NDArray, NDArray]:
        """Form parameters (k, P) in their units and every curve's delay (k, n) s."""
        Q = np.atleast_2d(Q)
        v = np.where(self.log, np.exp(np.minimum(Q, 700)), Q)
        delays = np.tile([c.latch_delay or 0.0 for c in self.curves], (len(Q), 1))
        if self.free_delay:
            delays[:, self.free_delay] = v[:, self.n_form:self.n_form + 1] * MS
        return v[:, :self.n_form], delays

    def simulate(self, Q: NDArray) -> list[NDArray]:
        """Simulated travel (m) at each curve's sample times, per curve (k, m_c)."""
        P, delays = self.values(Q)
        time, rod = self.form.travel(self.model, self.designs, P, self.steps)
        k = len(P)
        out = []
        for i, c in enumerate(self.curves):  # curves: a handful, each vectorised over k
            query = c.curve.time[None, :] - delays[:, i : i + 1]
            out.append(sample_travel(time[:, i], rod[:, i], np.broadcast_to(
                query, (k, len(c.curve.time)))))
        return out

    def residuals(self, Q: NDArray) -> NDArray:
        """Normalised residuals (k, N): (model - measured) / sigma, every curve."""
        sims = self.simulate(Q)
        return np.concatenate([(s - c.curve.travel) / sig for s, c, sig
                               in zip(sims, self.curves, self.sigma)], axis=1)

    # ---- fitting ---------------------------------------------------------------------
    def _fit(self, q0: NDArray, fixed: int | None = None, tight: bool = False
             ) -> tuple[NDArray, float]:
        """Robust least squares from q0; ``fixed`` keeps one coordinate at q0's. Returns
        q and the cost (0.5 sum rho)."""
        from scipy.optimize import least_squares

        free = np.array([i != fixed for i in range(len(q0))])
        base = q0.copy()

        def full(z: NDArray) -> NDArray:
            Z = np.repeat(base[None, :], len(np.atleast_2d(z)), axis=0)
            Z[:, free] = np.atleast_2d(z)
            return Z

        def fun(z: NDArray) -> NDArray:
            return self.residuals(full(z))[0]

        def jac(z: NDArray) -> NDArray:  # forward differences, one vectorised call
            h = 1e-6 * np.maximum(1.0, np.abs(z))
            Z = np.vstack([z, z + np.diag(h)])
            R = self.residuals(full(Z))
            return ((R[1:] - R[0]) / h[:, None]).T

        lo, hi = self.lower[free], self.upper[free]
        z0 = np.clip(q0[free], lo + 1e-9, hi - 1e-9)
        tol = 1e-8 if tight else 1e-6
        sol = least_squares(fun, z0, jac=jac, bounds=(lo, hi), loss="soft_l1",
                            f_scale=ROBUST_SCALE, x_scale=1.0, max_nfev=200 if tight else 100,
                            ftol=tol, xtol=tol)
        return full(sol.x)[0], float(sol.cost)

    def start(self) -> NDArray:
        """The form's case values and, for each fitted delay, the delay that puts the
        model's first motion on the curve's (from a quick look at the curves)."""
        p0 = self.form.start(self.config)
        q = np.array([np.log(v) if p.log else v for v, p in zip(p0, self.form.parameters)])
        time, rod = self.form.travel(self.model, self.designs, p0[None, :], self.steps)
        delays = []
        for i in self.free_delay:
            c = self.curves[i].curve
            moved = np.argmax(c.travel > 0.1 * np.max(c.travel))
            t_model = time[0, i][np.argmax(rod[0, i] > 0.1 * np.max(c.travel))]
            delays.append(np.clip((c.time[moved] - t_model) / MS, 0.01, MAX_DELAY_S / MS - 0.01))
        return np.r_[q, np.mean(delays)] if delays else q

    def fit(self) -> FormFit:
        """The fit, the profiles and the report of this form."""
        q0 = self.start()
        # two starts: the case's values and a perturbation of the first fit's end, keeping
        # the better (the cost surface of a delay and a release offset has shallow valleys)
        q, cost = self._fit(q0, tight=True)
        q2, cost2 = self._fit(q + 0.05 * self.log, tight=True)
        if cost2 < cost:
            q, cost = q2, cost2
        dof = max(self.n_samples - len(q), 1)
        s2 = max(2 * cost / dof, 1.0)
        rise = 0.5 * CHI2_95_1DOF * s2
        J = self._jacobian(q)
        cov = np.linalg.pinv(J.T @ J) * s2
        sd = np.sqrt(np.maximum(np.diag(cov), 1e-12))
        corr = cov / np.outer(sd, sd)
        ests, members = [], [q]
        for j, (name, unit) in enumerate(self.names()):
            ends = []
            for sign in (-1.0, 1.0):
                end, inside = self._profile(q, cost, j, sign, cov, rise)
                ends.append(end)
                members += inside
            lo_q, hi_q = ends
            low = _out(lo_q if lo_q is not None else self.lower[j], self.log[j])
            high = _out(hi_q if hi_q is not None else self.upper[j], self.log[j])
            value = _out(q[j], self.log[j])
            # identified: a closed profile interval inside the search bounds, within
            # IDENTIFIED_WITHIN of the value (the delay: IDENTIFIED_DELAY_MS)
            reach = max(value - low, high - value)
            identified = bool(lo_q is not None and hi_q is not None and (
                reach <= IDENTIFIED_WITHIN * abs(value) if self.log[j]
                else reach <= IDENTIFIED_DELAY_MS))
            ests.append(ParameterEstimate(name, unit, value, low, high, identified))
        P_band, _ = self.values(np.array(members))
        return FormFit(self.form.name, self.form.description, self._rms(q), tuple(ests),
                       corr, self._curve_fits(q), (), P_band)

    def names(self) -> list[tuple[str, str]]:
        """(name, unit) of every fitted coordinate: the form's, then the latch delay."""
        return [(p.name, p.unit) for p in self.form.parameters] + (
            [("latch_delay_ms", "ms")] if self.free_delay else [])

    def _costs(self, Q: NDArray) -> NDArray:
        """The robust cost (0.5 sum rho, as least_squares's) of each row of Q, (k,)."""
        z = (self.residuals(Q) / ROBUST_SCALE) ** 2
        return 0.5 * ROBUST_SCALE**2 * np.sum(2 * (np.sqrt(1 + z) - 1), axis=1)

    def _jacobian(self, q: NDArray) -> NDArray:
        h = 1e-6 * np.maximum(1.0, np.abs(q))
        R = self.residuals(np.vstack([q, q + np.diag(h)]))
        return ((R[1:] - R[0]) / h[:, None]).T

    def _profile(self, q: NDArray, cost: float, j: int, sign: float, cov: NDArray,
                 rise: float) -> tuple[float | None, list[NDArray]]:
        """Coordinate j's profile from the optimum ``q`` (cost ``cost``) in direction
        ``sign``: fixed at 1.5, 3, 6, ... linearised standard deviations (``cov``) from
        it, the others re-fitted, until the cost rises by more than ``rise``; a rise of
        more than 4 ``rise`` (a cliff: the profile is not a parabola there) is bisected
        until the bracket holds at most that, and the crossing is placed in the bracket
        as on a parabola through the optimum. Returns the end (None: the profile reaches
        the search bound, or 14 re-fits, under the threshold) and the re-fitted vectors
        inside the interval."""
        bound = self.upper[j] if sign > 0 else self.lower[j]
        room = abs(bound - q[j])
        d, near, near_rise = min(1.5 * float(np.sqrt(cov[j, j])), room), 0.0, 0.0
        far: tuple[float, float] | None = None
        last = q
        inside: list[NDArray] = []
        for _ in range(14):
            x = q[j] + sign * d
            # start from the better of the last inside point moved along j alone and the
            # linearised conditional optimum (the valley's direction near the optimum)
            starts = np.vstack([last, q + cov[:, j] / cov[j, j] * (x - q[j])])
            starts = np.clip(starts, self.lower + 1e-9, self.upper - 1e-9)
            starts[:, j] = x
            trial, c = self._fit(starts[int(np.argmin(self._costs(starts)))], fixed=j)
            r = c - cost
            if r <= rise:
                inside.append(trial)
                last, near, near_rise = trial, d, max(r, 0.0)
                if far is None and d >= room:
                    return None, inside
                d = min(2 * d, room) if far is None else 0.5 * (near + far[0])
            else:
                far = (d, r)
                if r <= 4 * rise or far[0] - near < 1e-4:
                    break
                d = 0.5 * (near + far[0])
        if far is None:
            return None, inside
        # the bracket (near, far): rise ~ a (distance)^2 through its two ends
        a = (far[1] - near_rise) / max(far[0] ** 2 - near**2, 1e-300)
        at = np.sqrt(near**2 + (rise - near_rise) / a) if a > 0 else far[0]
        return q[j] + sign * float(np.clip(at, near, far[0])), inside

    def _rms(self, q: NDArray) -> float:
        R = self.residuals(q)[0]
        sig = np.concatenate([np.full(len(c.curve.time), s)
                              for c, s in zip(self.curves, self.sigma)])
        return float(np.sqrt(np.mean((R * sig) ** 2)))

    def _curve_fits(self, q: NDArray) -> tuple[CurveFit, ...]:
        sims = self.simulate(q)
        _, delays = self.values(q)
        gap = self.config.contact_gap_mm * MM
        out = []
        for i, (c, s) in enumerate(zip(self.curves, sims)):
            t, meas = c.curve.time, c.curve.travel
            out.append(CurveFit(
                c.curve.source, c.design.label, float(delays[0, i]), t, meas, s[0],
                float(np.sqrt(np.mean((s[0] - meas) ** 2))),
                analyse(t, meas, gap, self.points),
                analyse(t, s[0], gap, self.points, rebounds=False)))
        return tuple(out)

    def predict(self, fit: FormFit, designs: Sequence[Design], best: NDArray
                ) -> tuple[Prediction, ...]:
        """Closing velocity and touch time of ``designs`` at the fitted form parameters
        ``best`` (P,) and their envelope over the fit's band."""
        P = np.vstack([best, fit.band])
        v, t = self.form.velocity(self.model, designs, P, self.steps)
        return tuple(Prediction(d.label, float(v[0, i]), float(np.nanmin(v[:, i])),
                                float(np.nanmax(v[:, i])), float(t[0, i]),
                                float(np.nanmin(t[:, i])), float(np.nanmax(t[:, i])))
                     for i, d in enumerate(designs))


def _out(q: float, log: bool) -> float:
    return float(np.exp(q)) if log else float(q)


def calibrate(config: VcbConfig, curves: Sequence[CurveCase], forms: Sequence[ModelForm],
              predict: Sequence[Design] = (), points: VelocityPoints | None = None
              ) -> tuple[FormFit, ...]:
    """Fit every form to the curves jointly and predict ``predict``'s designs (the
    curves' designs if empty)."""
    out = []
    for form in forms:
        cal = Calibration(config, form, curves, points)
        fit = cal.fit()
        best = np.array([p.value for p in fit.parameters[:cal.n_form]])
        designs = list(predict) or _unique(cal.designs)
        out.append(replace(fit, predictions=cal.predict(fit, designs, best)))
    return tuple(out)


def _unique(designs: Sequence[Design]) -> list[Design]:
    """One design per label, in order."""
    seen: dict[str, Design] = {}
    for d in designs:
        seen.setdefault(d.label, d)
    return list(seen.values())
