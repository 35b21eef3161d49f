"""Calibration of the VCB closing dynamics on measured travel curves (issue #32).

Each curve belongs to a design (the case's reference cam and springs unless the curve
names others) and is timed from the close command; the model's closing starts at the
release of the closing springs, a latch delay later. For every model form of
:data:`camopt.cases.vcb.forms.FORMS` (the one seam the identification on the ADAMS data
uses too: the parameters a form fits, their search bounds on curves and the closing it
simulates for designs and parameter rows) the fit is

    min over (p, d)  sum_curves sum_samples  rho( ((s_model(t_i - d_c; p) - s_i) / sigma_c)^2 )

robust least squares (scipy ``least_squares``, ``loss="soft_l1"``, ``f_scale`` 3: samples
further than ~3 noise levels from the model, an analyser's spikes, count linearly, not
quadratically; the profiles' re-fits by :meth:`Calibration.fit_many`, a Levenberg-Marquardt
that runs them side by side in one vectorised simulation) in the log of each positive
parameter, with one latch delay d_c per curve unless given (a nuisance parameter), sigma_c
each curve's noise (its second differences,
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

A form is **kept** (:func:`keep`) when its RMS misfit is at most 1.5 times the best
form's, or 1.5 times the curves' noise, whichever is larger: the identification's rule
(``form_keep_ratio`` times the best form's largest residual, or ``form_keep_pct``) with
the RMS misfit for the largest residual and the noise for the absolute floor. A form
not kept gets linearised intervals instead of profiles (:meth:`Calibration.fit`).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from camopt.cases.vcb.config import VcbConfig
from camopt.cases.vcb.curves import (
    AnalyserQuantities,
    TravelCurve,
    VelocityPoints,
    analyse,
)
from camopt.cases.vcb.dynamics import ClosingMotion
from camopt.cases.vcb.forms import CURVE_FORMS, ModelForm
from camopt.cases.vcb.model import Kinematics, Loads, VcbModel
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
FINE_STEP_S = 1e-5
"""The fitted model's curve is read by the analyser's rules at this step (100 kHz)."""
MIN_WINDOW_SAMPLES = 10
"""A measured curve with fewer samples between the contact velocity's calculation points
reads its closing time and contact velocity from the fit (resampled)."""


@dataclass(frozen=True)
class Design:
    """The design a curve (or a prediction) belongs to: follower-law coefficients ``a``
    (d + 1,) rad/rad^k, spring rates ``kc`` (2,) N/m, and a label."""

    label: str
    a: NDArray
    kc: NDArray


def closing(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: NDArray,
            steps: int) -> ClosingMotion:
    """The closing of every design under every parameter row of ``P`` (k, p) of
    ``form`` (:meth:`~camopt.cases.vcb.forms.ModelForm.closing`): k x n rows,
    parameter-major (row 0 for every design, then row 1, ...), the case's linkage and
    resisting loads."""
    P = np.atleast_2d(P)
    k, n = len(P), len(designs)
    degree = max(len(d.a) for d in designs)
    A = np.array([np.pad(d.a, (0, degree - len(d.a))) for d in designs])
    kc = np.array([d.kc for d in designs])
    link = np.tile(model.vendor_link, (k * n, 1))
    rod_offset = model.c.rod_arm_offset_deg * DEG
    return form.closing(model, np.tile(A, (k, 1)), np.tile(kc, (k, 1)), link, rod_offset,
                        _loads(model), np.repeat(P, n, axis=0),
                        model.c.follower_inertia_kg_m2, steps)


def travel(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: NDArray,
           steps: int) -> tuple[NDArray, NDArray]:
    """Time from the release (s) and rod travel (m) of each design under each parameter
    row of ``P`` (k, p): arrays (k, n, m) on the form's own grid, time increasing along m
    (inf after a stall)."""
    mo = closing(form, model, designs, P, steps)
    k, n = len(np.atleast_2d(P)), len(designs)
    return mo.time.reshape(k, n, -1), mo.rod.reshape(k, n, -1)


def velocity(form: ModelForm, model: VcbModel, designs: Sequence[Design], P: NDArray,
             steps: int) -> tuple[NDArray, NDArray]:
    """The case's closing velocity (m/s) and the touch time from the release (s) of each
    design under each parameter row of ``P`` (k, p), (k, n) each."""
    mo = closing(form, model, designs, P, steps)
    k, n = len(np.atleast_2d(P)), len(designs)
    return mo.closing_velocity_avg.reshape(k, n), mo.touch_time.reshape(k, n)


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


def _loads(model: VcbModel) -> Loads:
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
    at_bound: bool = False


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
    (m), the RMS misfit (m), the analyser's quantities of both curves and the curve's
    noise level (m)."""

    source: str
    design: str
    latch_delay: float
    time: NDArray
    measured: NDArray
    fitted: NDArray
    rms: float
    measured_quantities: AnalyserQuantities
    fitted_quantities: AnalyserQuantities
    noise: float = 0.0


RMS_RATIO_LIMIT = 1.5
"""A form explains the curves only if the RMS of its residuals, in units of each curve's
noise (winsorised at :data:`WINSOR` noise levels: a few analyser spikes do not count), is
at most this: the keep rule's noise floor. 1.5 rather than 1.1: the noise estimate is a
median of second differences, exact for Gaussian noise but up to ~1.4 times low for
heavier-tailed noise (Laplace), and the structure test catches a smooth misfit below it."""
STRUCTURE_Z_LIMIT = 3.0
"""... and only if its residuals show no serial structure: the Durbin-Watson statistic d
(pooled over the curves) is not below 2 by more than this many of its standard errors
under white noise, 2 / sqrt(N) (one-sided, p ~ 0.0013: with a dozen forms and curves a
correct form is rarely flagged by chance)."""
WINSOR = 5.0
"""Residuals beyond this many noise levels count as this many in the residual test."""
NEAR_BOUND_FACTOR = 1.5
"""A positive parameter is at its search bound when its fitted value is within this
factor of it or a tenth of its search range's log, whichever is less (an efficiency's
0.2..1 gives 1.17); the latch delay within :data:`NEAR_BOUND_DELAY_MS`."""
NEAR_BOUND_DELAY_MS = 0.1


def near_bound(q: float, lower: float, upper: float, log: bool) -> bool:
    """Whether a fitted coordinate ``q`` is at or near its search bounds (``log``: the log
    of a positive parameter, near: :data:`NEAR_BOUND_FACTOR`; else the latch delay
    in ms, within :data:`NEAR_BOUND_DELAY_MS`). A parameter there is not measured by the
    curves but held by the search: often a form standing in for physics it lacks."""
    room = (min(np.log(NEAR_BOUND_FACTOR), 0.1 * (upper - lower)) if log
            else NEAR_BOUND_DELAY_MS)
    return bool(q - lower <= room or upper - q <= room)


@dataclass(frozen=True)
class ResidualTest:
    """A form's residuals against the curves' noise (:func:`residual_test`): ``noise``
    the curves' RMS noise level (m, each curve's estimated from its own samples,
    :func:`camopt.cases.vcb.curves.noise_level`), ``rms_ratio`` the residuals' RMS in
    noise levels (winsorised), ``durbin_watson`` d = sum (e_i - e_i-1)^2 / sum e_i^2 of
    the normalised residuals within each curve, pooled (2 for white residuals, toward 0
    for a smooth misfit), ``structure_z`` = (2 - d) sqrt(N) / 2 its distance below 2 in
    standard errors, and the number of samples N."""

    noise: float
    rms_ratio: float
    durbin_watson: float
    structure_z: float
    samples: int

    def passes(self) -> bool:
        """Residuals at the noise (:data:`RMS_RATIO_LIMIT`) and without structure
        (:data:`STRUCTURE_Z_LIMIT`)."""
        return self.rms_ratio <= RMS_RATIO_LIMIT and self.structure_z <= STRUCTURE_Z_LIMIT


def residual_test(residuals: Sequence[NDArray], sigma: Sequence[float]) -> ResidualTest:
    """The test of a fit's residuals (m, one array per curve) against each curve's noise
    ``sigma`` (m): :class:`ResidualTest`. Normalised by the noise and winsorised at
    :data:`WINSOR`; the Durbin-Watson sums run within each curve (no difference across
    two curves) and are pooled."""
    e = [np.clip(np.asarray(r) / s, -WINSOR, WINSOR) for r, s in zip(residuals, sigma)]
    n = sum(len(x) for x in e)
    squares = sum(float(np.sum(x * x)) for x in e)
    steps = sum(float(np.sum(np.diff(x) ** 2)) for x in e)
    counts = np.array([len(x) for x in e])
    noise = float(np.sqrt(np.sum(counts * np.square(sigma)) / max(n, 1)))
    d = steps / squares if squares > 0 else 2.0
    return ResidualTest(noise, float(np.sqrt(squares / max(n, 1))), d,
                        (2.0 - d) * np.sqrt(n) / 2.0, n)


def missing_physics(fit: FormFit, gap: float) -> str:
    """Where a form's misfit lies along the closing and what typically shows there: the
    residuals' excess over the noise (sum of squares less N sigma^2) before the motion,
    in the stroke to the touch and from the touch on. A reading, not a fit: a smooth
    misfit of the moving part fits several missing effects alike (a distributed mass and
    a dashpot both leave an S-shaped residual across the touch), so it names them all."""
    parts = {"before the motion": 0.0, "in the stroke to the touch": 0.0,
             "from the touch to the latch": 0.0}
    for c in fit.curves:
        r = c.fitted - c.measured
        moving = c.measured > 0.05 * np.max(c.measured)
        first = int(np.argmax(moving)) if moving.any() else len(r)
        touched = c.measured >= gap
        t_touch = int(np.argmax(touched)) if touched.any() else len(r)
        for name, z in zip(parts, (slice(0, first), slice(first, t_touch),
                                   slice(t_touch, len(r)))):
            seg = r[z]
            parts[name] += max(float(np.sum(seg * seg)) - seg.size * c.noise**2, 0.0)
    where = max(parts, key=lambda k: parts[k])
    if where == "before the motion":
        return ("the misfit is largest before the motion: a latch delay that differs "
                "between the curves (give each its measured latch_delay_ms), a release "
                "that is not instantaneous, or a transducer offset")
    return (f"the misfit is largest {where}: likely missing from the rigid model with "
            "Coulomb losses: the closing springs' own mass (inertia along the stroke), "
            "viscous damping (a dashpot or buffer on the rod), the contacts' compliance")


@dataclass(frozen=True)
class FormFit:
    """The calibration of one model form: RMS misfit over every sample (m), the
    parameters (the form's, then the fitted latch delay in ms, if any), their correlation
    matrix at the optimum (linearised: (J^T J)^-1 s^2), the curves, the predictions,
    ``band``: the form's parameter rows met on the profiles inside the intervals, the fit
    first, whether the form is ``kept`` (:func:`keep`), how its ``intervals`` were
    found (``profile``: profile likelihood; ``linearised``: a form not kept), the test of
    its residuals against the curves' noise (:func:`residual_test`) and whether it
    ``explains`` the curves (kept, and its residuals pass: :meth:`ResidualTest.passes`),
    and why a form with more physics is not kept (``kept_note``: :func:`nested_keep`)."""

    form: str
    description: str
    rms: float
    parameters: tuple[ParameterEstimate, ...]
    correlation: NDArray
    curves: tuple[CurveFit, ...]
    predictions: tuple[Prediction, ...]
    band: NDArray = field(repr=False)
    kept: bool = True
    intervals: str = "profile"
    residuals: ResidualTest | None = None
    explains: bool = False
    kept_note: str = ""


@dataclass(frozen=True)
class Optimum:
    """A form's best fit: fitted coordinates ``q`` (n,), its robust cost, the linearised
    covariance of q ((J^T J)^-1 s^2, (n, n)), the reduced chi-square s^2 (at least 1) and
    the RMS misfit (m)."""

    q: NDArray
    cost: float
    cov: NDArray
    s2: float
    rms: float


@dataclass
class _Profile:
    """The state of one coordinate's profile in one direction (:meth:`Calibration.
    _profiles`): its coordinate ``j``, direction, the optimum's value of it
    (``origin``) and the room to the search bound, the step ``d`` from the optimum now
    tried, the furthest inside (``near``, its cost rise) and the nearest outside (``far``:
    distance, rise), the last re-fitted vector inside, those inside, and the end (None:
    open to a bound)."""

    j: int
    sign: float
    origin: float
    room: float
    d: float
    last: NDArray
    near: float = 0.0
    near_rise: float = 0.0
    far: tuple[float, float] | None = None
    inside: list[NDArray] = field(default_factory=list)
    done: bool = False
    end: float | None = None
    steps: int = 0


class Calibration:
    """Fits one model form to the curves (module docstring). ``steps`` the form's grid
    (the case's ``dynamics_steps``)."""

    MAX_PROFILE_STEPS = 10

    def __init__(self, config: VcbConfig, form: ModelForm, curves: Sequence[CurveCase],
                 points: VelocityPoints | None = None) -> None:
        self.config, self.form, self.curves = config, form, tuple(curves)
        self.model = _KinematicsMemo(config)
        self.steps = config.dynamics_steps
        self.points = points or VelocityPoints.last_third(config.contact_gap_mm * MM)
        self.designs = [c.design for c in self.curves]
        self.parameters = form.curve_parameters()
        self.n_form = len(self.parameters)
        # one latch delay for every curve without its own (the same breaker's coil and latch)
        self.free_delay = [i for i, c in enumerate(self.curves) if c.latch_delay is None]
        lo = [np.log(p.lower) if p.log else p.lower for p in self.parameters]
        hi = [np.log(p.upper) if p.log else p.upper for p in self.parameters]
        shared = 1 if self.free_delay else 0
        self.lower = np.r_[lo, np.zeros(shared)]
        self.upper = np.r_[hi, np.full(shared, MAX_DELAY_S / MS)]
        self.log = np.array([p.log for p in self.parameters] + [False] * shared)
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
        time, rod = travel(self.form, self.model, self.designs, P, self.steps)
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
    def fit_many(self, Q0: NDArray, fixed: NDArray | None = None, tol: float = 1e-9,
                 atol: float = 0.0, max_iter: int = 60) -> tuple[NDArray, NDArray]:
        """Robust least squares from each start of ``Q0`` (B, n) at once; ``fixed`` (B,)
        the coordinate each row keeps at its start (-1: none). Returns the fits (B, n)
        and their costs (B,) (0.5 sum rho, as scipy's ``least_squares``).

        Levenberg-Marquardt with Marquardt's scaling on iteratively reweighted least
        squares (soft-l1: weights w = 1 / sqrt(1 + (r / C)^2), C = :data:`ROBUST_SCALE`):
        the step solves (J^T W J + lambda diag(J^T W J)) dq = -J^T W r, J by forward
        differences; a step is kept when it lowers the robust cost (lambda / 3), else
        lambda x 4; a row stops when a kept step lowers its cost by less than ``tol``
        relative or ``atol``, or lambda exceeds 1e10, or after ``max_iter`` steps.

        Each step is one vectorised simulation of the trials and their forward steps,
        k (n + 1) parameter rows for the k rows still running: the Jacobian at a trial is
        ready when the trial is kept, and the last one still holds when it is not. The
        profiles' re-fits so run side by side for little more than the price of one (the
        model's cost grows slowly with the rows)."""
        Q = np.clip(np.atleast_2d(np.asarray(Q0, dtype=float)), self.lower, self.upper)
        B, n = Q.shape
        free = np.ones((B, n), dtype=bool)
        if fixed is not None:
            rows = np.flatnonzero(np.asarray(fixed) >= 0)
            free[rows, np.asarray(fixed)[rows]] = False
        R, J = self._with_jacobian(Q, free)
        cost = _robust_cost(R)
        lam = np.full(B, 1e-3)
        active = np.ones(B, dtype=bool)
        eye = np.eye(n)
        for _ in range(max_iter):
            idx = np.flatnonzero(active)
            if len(idx) == 0:
                break
            q, r, Jk = Q[idx], R[idx], J[idx]
            w = 1.0 / np.sqrt(1.0 + (r / ROBUST_SCALE) ** 2)
            g = np.einsum("knm,km->kn", Jk, w * r)
            # a coordinate on a bound that the descent would push out of it sits this
            # step out (an active set: clipping its step instead stalls the others)
            held = ((q <= self.lower + 1e-12) & (g > 0)) | ((q >= self.upper - 1e-12) & (g < 0))
            Jk = Jk * ~held[:, :, None]
            g = np.where(held, 0.0, g)
            H = np.einsum("knm,kjm,km->knj", Jk, Jk, w)
            diag = np.einsum("knn->kn", H)
            scale = np.maximum(diag, 1e-12 * diag.max(axis=1, keepdims=True) + 1e-300)
            A = H + (lam[idx][:, None] * scale)[:, :, None] * eye
            # pinv: a parameter the curves do not see (a zero column) takes no step
            step = -(np.linalg.pinv(A) @ g[:, :, None])[:, :, 0]
            trial = np.clip(q + step, self.lower, self.upper)
            Rt, Jt = self._with_jacobian(trial, free[idx])
            ct = _robust_cost(Rt)
            better = ct < cost[idx]
            gain = cost[idx] - ct
            good = idx[better]
            Q[good], R[good], J[good], cost[good] = (trial[better], Rt[better], Jt[better],
                                                     ct[better])
            lam[good] /= 3.0
            lam[idx[~better]] *= 4.0
            moved = np.max(np.abs(trial - q), axis=1)
            done = (better & ((gain <= np.maximum(tol * ct, atol)) | (moved < 1e-9))) | (
                lam[idx] > 1e10)
            active[idx[done]] = False
        return Q, cost

    def _with_jacobian(self, Q: NDArray, free: NDArray) -> tuple[NDArray, NDArray]:
        """Residuals (k, N) at the rows of ``Q`` (k, n) and their Jacobians' transposes
        (k, n, N) by forward differences (step 1e-6 max(1, |q|)), zero in the columns
        ``free`` (k, n) marks fixed: one simulation of k (n + 1) rows."""
        k, n = Q.shape
        h = 1e-6 * np.maximum(1.0, np.abs(Q))
        rows = np.concatenate([Q[:, None, :], Q[:, None, :] + np.eye(n)[None] * h[:, :, None]],
                              axis=1)
        Rall = self.residuals(rows.reshape(k * (n + 1), n)).reshape(k, n + 1, -1)
        J = (Rall[:, 1:] - Rall[:, :1]) / h[:, :, None]
        return Rall[:, 0], J * free[:, :, None]

    def _fit(self, q0: NDArray) -> tuple[NDArray, float]:
        """The fit from ``q0``: scipy's ``least_squares`` (trust region reflective,
        soft-l1, tight tolerances: the optimum every profile is measured from; its
        trust region follows the narrow valleys of a single curve better than
        :meth:`fit_many`'s Levenberg-Marquardt). Returns q and the cost."""
        from scipy.optimize import least_squares

        def fun(z: NDArray) -> NDArray:
            return self.residuals(z)[0]

        z0 = np.clip(q0, self.lower + 1e-9, self.upper - 1e-9)
        sol = least_squares(fun, z0, jac=self._jacobian, bounds=(self.lower, self.upper),
                            loss="soft_l1", f_scale=ROBUST_SCALE, x_scale=1.0, max_nfev=100,
                            ftol=1e-8, xtol=1e-8)
        return sol.x, float(sol.cost)

    def start(self) -> NDArray:
        """The form's case values and, for each fitted delay, the delay that puts the
        model's first motion on the curve's (from a quick look at the curves)."""
        p0 = self.form.start(self.config)
        q = np.array([np.log(v) if p.log else v for v, p in zip(p0, self.parameters)])
        time, rod = travel(self.form, self.model, self.designs, p0[None, :], self.steps)
        delays = []
        for i in self.free_delay:
            c = self.curves[i].curve
            moved = np.argmax(c.travel > 0.1 * np.max(c.travel))
            t_model = time[0, i][np.argmax(rod[0, i] > 0.1 * np.max(c.travel))]
            delays.append(np.clip((c.time[moved] - t_model) / MS, 0.01, MAX_DELAY_S / MS - 0.01))
        return np.r_[q, np.mean(delays)] if delays else q

    def optimum(self) -> Optimum:
        """The best fit from two starts: the case's values and a perturbation of the
        first fit's end, keeping the better (the cost surface of a delay and a release
        offset has shallow valleys); its linearised covariance and RMS misfit."""
        q, cost = self._fit(self.start())
        q2, cost2 = self._fit(q + 0.05 * self.log)
        if cost2 < cost:
            q, cost = q2, cost2
        dof = max(self.n_samples - len(q), 1)
        s2 = max(2 * cost / dof, 1.0)
        J = self._jacobian(q)
        return Optimum(q, cost, np.linalg.pinv(J.T @ J) * s2, s2, self._rms(q))

    def fit(self, opt: Optimum | None = None, profiled: bool = True) -> FormFit:
        """The fit (``opt``, else :meth:`optimum`), its intervals and the report of this
        form. ``profiled``: profile-likelihood intervals (module docstring); else
        linearised ones, q +- 1.96 sd of the covariance in the fitted coordinates (the log
        of a positive parameter), for a form the curves reject (not kept: its values
        calibrate nothing, and a misfitting form's profiles wander far for little)."""
        o = opt or self.optimum()
        q, cov = o.q, o.cov
        sd = np.sqrt(np.maximum(np.diag(cov), 1e-12))
        corr = cov / np.outer(sd, sd)
        rise = 0.5 * CHI2_95_1DOF * o.s2
        ends: dict[tuple[int, float], float | None] = {}
        members = [q]
        if profiled:
            for key, prof in self._profiles(q, o.cost, cov, rise).items():
                ends[key] = prof.end
                members += prof.inside
        else:
            for j in range(len(q)):
                for sign in (-1.0, 1.0):
                    x = q[j] + sign * np.sqrt(CHI2_95_1DOF) * sd[j]
                    inside = bool(self.lower[j] <= x <= self.upper[j])
                    ends[(j, sign)] = x if inside else None
                    # the linearised conditional optimum there: the band's member
                    m = np.clip(q + _valley(cov, j) * (x - q[j]), self.lower, self.upper)
                    members.append(m)
        ests = []
        for j, (name, unit) in enumerate(self.names()):
            lo_q, hi_q = ends[(j, -1.0)], ends[(j, 1.0)]
            low = _out(lo_q if lo_q is not None else self.lower[j], self.log[j])
            high = _out(hi_q if hi_q is not None else self.upper[j], self.log[j])
            value = _out(q[j], self.log[j])
            # identified: a closed profile interval inside the search bounds, within
            # IDENTIFIED_WITHIN of the value (the delay: IDENTIFIED_DELAY_MS); a form not
            # kept identifies nothing
            reach = max(value - low, high - value)
            identified = bool(profiled and lo_q is not None and hi_q is not None and (
                reach <= IDENTIFIED_WITHIN * abs(value) if self.log[j]
                else reach <= IDENTIFIED_DELAY_MS))
            ests.append(ParameterEstimate(name, unit, value, low, high, identified,
                                          near_bound(q[j], self.lower[j], self.upper[j],
                                                     bool(self.log[j]))))
        P_band, _ = self.values(np.array(members))
        return FormFit(self.form.name, self.form.summary, o.rms, tuple(ests), corr,
                       self._curve_fits(q), (), P_band,
                       intervals="profile" if profiled else "linearised")

    def names(self) -> list[tuple[str, str]]:
        """(name, unit) of every fitted coordinate: the form's, then the latch delay."""
        return [(p.name, p.unit) for p in self.parameters] + (
            [("latch_delay_ms", "ms")] if self.free_delay else [])

    def _costs(self, Q: NDArray) -> NDArray:
        """The robust cost (0.5 sum rho, as least_squares's) of each row of Q, (k,)."""
        return _robust_cost(self.residuals(Q))

    def _jacobian(self, q: NDArray) -> NDArray:
        h = 1e-6 * np.maximum(1.0, np.abs(q))
        R = self.residuals(np.vstack([q, q + np.diag(h)]))
        return ((R[1:] - R[0]) / h[:, None]).T

    def _profiles(self, q: NDArray, cost: float, cov: NDArray, rise: float
                  ) -> dict[tuple[int, float], _Profile]:
        """Every coordinate's profile from the optimum ``q`` (cost ``cost``) in both
        directions, side by side (:meth:`fit_many` re-fits them together): coordinate j
        fixed at 1.5, 3, 6, ... linearised standard deviations (``cov``) from the
        optimum, the others re-fitted, until the cost rises by more than ``rise``; a rise
        of more than 4 ``rise`` (a cliff: the profile is not a parabola there) is bisected
        until the bracket holds at most that, and the crossing is placed in the bracket
        as on a parabola through the optimum. A profile's end is None where it reaches
        the search bound, or :data:`MAX_PROFILE_STEPS` re-fits, under the threshold."""
        out = {}
        for j in range(len(q)):
            for sign in (-1.0, 1.0):
                bound = self.upper[j] if sign > 0 else self.lower[j]
                room = abs(bound - q[j])
                # a coordinate the curves do not see (no variance) starts at its bound
                first = 1.5 * float(np.sqrt(cov[j, j])) if cov[j, j] > 0 else room
                out[(j, sign)] = _Profile(j, sign, float(q[j]), room, min(first, room), q)
        for _ in range(self.MAX_PROFILE_STEPS):
            live = [p for p in out.values() if not p.done]
            if not live:
                break
            # start from the better of the last inside point moved along j alone and the
            # linearised conditional optimum (the valley's direction near the optimum)
            starts = []
            for p in live:
                x = q[p.j] + p.sign * p.d
                two = np.vstack([p.last, q + _valley(cov, p.j) * (x - q[p.j])])
                two = np.clip(two, self.lower + 1e-9, self.upper - 1e-9)
                two[:, p.j] = x
                starts.append(two)
            S = np.vstack(starts)
            c2 = self._costs(S).reshape(len(live), 2)
            S0 = S.reshape(len(live), 2, -1)[np.arange(len(live)), np.argmin(c2, axis=1)]
            # a re-fit needs its cost to a small part of the threshold, not to round-off
            trials, costs = self.fit_many(S0, np.array([p.j for p in live]), atol=0.005 * rise,
                                          max_iter=50)
            for p, trial, c in zip(live, trials, costs):
                _advance(p, trial, float(c - cost), rise)
        for p in out.values():
            if not p.done:
                _finish(p, rise)
        return out

    def _rms(self, q: NDArray) -> float:
        R = self.residuals(q)[0]
        sig = np.concatenate([np.full(len(c.curve.time), s)
                              for c, s in zip(self.curves, self.sigma)])
        return float(np.sqrt(np.mean((R * sig) ** 2)))

    def _curve_fits(self, q: NDArray) -> tuple[CurveFit, ...]:
        """Each curve's fit at ``q``: the model at the samples' times, and the analyser's
        quantities of the measured curve and of the model sampled every
        :data:`FINE_STEP_S` (the fit's own reading, at any sampling rate of the curve).
        A measured curve with fewer than :data:`MIN_WINDOW_SAMPLES` samples between the
        velocity's calculation points reads its contact velocity and closing time from
        the fit (resampled, said in its notes): linear interpolation between samples
        5 ms apart reads a 1.73 m/s closing at 1.37."""
        sims = self.simulate(q)
        P, delays = self.values(q)
        gap = self.config.contact_gap_mm * MM
        out = []
        for i, (c, s) in enumerate(zip(self.curves, sims)):
            t, meas = c.curve.time, c.curve.travel
            fine_t = np.arange(t[0], t[-1] + FINE_STEP_S / 2, FINE_STEP_S)
            time, rod = travel(self.form, self.model, [self.designs[i]], P, self.steps)
            fine = sample_travel(time[:, 0], rod[:, 0], (fine_t - delays[0, i])[None, :])[0]
            fitted = analyse(fine_t, fine, gap, self.points, rebounds=False)
            measured = analyse(t, meas, gap, self.points)
            inside = int(np.sum((meas >= self.points.low) & (meas <= self.points.high)))
            if inside < MIN_WINDOW_SAMPLES:
                measured = replace(measured, closing_time=fitted.closing_time,
                                   contact_velocity=fitted.contact_velocity,
                                   notes=(*measured.notes,
                                          f"closing time and contact velocity resampled from "
                                          f"the fit: {inside} sample(s) between the velocity's "
                                          f"calculation points, fewer than "
                                          f"{MIN_WINDOW_SAMPLES}"))
            out.append(CurveFit(
                c.curve.source, c.design.label, float(delays[0, i]), t, meas, s[0],
                float(np.sqrt(np.mean((s[0] - meas) ** 2))), measured, fitted,
                float(self.sigma[i])))
        return tuple(out)

    def predict(self, fit: FormFit, designs: Sequence[Design], best: NDArray,
                opt: Optimum | None = None) -> tuple[Prediction, ...]:
        """Closing velocity and touch time of ``designs`` at the fitted form parameters
        ``best`` (P,): low and high the wider of their envelope over the fit's band and,
        given the optimum ``opt``, the linearised 95 % interval +-1.96 sqrt(g^T C g)
        (g the prediction's gradient in the fitted coordinates by forward differences, C
        the optimum's covariance). The envelope alone is the profiles' extremes along
        each parameter's axis; a prediction that moves with several parameters at once
        lies off those axes, and the envelope alone covered a third design's true
        velocity in too few noisy curves (tests/cases/test_vcb_calibrate.py's coverage
        study)."""
        P = np.vstack([best, fit.band])
        v, t = velocity(self.form, self.model, designs, P, self.steps)
        sd_v = sd_t = np.zeros(len(designs))
        if opt is not None:
            h = 1e-6 * np.maximum(1.0, np.abs(opt.q))
            Q = np.vstack([opt.q, opt.q + np.diag(h)])
            vq, tq = velocity(self.form, self.model, designs, self.values(Q)[0], self.steps)
            with np.errstate(invalid="ignore"):
                gv, gt = (vq[1:] - vq[:1]) / h[:, None], (tq[1:] - tq[:1]) / h[:, None]
                sd_v = np.sqrt(np.einsum("in,ij,jn->n", gv, opt.cov, gv))
                sd_t = np.sqrt(np.einsum("in,ij,jn->n", gt, opt.cov, gt))
        z = np.sqrt(CHI2_95_1DOF)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: never touches
            return tuple(Prediction(
                d.label, float(v[0, i]),
                float(np.nanmin(np.r_[v[:, i], v[0, i] - z * sd_v[i]])),
                float(np.nanmax(np.r_[v[:, i], v[0, i] + z * sd_v[i]])), float(t[0, i]),
                float(np.nanmin(np.r_[t[:, i], t[0, i] - z * sd_t[i]])),
                float(np.nanmax(np.r_[t[:, i], t[0, i] + z * sd_t[i]])))
                for i, d in enumerate(designs))


def _valley(cov: NDArray, j: int) -> NDArray:
    """How the linearised conditional optimum moves per unit of coordinate j (n,):
    column j of the covariance over its variance. A coordinate the curves do not see
    (a zero column of the Jacobian: zero variance in the pseudo-inverse) moves alone:
    the others have nothing to trade against it (0 / 0 there was NaN, and a
    RuntimeWarning)."""
    if cov[j, j] > 0:
        return cov[:, j] / cov[j, j]
    return np.eye(len(cov))[j]


def _robust_cost(R: NDArray) -> NDArray:
    """soft-l1 cost of residual rows ``R`` (k, N), (k,): 0.5 C^2 sum 2 (sqrt(1 + (r/C)^2)
    - 1), scipy ``least_squares``'s with ``f_scale`` C = :data:`ROBUST_SCALE`."""
    z = (R / ROBUST_SCALE) ** 2
    return 0.5 * ROBUST_SCALE**2 * np.sum(2 * (np.sqrt(1 + z) - 1), axis=1)


def _advance(p: _Profile, trial: NDArray, r: float, rise: float) -> None:
    """One re-fit of profile ``p`` at its step ``p.d``, the cost risen by ``r``: the next
    step (doubling while inside, bisecting once outside) or the end."""
    p.steps += 1
    if r <= rise:
        p.inside.append(trial)
        p.last, p.near, p.near_rise = trial, p.d, max(r, 0.0)
        if p.far is None and p.d >= p.room:
            p.done, p.end = True, None  # open up to the search bound
            return
        p.d = min(2 * p.d, p.room) if p.far is None else 0.5 * (p.near + p.far[0])
    else:
        p.far = (p.d, r)
        if r <= 4 * rise or p.far[0] - p.near < 1e-4:
            _finish(p, rise)
            return
        p.d = 0.5 * (p.near + p.far[0])


def _finish(p: _Profile, rise: float) -> None:
    """The end of profile ``p``: None without a point outside, else the crossing in the
    bracket (near, far) on a parabola rise ~ a (distance)^2 through its two ends."""
    p.done = True
    if p.far is None:
        p.end = None
        return
    a = (p.far[1] - p.near_rise) / max(p.far[0] ** 2 - p.near**2, 1e-300)
    at = np.sqrt(p.near**2 + (rise - p.near_rise) / a) if a > 0 else p.far[0]
    p.end = float(p.origin + p.sign * float(np.clip(at, p.near, p.far[0])))


def _out(q: float, log: bool) -> float:
    return float(np.exp(q)) if log else float(q)


KEEP_RATIO = 1.5
"""A form is kept when its RMS misfit is at most this many times the best form's or the
curves' noise, whichever is larger (identification's ``form_keep_ratio``, 1.5: a form
that fits about as well as the best, or to within the analyser's noise, is as
credible)."""


def keep(rms: Sequence[float], noise: float) -> list[bool]:
    """Which forms are kept by their RMS misfits ``rms`` (m): at most
    :data:`KEEP_RATIO` times the larger of the best form's and ``noise`` (m, the curves'
    RMS noise level)."""
    if not rms:
        return []
    limit = KEEP_RATIO * max(min(rms), noise)
    return [r <= limit for r in rms]


CHI2_99_1DOF = 6.634896601021214
"""chi-square quantile, 1 degree of freedom, 0.99 (scipy.stats.chi2.ppf(0.99, 1))."""


def nested_keep(forms: Sequence[ModelForm], optima: Sequence[Optimum], kept: Sequence[bool]
                ) -> list[tuple[bool, str]]:
    """The keep rule for a form that adds one term to a ``base`` form fitted beside it:
    kept only where the term improves the fit beyond chance, the likelihood ratio
    2 (cost_base - cost) / s^2 at least chi2(1, 0.99) = 6.63 (s^2 the form's reduced
    chi-square, at least 1). A term the curves do not need fits them as well as the base
    (its parameter at its lower bound, the ratio ~0) and is kept out: its extra freedom
    would only widen the predictions. Returns (kept, why not) per form."""
    names = [f.name for f in forms]
    out = []
    for form, opt, k in zip(forms, optima, kept):
        if form.base is None or form.base not in names or not k:
            out.append((k, ""))
            continue
        ratio = 2 * (optima[names.index(form.base)].cost - opt.cost) / opt.s2
        out.append((True, "") if ratio >= CHI2_99_1DOF else (
            False, f"not kept: its {form.extra.replace('_', ' ')} does not improve on "
            f"{form.base} (likelihood ratio {ratio:.2f} < {CHI2_99_1DOF:.2f})"))
    return out


def calibrate(config: VcbConfig, curves: Sequence[CurveCase],
              forms: Sequence[ModelForm] = CURVE_FORMS, predict: Sequence[Design] = (),
              points: VelocityPoints | None = None) -> tuple[FormFit, ...]:
    """Fit every form (default :data:`~camopt.cases.vcb.forms.CURVE_FORMS`) to the curves
    jointly, mark the forms kept (:func:`keep`, :func:`nested_keep`; where some form
    explains the curves, a form whose residuals fail the test is not kept), find the
    intervals (profile likelihood for the kept forms, linearised for the others:
    :meth:`Calibration.fit`) and predict ``predict``'s designs (the curves' designs if
    empty)."""
    cals = [Calibration(config, form, curves, points) for form in forms]
    optima = [c.optimum() for c in cals]
    sigma = np.array([max(c.curve.noise, 1e-3 * MM) for c in curves])
    counts = np.array([len(c.curve.time) for c in curves])
    noise = float(np.sqrt(np.sum(counts * sigma**2) / np.sum(counts)))
    decided = nested_keep(forms, optima, keep([o.rms for o in optima], noise))
    tests = [residual_test([s[0] - c.curve.travel for s, c in zip(cal.simulate(o.q), curves)],
                           list(cal.sigma)) for cal, o in zip(cals, optima)]
    explaining = [f.name for f, (k, _), t in zip(forms, decided, tests) if k and t.passes()]
    if explaining:  # forms that explain the curves outrank forms that merely fit as well
        decided = [(k, why) if not k or t.passes() else (
            False, f"not kept: its residuals are not the noise (RMS {t.rms_ratio:.2f} x, "
            f"Durbin-Watson {t.durbin_watson:.2f}) where {', '.join(explaining)} explain "
            "the curves") for (k, why), t in zip(decided, tests)]
    out = []
    for cal, opt, (k, why), test in zip(cals, optima, decided, tests):
        fit = cal.fit(opt, profiled=k)
        best = np.array([p.value for p in fit.parameters[:cal.n_form]])
        designs = list(predict) or _unique(cal.designs)
        out.append(replace(fit, predictions=cal.predict(fit, designs, best, opt), kept=k,
                           residuals=test, explains=k and test.passes(), kept_note=why))
    return tuple(out)


PREDICTION_SPREAD = 0.02
"""Forms that explain the curves but predict a design's closing velocity further apart
than this (relative) are told apart by no curve: a warning says so."""


@dataclass(frozen=True)
class Verdict:
    """Whether any form explains the curves (``explained``, those ``forms``), the
    one-line ``headline`` a report leads and ends with, and ``warnings``: parameters at a
    search bound, explaining forms whose predictions disagree."""

    explained: bool
    forms: tuple[str, ...]
    headline: str
    warnings: tuple[str, ...]


def verdict(fits: Sequence[FormFit], gap: float) -> Verdict:
    """The verdict on fitted forms (:func:`calibrate`'s) of curves whose contact gap is
    ``gap`` (m): explained by the forms that explain them (:attr:`FormFit.explains`),
    else NOT EXPLAINED with the best form's residual test and where its misfit lies
    (:func:`missing_physics`)."""
    good = [f for f in fits if f.explains]
    warn: list[str] = []
    for f in fits:
        if not f.kept:
            continue
        for p in f.parameters:
            if p.at_bound:
                warn.append(f"form {f.form}: {p.name} = {p.value:.4g} {p.unit} is at its "
                            "search bound: the curves do not measure it (the form may "
                            "stand in for physics it lacks)")
    if good:
        by_design: dict[str, list[float]] = {}
        for f in good:
            for pr in f.predictions:
                by_design.setdefault(pr.design, []).append(pr.closing_velocity)
        for design, v in by_design.items():
            lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
            if len(v) > 1 and hi - lo > PREDICTION_SPREAD * abs(hi):
                warn.append(f"design {design}: the forms that explain the curves predict a "
                            f"closing velocity of {lo:.3f} to {hi:.3f} m/s: the curves do "
                            "not tell them apart (a curve with other springs does)")
        coarse: dict[str, list[float]] = {}
        for f in good:
            for c in f.curves:
                q = c.measured_quantities
                if q.contact_velocity is not None and any("resampled" in n for n in q.notes):
                    coarse.setdefault(c.source, []).append(q.contact_velocity)
        for source, v in coarse.items():
            lo, hi = min(v), max(v)
            warn.append(f"curve {source} is sampled too coarsely for its contact velocity: "
                        "read from the fit"
                        + (f", {lo:.3f} to {hi:.3f} m/s over the forms that explain it"
                           if hi - lo > PREDICTION_SPREAD * hi else ""))
        names = ", ".join(f.form for f in good)
        head = (f"verdict: explained by form{'s' if len(good) > 1 else ''} {names} "
                "(residuals at the curves' noise, without structure)")
        return Verdict(True, tuple(f.form for f in good), head, tuple(warn))
    best = min(fits, key=lambda f: f.rms)
    t = best.residuals
    detail = "" if t is None else (
        f"best form {best.form}: residual RMS {best.rms / t.noise:.2f} x the noise "
        f"({t.noise / MM:.4f} mm), Durbin-Watson {t.durbin_watson:.2f} "
        f"({t.structure_z:.1f} standard errors below 2)")
    head = (f"verdict: NOT EXPLAINED: no model form fits the curves to their noise; {detail}; "
            f"{missing_physics(best, gap)}")
    return Verdict(False, (), head, tuple(warn))


def _unique(designs: Sequence[Design]) -> list[Design]:
    """One design per label, in order."""
    seen: dict[str, Design] = {}
    for d in designs:
        seen.setdefault(d.label, d)
    return list(seen.values())
